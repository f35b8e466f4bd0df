"""A box surging in a refinement zone against uniform runs: a 2D box 0.2 m wide, 0.08 m under 0.3 m
of water in a 1 m tank, on a 1 cm sinusoid at 1 s from rest, with (``--zone``) a zone at half the
spacing 0.15 m about it (multirate) or without. Prints its particles, the mean vertical force over
1-3 s (against the buoyancy rho g A = 157 N/m) and the RMS of its surge force, and writes the force
series (t, fx, fy) to ``--out`` for a comparison run against run (docs/results/bodies.md).

    python bench/moving_zone.py --dx 0.02 --zone --out zoned.csv
    python bench/moving_zone.py --dx 0.01 --out fine.csv --against zoned.csv
"""
import argparse
import time

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=0.02)
    ap.add_argument("--zone", action="store_true", help="a zone at dx / 2 0.15 m about the box")
    ap.add_argument("--out", help="CSV of t, fx, fy")
    ap.add_argument("--against", help="another run's CSV: this run's surge force RMS over its")
    args = ap.parse_args()
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.measure.forces import BodyWrench
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import parse_scene
    from gpusph_ros.sph import Solver

    scene = {"name": "surge", "dim": 2, "tank": [1.0, 0.6], "walls": "particles",
             "fluid": [{"name": "water", "lo": [0, 0], "hi": [1.0, 0.3]}],
             "obstacles": [{"name": "box", "lo": [0.4, 0.22], "hi": [0.6, 0.36], "displaces_fluid": True,
                            "motion": {"type": "sinusoid", "amplitude": [0.01, 0.0], "period": 1.0,
                                       "phase_deg": -90}}]}
    if args.zone:
        scene["refine"] = [{"name": "near", "lo": [0.25, 0.07], "hi": [0.75, 0.6], "ratio": 0.5}]
    model = build(parse_scene(scene), dx=args.dx)
    solver = Solver(model.config, model.particles)
    wrench = BodyWrench(solver, 0)
    t0, rows = time.perf_counter(), []
    for t in np.arange(0.02, 3.0 + 1e-9, 0.02):
        solver.advance(float(t))
        force, _ = wrench.sample()
        rows.append((solver.time, force[0], force[1]))
    rows = np.array(rows)
    late = rows[:, 0] > 1.0
    rms = float(np.sqrt(np.mean(rows[late, 1] ** 2)))
    buoyancy = 1000.0 * 9.81 * 0.2 * 0.08
    print(f"dx {args.dx} {'zoned' if args.zone else 'uniform'}: {len(model.particles.pos):,} slots; vertical force "
          f"{rows[late, 2].mean():.2f} N/m ({rows[late, 2].mean() / buoyancy - 1:+.1%} of rho g A); surge force RMS "
          f"{rms:.3f} N/m; {solver.excluded_particles} excluded; {time.perf_counter() - t0:.0f} s")
    if args.out:
        np.savetxt(args.out, rows, delimiter=",", header="t,fx,fy")
    if args.against:
        other = np.loadtxt(args.against, delimiter=",")
        print(f"surge force RMS over the other run's: {rms / np.sqrt(np.mean(other[other[:, 0] > 1.0, 1] ** 2)):.3f}")


if __name__ == "__main__":
    main()
