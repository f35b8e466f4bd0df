"""Run under mpiexec by tests/test_ranks.py: a scene stepped on every rank (sph/exchange.py), its
owned particles' state gathered to rank 0 and saved.

    mpiexec -n N python tests/ranks_run.py OUT.npz SCENE DX STEPS [KEY=VALUE ...]
"""
import sys

import numpy as np
import warp as wp
from mpi4py import MPI


def main():
    out, scene, dx, steps, *sets = sys.argv[1:]
    wp.config.log_level = wp.LOG_WARNING
    wp.config.quiet = True
    from gpusph_ros.scenes.build import build_run
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve
    from gpusph_ros.sph.exchange import RankedRun

    sc = load_scene(scene)
    model = build_run(sc, resolve(sc, sets=sets, dx=float(dx), end_time=10.0))
    run = RankedRun(model, MPI.COMM_WORLD)
    times = [run.step() for _ in range(int(steps))]
    state = run.gather()
    if state is not None:
        np.savez(out, times=np.array(times), **state)


if __name__ == "__main__":
    main()
