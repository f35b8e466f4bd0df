"""A body floating in a still tank against Archimedes: a box (its draft density / rho0 of its height),
a disc or a sphere of half the water's density (its centre on the level), let go ``--above`` over
that (at ``--release``) and left to heave, or (``--held``) held at its draft. Prints the body's
height against the level far from it (the mean of measure.surface.Gauges a spacing apart, beyond the
kernel's reach of the walls and of the body's box) every 0.02 s, and the mean over its whole heave
periods (between upward crossings of its mean height after 0.5 s): the draft's error; and the free
decay of its heave from release, fitted with z0 + e^(-zeta omega_n t) (a cos omega_d t + b sin
omega_d t) (a scan of omega_d and zeta, the rest least squares): against the damped period and
damping ratio that linear theory's added mass and radiation damping give the box, 2D or 3D
(theory/heave.py, data/heave_added_mass/README.md).

    python bench/floating_draft.py --dim 3 --shape box --dx 0.01 [--end 2.0] [--set KEY=VALUE ...]
"""
import argparse
import time

import numpy as np

# the box's: its 2D section (0.2 m beam) or the 3D box (0.2 x 0.2 m), 0.05 m draft, 0.3 m of water
TABLE = {2: "box_B0.2_T0.05_h0.3.csv", 3: "box3d_L0.2_B0.2_T0.05_h0.3.csv"}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dim", type=int, choices=[2, 3], default=3)
    ap.add_argument("--shape", choices=["box", "cylinder", "sphere"], default="box")
    ap.add_argument("--dx", type=float, default=0.02)
    ap.add_argument("--end", type=float, default=2.0)
    ap.add_argument("--above", type=float, default=0.01, help="[m] let go this far above its rest")
    ap.add_argument("--release", type=float, default=0.0, help="[s] held where it was put until then")
    ap.add_argument("--held", action="store_true", help="a box held at its draft throughout: the fluid's force on "
                                                        "it against the hydrostatic load under the gauges' level")
    ap.add_argument("--width", type=float, help="[m] the tank's (default 1 in 2D, 0.5 in 3D); a wide one keeps the "
                                                "radiated waves away for longer")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args()
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.analysis.oscillation import free_decay, whole_periods
    from gpusph_ros.measure.forces import BodyWrench
    from gpusph_ros.measure.surface import Gauges
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import parse_scene
    from gpusph_ros.scenes.yaml_input import value
    from gpusph_ros.share import data_dir
    from gpusph_ros.sph import Solver
    from gpusph_ros.theory import heave

    if args.held and (args.shape != "box" or args.above != 0.0):
        raise SystemExit("--held: a box, --above 0")
    release = 2.0 * args.end if args.held else args.release
    dim, dx, up = args.dim, args.dx, args.dim - 1
    width, depth, size = args.width or (0.5 if dim == 3 else 1.0), 0.3, 0.2  # tank, water, body
    density = 500.0  # at rest every body's centre is on the level: a box 0.1 tall has a 5 cm draft
    half = [size / 2] * (dim - 1) + [0.05] if args.shape == "box" else [size / 2] * dim
    centre = [width / 2] * (dim - 1) + [depth + args.above]
    body = {"name": "body", "lo": [c - h for c, h in zip(centre, half)], "hi": [c + h for c, h in zip(centre, half)],
            "displaces_fluid": True, "floating": {"density": density, "rotate": False, "release": release}}
    if args.shape != "box":
        body["shape"] = args.shape
        if dim == 3 and args.shape == "cylinder":
            body["axis"] = "y"
    scene = parse_scene({"name": "float", "dim": dim, "tank": [width] * (dim - 1) + [0.6],
                         "fluid": [{"name": "water", "lo": [0.0] * dim, "hi": [width] * (dim - 1) + [depth]}],
                         "obstacles": [body]})
    settings = {k: value(v) for k, _, v in (a.partition("=") for a in args.set)}
    model = build(scene, dx=dx, **settings)
    solver = Solver(model.config, model.particles)
    print(f"{dim}D {args.shape} of density {density} at dx = {dx} m: {solver.n} particles, {settings}", flush=True)
    # gauges a spacing apart, beyond the kernel's reach (2h) of the walls and of the body's box
    reach = 2.0 * model.config.hdx * dx
    grid = np.arange(reach, width - reach + 1e-9, dx)
    spots = np.stack(np.meshgrid(*[grid] * up, indexing="ij"), axis=-1).reshape(-1, up)
    spots = spots[np.abs(spots - width / 2).max(axis=1) >= size / 2 + reach]
    gauges = Gauges(solver, np.column_stack([spots, np.zeros((len(spots), 3 - up))]), 0.2, 0.45, dx)
    wrench = BodyWrench(solver, 0)
    t0, rows = time.perf_counter(), []
    for t in np.arange(0.02, args.end + 1e-9, 0.02):
        wrench.restart()
        solver.advance(float(t))
        level = float(gauges.elevations().mean())
        height = solver.body_states()[0]["position"][up]
        rows.append((solver.time, height, level, wrench.sample()[0][up]))
    r = np.array(rows)
    if args.held:  # the fluid's mean force on it after 0.5 s against rho0 g A (level - bottom)
        settled = r[:, 0] >= 0.5
        load = model.config.rho0 * 9.81 * size ** (dim - 1) * (r[settled, 2] - (depth - 0.05))
        force = r[settled, 3]
        print(f"held at its draft: the fluid's force {force.mean():.4f} N against the hydrostatic load "
              f"{load.mean():.4f} N (per metre in 2D) under the gauges' level: "
              f"{100 * (force.mean() / load.mean() - 1):+.2f}%; {time.perf_counter() - t0:.0f} s")
        return
    whole, crossings = whole_periods(r[:, 0], r[:, 1], after=args.release + 0.5)
    if crossings < 2:
        raise SystemExit(f"{crossings} upward crossings by {args.end} s: a longer --end")
    offset = float((r[whole, 1] - r[whole, 2]).mean())
    if args.shape == "box":
        print(f"draft {0.05 - offset:.5f} m against Archimedes' 0.05 m: {-offset / 0.05 * 100:+.1f}%", end="")
    else:
        print(f"centre {offset * 1000:+.2f} mm from the level ({offset / 0.1 * 100:+.1f}% of the radius)", end="")
    late = r[:, 0] >= args.release
    fit = free_decay(r[late, 0] - args.release, r[late, 1])
    print(f"; free decay: damped period {fit['period']:.3f} s, damping ratio {fit['damping_ratio']:.3f} (residual "
          f"{fit['rms'] * 1000:.2f} mm); {solver.excluded_particles} excluded; {time.perf_counter() - t0:.0f} s")
    if args.shape == "box":
        area = size ** (dim - 1)  # the waterline's beam (2D) or the waterplane's area (3D)
        theory = heave.natural(density * 0.1 * area, area, heave.table(data_dir("heave_added_mass") / TABLE[dim]))
        print(f"linear theory (data/heave_added_mass): added mass {theory['added_mass']:.2f} kg(/m), damped period "
              f"{theory['damped_period']:.3f} s ({100 * (fit['period'] / theory['damped_period'] - 1):+.1f}%), "
              f"damping ratio {theory['damping_ratio']:.3f}", flush=True)


if __name__ == "__main__":
    main()
