"""Headless entry points: run a built-in scene with a progress line."""
import argparse
import sys
import time

import numpy as np

SURGE_LEVEL = 0.05  # [m] above the 0.01 m wet bed of DamBreak 1


def _run(args):
    import warp as wp

    wp.config.quiet = True
    from .scenes.dambreak import dambreak1
    from .sph import HealthError, Solver

    overrides = {"precision": args.precision, "device": args.device}
    cfg, parts = dambreak1(args.dx, **overrides)
    solver = Solver(cfg, parts)
    n_fluid = int((parts.ptype == 0).sum())
    print(f"{args.scene}: dx = {args.dx} m, {solver.n} particles ({n_fluid} fluid), {cfg.kernel} kernel, "
          f"{cfg.viscosity} viscosity, {cfg.boundary} boundaries, {cfg.precision} on {solver.device}", flush=True)
    start = time.perf_counter()
    try:
        for t in np.arange(args.output, args.end_time + 1e-9, args.output):
            solver.advance(float(t))
            wall = time.perf_counter() - start
            snap = solver.snapshot()
            # the surge front: the farthest fluid above the wet bed
            surge = (snap["ptype"] == 0) & (snap["pos"][:, 2] > SURGE_LEVEL)
            front = snap["pos"][surge, 0].max()
            mipps = solver.n * solver.steps / wall / 1e6
            eta = wall / solver.time * (args.end_time - solver.time)
            print(f"t = {solver.time:6.3f} s  steps {solver.steps:6d}  {solver.steps / wall:6.1f} steps/s  "
                  f"{mipps:5.3f} MIPPS  surge front x = {front:5.3f} m  ETA {eta:5.0f} s", flush=True)
    except HealthError as err:
        print(f"stopped: {err}", file=sys.stderr)
        return 2
    return 0


def main(argv=None):
    parser = argparse.ArgumentParser(prog="gpusph_ros.cli", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a built-in scene headless")
    run.add_argument("scene", choices=["dambreak3d"], help="DamBreak 1 of the thesis (Yeh & Petroff)")
    run.add_argument("--dx", type=float, default=0.03, help="particle spacing [m]")
    run.add_argument("--end-time", type=float, default=0.5, help="simulated end time [s]")
    run.add_argument("--output", type=float, default=0.05, help="progress interval, simulated [s]")
    run.add_argument("--precision", choices=["float32", "float64"], default="float32")
    run.add_argument("--device", default="cpu", help="Warp device: cpu or cuda:N")
    args = parser.parse_args(argv)
    return _run(args)


if __name__ == "__main__":
    sys.exit(main())
