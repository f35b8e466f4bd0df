"""Solver throughput on DamBreak 1 (3D dam break onto an obstruction) at three spacings, both precisions,
with neighbour lists or walking the cells (sph/neighbours.py; by default the device's choice).

Prints, per case: device, search, precision, dx, particles (all, and fluid), mean neighbours per fluid
particle (within the list radius, 1.1 kernel supports), steps/s, million particle-steps per
second (MIPPS, GPUSPH's figure of merit, counting every particle), neighbour interactions per
second (list entries visited by the two force passes of each predictor-corrector step) and the
fraction of steps that rebuilt the neighbour lists. Each case first runs to --start simulated
seconds untimed (the surge is then under way, so lists go stale at a realistic rate), then is
timed for --seconds of wall clock; compilation is never counted.

    python bench/solver.py [--device cpu|cuda:0] [--dx 0.03 0.02 0.015 | --particles 1e5 1e6]
                           [--seconds 20] [--start 0.05] [--search auto|lists|cells ...]
"""
import argparse
import itertools
import time

import warp as wp

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.sph import ConfigError

from series import model_of_about

FORCE_PASSES_PER_STEP = 2


def measure(dx: float, precision: str, device: str, seconds: float, start_time: float, particles=None,
            search: str = "auto"):
    """One case at spacing ``dx``, or at the spacing that gives about ``particles``."""
    numerics = {"precision": precision, "device": device, "neighbour_search": search}
    if particles:
        model = model_of_about("dambreak1_thesis", particles, **numerics)
        dx = model.config.dx
    else:
        model = build(load_scene("dambreak1_thesis"), dx=dx, **numerics)
    solver = model.solver()
    solver.advance(start_time)
    wp.synchronize_device(solver.device)
    neighbours = solver.mean_neighbours()
    listed = float(solver.neighbours.counts().sum())
    builds0 = int(solver.neighbours.builds.numpy()[0])
    start = time.perf_counter()
    steps0 = solver.steps
    # advance in short simulated slices until the wall-clock budget is spent
    while time.perf_counter() - start < seconds:
        solver.advance(solver.time + 20 * solver.dt_stable)
    wp.synchronize_device(solver.device)
    wall = time.perf_counter() - start
    steps = solver.steps - steps0
    rate = steps / wall
    builds = int(solver.neighbours.builds.numpy()[0]) - builds0
    return {
        "device": str(solver.device), "search": "cells" if solver.neighbours.cells else "lists",
        "precision": precision, "dx": dx, "particles": solver.n,
        "fluid": model.fluid_particles, "neighbours": neighbours, "steps": steps, "wall": wall,
        "steps_per_s": rate, "mipps": solver.n * rate / 1e6,
        "interactions_per_s": listed * FORCE_PASSES_PER_STEP * rate, "sim_time": solver.time,
        "rebuilds": builds / max(steps, 1),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--dx", type=float, nargs="+", default=[0.03, 0.02, 0.015])
    parser.add_argument("--particles", type=float, nargs="+", help="about how many particles each case has "
                        "(instead of --dx)")
    parser.add_argument("--precision", nargs="+", default=["float32", "float64"])
    parser.add_argument("--seconds", type=float, default=20.0, help="wall-clock time measured per case")
    parser.add_argument("--start", type=float, default=0.05, help="simulated time run untimed first [s]")
    parser.add_argument("--search", nargs="+", default=["auto"], choices=["auto", "lists", "cells"],
                        help="how the passes find neighbours (neighbour_search); auto: the device's choice")
    args = parser.parse_args()
    wp.config.log_level = wp.LOG_WARNING  # no per-module load lines
    header = (f"{'device':8s} {'search':6s} {'precision':9s} {'dx [m]':>7s} {'particles':>10s} {'fluid':>8s} "
              f"{'nbrs':>6s} {'steps':>6s} {'steps/s':>8s} {'MIPPS':>7s} {'interactions/s':>15s} {'rebuilds':>8s}")
    print("DamBreak 1 (Yeh & Petroff / GPUSPH DamBreak3D), default numerics: "
          "cubic spline, artificial viscosity, dynamic boundaries, delta-SPH")
    print(header)
    print("-" * len(header))
    cases = [(None, n) for n in args.particles] if args.particles else [(dx, None) for dx in args.dx]
    for (dx, particles), search, precision in itertools.product(cases, args.search, args.precision):
        try:
            r = measure(dx, precision, args.device, args.seconds, args.start, particles, search)
        except ConfigError as err:  # more than the device holds: say so, go on with the others
            print(f"{args.device:8s} {search:6s} {precision:9s} {particles or dx:g}: refused: {err}", flush=True)
            continue
        print(f"{r['device']:8s} {r['search']:6s} {r['precision']:9s} {r['dx']:7.4f} {r['particles']:10d} "
              f"{r['fluid']:8d} {r['neighbours']:6.1f} {r['steps']:6d} {r['steps_per_s']:8.2f} {r['mipps']:7.3f} "
              f"{r['interactions_per_s']:15.3e} {r['rebuilds']:8.2f}", flush=True)


if __name__ == "__main__":
    main()
