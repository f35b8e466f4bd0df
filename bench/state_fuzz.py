"""Edited state files against a live solver: each array and host value of a real state mutated in
turn (scaled, negated, NaN, infinite, another dtype, another shape, indices out of range, text, one
element anywhere set to an extreme, drawn afresh on each pass),
written to a state file, read back and restored. The process must never die, a refused state
must leave the run as it was, bit for bit, and an accepted one must run (a health check, or the
lists' overflow of clumped particles, may stop it; nothing else may).

The cases run in a child process, which names each case before it tries it: if the child dies
(SIGSEGV, an abort from the allocator) the parent reports the case and exits 1.

    python bench/state_fuzz.py [--minutes 10] [--seed 1]

tests/test_state_fuzz.py runs an 18-second round in the suite.
"""
import argparse
import ctypes
import json
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

# a 2D column with a floating box beside a refinement zone under multirate: every array family
SCENE = {"name": "fuzz", "dim": 2, "tank": [0.6, 0.32],
         "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.12, 0.2]}],
         "refine": [{"name": "downstream", "lo": [0.3, 0.0], "hi": [0.6, 0.32], "ratio": 0.5}],
         "obstacles": [{"name": "box", "lo": [0.03, 0.18], "hi": [0.09, 0.22], "displaces_fluid": True,
                        "floating": {"density": 500.0}}]}


def mutations(value, rng):
    """(name, mutated value) of ``value``, an array or a host value."""
    if isinstance(value, np.ndarray):
        out = [("shape -1", value[:-1]), ("shape +1", np.concatenate([value, value[-1:]]) if value.size else value),
               ("axis +1", value[..., None]), ("zeros", np.zeros_like(value))]
        if value.dtype.names:  # a struct array: its fields are mutated as a whole
            return out
        out.append(("text", value.astype(str)))
        if value.dtype.kind == "f":
            out += [("x100", value * 100), ("x1e6", value * 1e6), ("negated", -value), ("NaN", value * np.nan),
                    ("inf", value + np.inf), ("other float", value.astype(np.float32 if value.dtype == np.float64
                                                                             else np.float64)),
                    ("complex", value.astype(np.complex128))]
        if value.dtype.kind in "fiu" and value.size:  # one element, anywhere, set to an extreme
            one = value.copy()
            extremes = [-2 ** 31, -1, 0, 1, len(value), 2 ** 31 - 1] + (
                [np.nan, np.inf, -np.inf, 1e30, -1e30, 1e-30] if value.dtype.kind == "f" else [])
            one.flat[rng.integers(one.size)] = extremes[rng.integers(len(extremes))]
            out.append(("one element", one))
        if value.dtype.kind in "iu":
            big = np.iinfo(np.int32).max
            out += [("x100", value * 100), ("negated", -value), ("+n", value + len(value)), ("max", value * 0 + big),
                    ("min", value * 0 - big), ("int64", value.astype(np.int64)),
                    ("shuffled", rng.permutation(value)), ("datetime", value.astype("datetime64[s]"))]
        return out
    if isinstance(value, bool) or value is None:
        return [("text", "x"), ("number", 7)]
    if isinstance(value, (int, float)):
        return [("x100", value * 100), ("x1e9", value * 10 ** 9), ("negated", -value), ("NaN", float("nan")),
                ("inf", float("inf")), ("text", str(value)), ("other type", float(value) if isinstance(value, int)
                                                               else int(value) if np.isfinite(value) else 0)]
    if isinstance(value, (tuple, list)):
        return [("shorter", type(value)(value[:-1])), ("longer", type(value)([*value, *value[-1:]])),
                ("text", "x")]
    return [("text", "x")]


def cases(state, rng):
    """(label, mutated state) of every field of ``state`` (a checkpoint.capture) and its mutations."""
    for path in sorted(state["arrays"]):
        for name, value in mutations(state["arrays"][path], rng):
            yield f"arrays {path}: {name}", {**state, "arrays": {**state["arrays"], path: value}}
    for holder in sorted(state["host"]):
        for key in sorted(state["host"][holder]):
            for name, value in mutations(state["host"][holder][key], rng):
                host = {**state["host"], holder: {**state["host"][holder], key: value}}
                yield f"host {holder}.{key}: {name}", {**state, "host": host}


def _die_with_parent():
    """Have Linux kill this process when its parent dies: a parent stopped at its time limit (the
    suite's subprocess timeout) left a child stuck in a case running for hours beside later tests."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # not Linux: the child outlives a killed parent, as before
        pass


def child(seconds: float, seed: int, log: Path):
    """Try cases until ``seconds`` pass; each case's label into ``log`` before it is tried, its
    outcome after. Raises AssertionError on a refusal that changed the run."""
    _die_with_parent()
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.output import state_file
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import parse_scene
    from gpusph_ros.sph import checkpoint
    from gpusph_ros.sph.health import HealthError
    from gpusph_ros.sph.neighbours import NeighbourOverflow

    solver = build(parse_scene(SCENE), dx=0.02, cpu_threads=1).solver()
    solver.advance(0.02)
    original = checkpoint.capture(solver)
    before = checkpoint.fingerprint(original)
    checkpoint.restore(solver, original)  # the state as taken goes in whole
    assert checkpoint.fingerprint(checkpoint.capture(solver)) == before, "the state as taken did not go back in whole"
    rng = np.random.default_rng(seed)
    end = time.monotonic() + seconds
    tally = {"refused": 0, "accepted and ran": 0, "accepted, stopped by a health check": 0}
    path = Path(tempfile.mkdtemp()) / "state.npz"
    last = None
    with open(log, "a") as out:
        while time.monotonic() < end:
            for label, state in cases(original, rng):
                if time.monotonic() >= end:
                    break
                out.write(json.dumps({"case": label}) + "\n")
                out.flush()
                try:
                    state_file.write(path, "fuzz", state)
                    state = state_file.read(path, "fuzz")
                    checkpoint.restore(solver, state)
                except (ValueError, TypeError) as err:  # StateFileError is a ValueError
                    tally["refused"] += 1
                    now = checkpoint.fingerprint(checkpoint.capture(solver))
                    changed = sorted(k for k in before if now.get(k) != before[k])
                    assert not changed, f"{label}: refused ({err}) but {changed} changed (the case before: {last})"
                    continue
                try:
                    solver.advance(solver.time + 0.002)
                    tally["accepted and ran"] += 1
                except (HealthError, NeighbourOverflow):  # the run stopped by a check, named
                    tally["accepted, stopped by a health check"] += 1
                checkpoint.restore(solver, original)
                last = label
        out.write(json.dumps({"tally": tally}) + "\n")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.minutes * 60.0, args.seed, args.child)
        return 0
    log = Path(tempfile.mkdtemp()) / "cases.jsonl"
    start = time.perf_counter()
    done = subprocess.run([sys.executable, __file__, "--minutes", str(args.minutes), "--seed", str(args.seed),
                           "--child", str(log)], capture_output=True, text=True)
    lines = [json.loads(line) for line in log.read_text().splitlines()] if log.exists() else []
    tried = sum("case" in line for line in lines)
    tally = next((line["tally"] for line in lines if "tally" in line), None)
    print(f"{tried} cases in {time.perf_counter() - start:.0f} s; " + (
        ", ".join(f"{k} {v}" for k, v in tally.items()) if tally else "no tally"))
    if done.returncode != 0:
        last = next((line["case"] for line in reversed(lines) if "case" in line), None)
        print(f"the child process ended with status {done.returncode} during case {last!r}:\n{done.stderr[-3000:]}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
