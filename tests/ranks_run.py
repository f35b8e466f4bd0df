"""Run under mpiexec by tests/test_ranks.py: a scene stepped on every rank (sph/exchange.py), its
owned particles' state gathered to rank 0 and saved with each step's time and how often the slabs
were cut again.

    mpiexec -n N python -m mpi4py tests/ranks_run.py OUT.npz SCENE DX STEPS [KEY=VALUE ...]
        [--rebalance FRACTION] [--every STEPS]
"""
import argparse

import numpy as np
import warp as wp
from mpi4py import MPI


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("scene")
    ap.add_argument("dx", type=float)
    ap.add_argument("steps", type=int)
    ap.add_argument("sets", nargs="*")
    ap.add_argument("--rebalance", type=float, default=0.1)
    ap.add_argument("--every", type=int, default=100)
    args = ap.parse_args()
    wp.config.log_level = wp.LOG_WARNING
    wp.config.quiet = True
    from gpusph_ros.scenes.build import build_run
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve
    from gpusph_ros.sph.exchange import RankedRun

    sc = load_scene(args.scene)
    model = build_run(sc, resolve(sc, sets=args.sets, dx=args.dx, end_time=10.0))
    run = RankedRun(model, MPI.COMM_WORLD, rebalance=args.rebalance, rebalance_every=args.every)
    cuts = [run.slabs.cuts]
    times = [run.step() for _ in range(args.steps)]
    cuts.append(run.slabs.cuts)
    state = run.gather()
    if state is not None:
        np.savez(args.out, times=np.array(times), recuts=run.recuts, first_cuts=np.array(cuts[0]),
                 last_cuts=np.array(cuts[-1]), **state)


if __name__ == "__main__":
    main()
