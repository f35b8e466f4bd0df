"""The same run twice on one device, bit for bit: DamBreak 1 of the experiment (3D) with dynamic and
Adami walls, in its refinement zone under multirate, and with a box floating in its column, each
run twice from the same build, outputs every 0.01 s, and a digest of its state, the obstruction's
(or the box's) wrench at every output and the floating body's state compared (make gpu-check's
determinism step). A GPU runs a kernel's threads in any order: a sum whose bits depend on it
makes two runs differ, which tests/test_determinism.py can only approximate on the CPU.

    python bench/repeat.py [--device cuda:0] [--dx 0.02] [--end 0.1]

Exits 1 when a case's two runs differ.
"""
import argparse
import hashlib
import sys
import time

import numpy as np
import yaml

FLOATING_BOX = {"name": "box", "lo": [0.1, 0.28, 0.25], "hi": [0.2, 0.38, 0.35], "displaces_fluid": True,
                "floating": {"density": 500.0}}
# case: (scene, settings, an obstacle added)
CASES = {"dynamic": ("dambreak1_lab", {"boundary": "dynamic"}, None),
         "adami": ("dambreak1_lab", {"boundary": "adami"}, None),
         "zoned multirate": ("dambreak1_lab_zoned", {}, None),
         "floating": ("dambreak1_lab", {}, FLOATING_BOX)}


def digest(case: str, device: str, dx: float, end: float) -> tuple:
    """(steps, particles, hex digest, wall seconds) of one run of ``case``."""
    from gpusph_ros.measure.forces import BodyWrench
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import load_scene, parse_scene

    name, settings, extra = CASES[case]
    data = yaml.safe_load(load_scene(name).text)
    if extra is not None:
        data["obstacles"] = [*data.get("obstacles", []), extra]
    solver = build(parse_scene(data), dx=dx, device=device, **settings).solver()
    wrenches = [BodyWrench(solver, b) for b in range(len(data["obstacles"]))]
    h = hashlib.sha256()
    start = time.perf_counter()
    for k in range(1, int(round(end / 0.01)) + 1):
        solver.advance(0.01 * k)
        for w in wrenches:
            h.update(np.concatenate(w.sample()).tobytes())
        for s in solver.body_states():
            if s is not None:
                h.update(np.concatenate([s["position"], s["velocity"], s["quaternion"]]).tobytes())
    wall = time.perf_counter() - start
    snap = solver.snapshot()
    for field in ("pos", "vel", "rho", "ptype"):
        h.update(np.ascontiguousarray(snap[field]).tobytes())
    return solver.steps, solver.n, h.hexdigest()[:16], wall


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cuda:0")
    parser.add_argument("--dx", type=float, default=0.02)
    parser.add_argument("--end", type=float, default=0.1)
    args = parser.parse_args()
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    differ = []
    for case in CASES:
        runs = [digest(case, args.device, args.dx, args.end) for _ in range(2)]
        same = runs[0][:3] == runs[1][:3]
        steps, n = runs[0][:2]
        print(f"{case}: {n} particles, {steps} steps, digests {runs[0][2]} {runs[1][2]}: "
              f"{'the same' if same else 'DIFFER'}; {runs[0][3]:.1f} s and {runs[1][3]:.1f} s, "
              f"{n * steps / runs[1][3] / 1e6:.2f} MIPPS", flush=True)
        if not same:
            differ.append(case)
    print("every case repeats bit for bit" if not differ else f"differ: {', '.join(differ)}")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
