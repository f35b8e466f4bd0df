"""The host memory a saved state costs: DamBreak 1 at about ``--particles`` particles, stepped to its
first output, then its state taken (sph/checkpoint.capture) and written as a state file
(output/state_file.write), as ``~/save_state`` and a run's checkpoints do. Python's allocation
tracer counts the host arrays made meanwhile (numpy's among them); the peak is set against the
state's own size (the bytes of its arrays). Read back into a second solver, the state must step on
bit for bit (the digest of positions, velocities and densities after one more output).

    python bench/state_memory.py [--particles 1e6] [--set neighbour_search=cells]
"""
import argparse
import hashlib
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

from series import model_of_about


def digest(solver) -> str:
    snap = solver.snapshot()
    return hashlib.sha256(b"".join(np.ascontiguousarray(snap[n]).tobytes() for n in ("pos", "vel", "rho"))).hexdigest()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--particles", type=float, default=1e6)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args()
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.output import state_file
    from gpusph_ros.scenes.settings import parse_set
    from gpusph_ros.sph import checkpoint

    model = model_of_about("dambreak1_lab", args.particles, **dict(parse_set(item) for item in args.set))
    solver = model.solver()
    solver.advance(0.01)
    search = "walking the cells" if solver.neighbours.cells else "with lists"
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "state.npz"
        tracemalloc.start()
        start = time.perf_counter()
        state = checkpoint.capture(solver)
        state_file.write(path, "checkpoint", {"solver": state})
        wall = time.perf_counter() - start
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        own = sum(a.nbytes for a in state["arrays"].values())
        print(f"DamBreak 1 lab at dx = {model.config.dx:.4g} m, {solver.n:,} particles, {search}: device "
              f"{solver.device_bytes() / 2 ** 20:.1f} MiB; the state {own / 2 ** 20:.1f} MiB, its file "
              f"{path.stat().st_size / 2 ** 20:.1f} MiB; host arrays made taking and writing it: peak "
              f"{peak / 2 ** 20:.1f} MiB ({peak / own:.2f} x the state), {wall:.1f} s")
        del state
        read = state_file.read(path, "checkpoint")["solver"]
    second = model.solver()
    checkpoint.restore(second, read)
    for s in (solver, second):
        s.advance(0.02)
    print("read back, one more output: " + ("the same digest" if digest(solver) == digest(second) else "DIFFERS"))


if __name__ == "__main__":
    main()
