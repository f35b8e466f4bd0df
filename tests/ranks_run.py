"""Run under mpiexec by tests/test_ranks.py: a scene stepped on every rank (sph/exchange.py), its
owned particles' state gathered to rank 0 and saved with each step's time, how often the slabs
were cut again, the run's health peaks and its last census's totals (Solver.health_peaks: every
rank's are the run's).

    mpiexec -n N python -m mpi4py tests/ranks_run.py OUT.npz SCENE DX STEPS [KEY=VALUE ...]
        [--rebalance FRACTION] [--every STEPS] [--save-at STEP --state FILE | --resume FILE]

``--save-at``: the run's state (sph/portable.py) after that many steps, to FILE; ``--resume``: go on
from such a state for STEPS more steps.
"""
import argparse

import numpy as np
import warp as wp
from mpi4py import MPI


def save_state(path, state):
    if state is not None:
        np.savez(path, **{f"{part}.{k}": v for part in ("particles", "counters", "bodies")
                          for k, v in state[part].items()})


def load_state(path) -> dict:
    from gpusph_ros.sph import portable

    with np.load(path) as f:
        return {"format": portable.FORMAT, "particles": {k: f[f"particles.{k}"] for k in portable.PARTICLE_KEYS},
                "counters": {k: f[f"counters.{k}"] for k in portable.COUNTERS},
                "bodies": {k: f[f"bodies.{k}"] for k in portable.BODIES if f"bodies.{k}" in f}}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("scene")
    ap.add_argument("dx", type=float)
    ap.add_argument("steps", type=int)
    ap.add_argument("sets", nargs="*")
    ap.add_argument("--rebalance", type=float, default=0.1)
    ap.add_argument("--every", type=int, default=100)
    ap.add_argument("--save-at", type=int, default=-1)
    ap.add_argument("--state")
    ap.add_argument("--resume")
    args = ap.parse_args()
    wp.config.log_level = wp.LOG_WARNING
    wp.config.quiet = True
    from gpusph_ros.scenes.build import build_run
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve
    from gpusph_ros.sph.exchange import RankedRun

    sc = load_scene(args.scene)
    model = build_run(sc, resolve(sc, sets=args.sets, dx=args.dx, end_time=10.0))
    state = None if args.resume is None else load_state(args.resume)
    run = RankedRun(model, MPI.COMM_WORLD, rebalance=args.rebalance, rebalance_every=args.every, state=state)
    cuts = [run.slabs.cuts]
    times = []
    for k in range(args.steps):
        if k == args.save_at:
            save_state(args.state, run.portable())
        times.append(run.step())
    cuts.append(run.slabs.cuts)
    state = run.gather()
    if state is not None:
        peaks = {f"peak.{k}": np.nan if v is None else v for k, v in run.solver.health_peaks.items()}
        np.savez(args.out, times=np.array(times), recuts=run.recuts, first_cuts=np.array(cuts[0]),
                 last_cuts=np.array(cuts[-1]), census=run.solver._census_host, **state, **peaks)


if __name__ == "__main__":
    main()
