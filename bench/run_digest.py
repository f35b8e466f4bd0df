"""A built-in scene stepped by the solver alone to an end time, outputs every 0.01 s: its steps, its
neighbour lists' width, its excluded particles, a digest of its state (positions, velocities,
densities, kinds) and the wall time. Two codes that give the same digest ran the same run bit for
bit; run them one after the other, alone, to compare their times (docs/results/speed.md).

    python bench/run_digest.py dambreak1_lab 0.015 0.5 [--set neighbour_search=cells]
"""
import argparse
import hashlib
import time

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("dx", type=float)
    ap.add_argument("end", type=float)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a solver setting")
    args = ap.parse_args()
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import parse_set
    from gpusph_ros.sph import Solver

    model = build(load_scene(args.scene), dx=args.dx, **dict(parse_set(item) for item in args.set))
    solver = Solver(model.config, model.particles)
    t0 = time.perf_counter()
    for k in range(1, int(round(args.end / 0.01)) + 1):
        solver.advance(0.01 * k)
    snap = solver.snapshot()
    digest = hashlib.sha256(b"".join(np.ascontiguousarray(snap[n]).tobytes() for n in ("pos", "vel", "rho", "ptype")))
    search = "no lists (cells walked)" if solver.neighbours.cells else f"lists {solver.neighbours.max_neighbours} wide"
    print(f"{args.scene} at {args.dx} m to {args.end} s: {solver.steps} steps, {search}, "
          f"{solver.excluded_particles} excluded, digest {digest.hexdigest()[:16]}, {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
