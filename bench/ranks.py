"""One run on MPI ranks against one rank, on this machine (issue 69; docs/ranks.md): wall time to
the same simulated time, time in the exchange a step, the halo's share of each rank's particles,
and the imbalance of the owned particles.

    python bench/ranks.py [--scene dambreak1_lab] [--dx 0.015] [--end 0.3] [--ranks 2] [--threads 2]

It runs, one after another and each alone:
- one solver with ``--threads`` threads and its replayed loop (`Solver.advance`);
- the same under the exchange on one rank (host-driven steps);
- ``--ranks`` ranks of one thread each (`mpiexec -n R python -m mpi4py bench/ranks.py --worker`), with
  the cuts kept where they fell at the start and with them moved (RankedRun's ``rebalance``: 10%
  over the mean, tried at most every 100 steps).
"""
import argparse
import json
import subprocess
import sys
import time
from pathlib import Path


def worker(args):
    import numpy as np
    import warp as wp
    from mpi4py import MPI

    wp.config.quiet, wp.config.log_level = True, wp.LOG_WARNING
    from gpusph_ros.scenes.build import build_run
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve
    from gpusph_ros.sph.exchange import RankedRun
    from gpusph_ros.sph.state import VACANT

    comm = MPI.COMM_WORLD
    sc = load_scene(args.scene)
    model = build_run(sc, resolve(sc, dx=args.dx, end_time=args.end, cpu_threads=args.threads,
                                  energy_growth_ratio=0.0))
    run = RankedRun(model, comm, rebalance=args.rebalance)
    s = run.solver
    owned, held = [], []
    comm.Barrier()
    start = time.perf_counter()
    while s.time < args.end - 1e-12:
        run.step()
        if not owned or s.steps % 20 == 0:
            o = s.fields.owned.numpy().astype(bool)
            h = s.ptype.numpy() != VACANT
            owned.append(int((o & h).sum()))
            held.append(int(h.sum()))
    comm.Barrier()
    wall = time.perf_counter() - start
    every = comm.gather({"owned": owned, "held": held, "exchange_s": run.exchange_s, "steps": s.steps,
                         "wall": wall}, root=0)
    if comm.rank == 0:
        o = np.array([e["owned"] for e in every], dtype=float)
        h = np.array([e["held"] for e in every], dtype=float)
        print(json.dumps({"ranks": comm.size, "wall": max(e["wall"] for e in every), "steps": every[0]["steps"],
                          "particles": len(model.particles),
                          "exchange_s_per_step": max(e["exchange_s"] for e in every) / every[0]["steps"],
                          "halo_share": float(((h - o) / o).mean()),
                          "imbalance_first": float(o[:, 0].max() / o[:, 0].mean() - 1.0) if o.size else 0.0,
                          "imbalance_last": float(o[:, -1].max() / o[:, -1].mean() - 1.0) if o.size else 0.0,
                          "imbalance_peak": float((o.max(axis=0) / o.mean(axis=0)).max() - 1.0) if o.size else 0.0,
                          "recuts": run.recuts}))


def one_solver(args) -> dict:
    import warp as wp

    wp.config.quiet, wp.config.log_level = True, wp.LOG_WARNING
    from gpusph_ros.scenes.build import build_run
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve

    sc = load_scene(args.scene)
    solver = build_run(sc, resolve(sc, dx=args.dx, end_time=args.end, cpu_threads=args.threads,
                                   energy_growth_ratio=0.0)).solver()
    solver.step()  # the kernels loaded, as the ranks' first step loads theirs
    start = time.perf_counter()
    solver.advance(args.end)
    return {"wall": time.perf_counter() - start, "steps": solver.steps, "particles": solver.n}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="dambreak1_lab")
    ap.add_argument("--dx", type=float, default=0.015)
    ap.add_argument("--end", type=float, default=0.3)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--threads", type=int, default=2, help="the one solver's CPU threads (each rank has one)")
    ap.add_argument("--rebalance", type=float, default=0.1, help=argparse.SUPPRESS)
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        return worker(args)
    mpiexec = Path(sys.executable).parent / "mpiexec"
    here = Path(__file__).resolve()

    def ranks(n: int, threads: int, rebalance: float) -> dict:
        out = subprocess.run([str(mpiexec), "-n", str(n), sys.executable, "-m", "mpi4py", str(here), "--worker",
                              "--scene", args.scene, "--dx", str(args.dx), "--end", str(args.end),
                              "--threads", str(threads), "--rebalance", str(rebalance)], capture_output=True,
                             text=True, check=True)
        return json.loads(out.stdout.strip().splitlines()[-1])

    one = one_solver(args)
    print(f"{args.scene} at dx = {args.dx} m to t = {args.end} s, {one['particles']:,} particles")
    print(f"one solver, {args.threads} threads, replayed loop: {one['wall']:.1f} s, {one['steps']} steps, "
          f"{one['particles'] * one['steps'] / one['wall'] / 1e6:.3f} MIPPS")
    for n, threads, rebalance in ((1, args.threads, 0.1), (args.ranks, 1, 0.0), (args.ranks, 1, 0.1)):
        r = ranks(n, threads, rebalance)
        cut = "" if n == 1 else ", cuts kept" if not rebalance else f", cuts moved {r['recuts']} times"
        print(f"{n} rank(s) x {threads} thread(s){cut}, host-driven: {r['wall']:.1f} s ({r['wall'] / one['wall']:.2f}x "
              f"the one solver), {r['steps']} steps, exchange {1e3 * r['exchange_s_per_step']:.2f} ms a step, halo "
              f"{100 * r['halo_share']:.1f}% of the owned, imbalance {100 * r['imbalance_first']:+.1f}% at the start, "
              f"{100 * r['imbalance_peak']:+.1f}% at its worst, {100 * r['imbalance_last']:+.1f}% at the end",
              flush=True)


if __name__ == "__main__":
    main()
