"""What a step asks of the device, and the step loop eager against replayed from its captured graph
(sph/graph.py), on one device: part of `make gpu-check`'s report.

1. Launches, sorts, fills, copies, host reads and allocations of each kind of step (ordinary; the
   lists stale; reorder and census), counted eagerly (sph/device_calls.py) over 48 steps of a surge.
2. Per output, eager and replayed: the host's syncs, its other reads, allocations and replays.
3. Wall time to the same simulated time from the same state, eager and replayed, one after the
   other (the capture is made at the first output, not timed).

    python bench/step_counts.py [--device cpu|cuda:0] [--scene dambreak1_lab] [--dx 0.03]
                                [--span 0.05] [--precision float32] [--boundary adami]
"""
import argparse
import time

import warp as wp

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.sph import Solver
from gpusph_ros.sph.device_calls import counting
from gpusph_ros.sph.state import CENSUS_DUE, REORDER_DUE

START = 0.05  # s of the surge run first: the lists then go stale every few steps
OUTPUT = 0.01  # s between outputs


def kind_of(solver) -> str:
    if int(solver.flag(REORDER_DUE).numpy()[0]) or int(solver.flag(CENSUS_DUE).numpy()[0]):
        return "reorder and census"
    return "lists stale" if int(solver.neighbours.stale.numpy()[0]) else "ordinary"


def per_step(solver, steps: int = 48) -> dict:
    """{kind of step: (how many, the most of each count over them)}."""
    solver.aim(float("inf"))
    seen = {}
    for _ in range(steps):
        kind = kind_of(solver)
        with counting(Solver) as counts:
            solver.loop_body(block=2 ** 31 - 1)
        n, most = seen.get(kind, (0, {}))
        seen[kind] = (n + 1, {k: max(most.get(k, 0), counts[k]) for k in set(most) | set(counts)})
    return seen


def per_output(solver, outputs: int = 3) -> dict:
    """The counts of each of ``outputs`` outputs, the largest of each."""
    most = {}
    for _ in range(outputs):
        with counting(Solver) as counts:
            solver.advance(solver.time + OUTPUT)
        most = {k: max(most.get(k, 0), counts[k]) for k in set(most) | set(counts)}
    return most


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--scene", default="dambreak1_lab")
    parser.add_argument("--dx", type=float, default=0.03)
    parser.add_argument("--span", type=float, default=0.05, help="simulated seconds timed per mode")
    parser.add_argument("--precision", default="float32")
    parser.add_argument("--boundary", default=None, help="the wall model (default: the run's default)")
    args = parser.parse_args()
    wp.config.log_level = wp.LOG_WARNING
    scene = load_scene(args.scene)

    def solver(step_graph: str, threads: int = 0):
        walls = {"boundary": args.boundary} if args.boundary else {}
        model = build(scene, dx=args.dx, device=args.device, precision=args.precision, step_graph=step_graph,
                      cpu_threads=threads, **walls)
        s = model.solver()
        s.advance(START)
        return s

    # one thread on a CPU: a heavy pass is one launch, as on a GPU
    counted = solver("off", threads=1)
    print(f"{args.scene} at dx = {args.dx:g} m, {counted.n:,} particles, {counted.config.boundary} walls, "
          f"{args.precision} on {args.device}")
    print("\n| step | how many of 48 | launches | sorts | fills | copies | host reads | allocations |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for kind, (n, most) in sorted(per_step(counted).items()):
        print(f"| {kind} | {n} | " + " | ".join(str(most.get(k, 0)) for k in
                                                 ("launch", "sort", "fill", "copy", "host_read", "allocation"))
              + " |")
    print("\n| loop | syncs an output | other host reads | allocations | replays | launches from the host |")
    print("| --- | --- | --- | --- | --- | --- |")
    for mode in ("off", "on"):
        counted.reconfigure(step_graph=mode)
        counted.advance(counted.time + OUTPUT)  # a replay captures the loop here
        most = per_output(counted)
        label = "replayed" if mode == "on" else "eager"
        print(f"| {label} | {most.get('sync', 0)} | {most.get('host_read', 0)} | {most.get('allocation', 0)} | "
              f"{most.get('replay', 0)} | {most.get('launch', 0)} |")
    print(f"\n| loop | threads | steps | wall [s] to t + {args.span:g} s | steps/s | MIPPS |")
    print("| --- | --- | --- | --- | --- | --- |")
    for mode in ("off", "on"):
        s = solver(mode)
        s.advance(s.time + OUTPUT)
        wp.synchronize_device(s.device)
        t0, steps0, start = s.time, s.steps, time.perf_counter()
        k = 1
        while not s.reached(t0 + args.span):
            s.advance(min(t0 + args.span, t0 + k * OUTPUT))
            k += 1
        wp.synchronize_device(s.device)
        wall = time.perf_counter() - start
        steps = s.steps - steps0
        threads = 1 if mode == "on" or s.device.is_cuda else s.launch.threads
        print(f"| {'replayed' if mode == 'on' else 'eager'} | {threads} | {steps} | {wall:.2f} | {steps / wall:.1f} | "
              f"{s.n * steps / wall / 1e6:.3f} |")


if __name__ == "__main__":
    main()
