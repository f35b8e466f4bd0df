"""Solver throughput on DamBreak 1 (3D dam break onto an obstruction) at three spacings, both precisions.

Prints, per case: device, precision, dx, particles (all, and fluid), mean neighbours per fluid
particle (within the list radius, 1.1 kernel supports), steps/s, million particle-steps per
second (MIPPS, GPUSPH's figure of merit, counting every particle), neighbour interactions per
second (list entries visited by the two force passes of each predictor-corrector step) and the
fraction of steps that rebuilt the neighbour lists. Each case first runs to --start simulated
seconds untimed (the surge is then under way, so lists go stale at a realistic rate), then is
timed for --seconds of wall clock; compilation is never counted.

    python bench/solver.py [--device cpu|cuda:0] [--dx 0.03 0.02 0.015 | --particles 1e5 1e6]
                           [--seconds 20] [--start 0.05]
"""
import argparse
import time

import warp as wp

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.sph import ConfigError

from series import model_of_about

FORCE_PASSES_PER_STEP = 2


def measure(dx: float, precision: str, device: str, seconds: float, start_time: float, particles=None):
    """One case at spacing ``dx``, or at the spacing that gives about ``particles``."""
    if particles:
        model = model_of_about("dambreak1_thesis", particles, precision=precision, device=device)
        dx = model.config.dx
    else:
        model = build(load_scene("dambreak1_thesis"), dx=dx, precision=precision, device=device)
    solver = model.solver()
    solver.advance(start_time)
    wp.synchronize_device(solver.device)
    neighbours = solver.mean_neighbours()
    listed = float(solver.neighbours.count.numpy().sum())
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
        "device": str(solver.device), "precision": precision, "dx": dx, "particles": solver.n,
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
    args = parser.parse_args()
    wp.config.log_level = wp.LOG_WARNING  # no per-module load lines
    header = (f"{'device':8s} {'precision':9s} {'dx [m]':>7s} {'particles':>10s} {'fluid':>8s} {'nbrs':>6s} "
              f"{'steps':>6s} {'steps/s':>8s} {'MIPPS':>7s} {'interactions/s':>15s} {'rebuilds':>8s}")
    print("DamBreak 1 (Yeh & Petroff / GPUSPH DamBreak3D), default numerics: "
          "cubic spline, artificial viscosity, dynamic boundaries, delta-SPH")
    print(header)
    print("-" * len(header))
    for dx, particles in ([(None, n) for n in args.particles] if args.particles else [(dx, None) for dx in args.dx]):
        for precision in args.precision:
            try:
                r = measure(dx, precision, args.device, args.seconds, args.start, particles)
            except ConfigError as err:  # more than the device holds: say so, go on with the others
                print(f"{args.device:8s} {precision:9s} {particles or dx:g}: refused: {err}", flush=True)
                continue
            print(f"{r['device']:8s} {r['precision']:9s} {r['dx']:7.4f} {r['particles']:10d} {r['fluid']:8d} "
                  f"{r['neighbours']:6.1f} {r['steps']:6d} {r['steps_per_s']:8.2f} {r['mipps']:7.3f} "
                  f"{r['interactions_per_s']:15.3e} {r['rebuilds']:8.2f}", flush=True)


if __name__ == "__main__":
    main()
