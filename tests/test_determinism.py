"""The same run gives the same bits however its threads run: on the CPU under the strict mode
(sph/device_calls.strict: no allocation, allocating utility or host read inside a captured
region; a heavy pass's chunks run last first), over more than 200 steps and eight outputs, the
replayed loop on one thread and the eager loop on 1, 2 and 3 threads end on the same state and
record the same outputs (a body's wrench, column means, pressure blocks, the floating bodies'
states and the census), for dynamic, Adami and mDBC walls, a zone under multirate, a floating
body and a driven one.

A GPU runs a kernel's threads at once and in any order, so a sum whose bits depend on the order
of its terms (a float atomic add) differs from run to run there; on the CPU it differs between
thread counts once its pass is cut into chunks, which is what this test sees."""
import hashlib

import numpy as np
import pytest

from gpusph_ros.measure.blocks import PressureBlockForce
from gpusph_ros.measure.columns import ColumnMeans
from gpusph_ros.measure.forces import BodyWrench
from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import parse_scene
from gpusph_ros.sph.device_calls import strict

pytestmark = pytest.mark.unit

COLUMN = {"name": "tank", "dim": 2, "tank": [0.6, 0.32],
          "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.12, 0.2]}]}
BLOCK = {"name": "block", "lo": [0.3, 0.0], "hi": [0.34, 0.06]}
DOWNSTREAM = {"name": "downstream", "lo": [0.2, 0.0], "hi": [0.6, 0.32], "ratio": 0.5}
FLOATING = {"name": "box", "lo": [0.03, 0.18], "hi": [0.09, 0.22], "displaces_fluid": True,
            "floating": {"density": 500.0}}
DRIVEN = {"name": "paddle", "lo": [0.3, 0.0], "hi": [0.34, 0.32],
          "motion": {"type": "driven", "max_speed": 0.5, "max_acceleration": 5.0}}
WITH_BLOCK = {**COLUMN, "obstacles": [BLOCK]}
CASES = {"dynamic": (WITH_BLOCK, dict(dx=0.01, shepard_every=30)),
         "adami": (WITH_BLOCK, dict(dx=0.01, boundary="adami")),
         "mdbc": (WITH_BLOCK, dict(dx=0.01, boundary="mdbc")),
         "zoned_multirate": ({**WITH_BLOCK, "refine": [DOWNSTREAM]}, dict(dx=0.02)),
         "floating": ({**COLUMN, "obstacles": [FLOATING]}, dict(dx=0.01)),
         "driven": ({**COLUMN, "obstacles": [DRIVEN]}, dict(dx=0.01))}
OUTPUTS = 8
INTERVAL = 0.01


def _record(h, *values):
    for v in values:
        h.update(np.ascontiguousarray(np.asarray(v, dtype=np.float64)).tobytes())


def run(case: str, step_graph: str, threads: int):
    """(steps, digest) of ``case``: its state and every recorded output over OUTPUTS outputs."""
    scene, settings = CASES[case]
    model = build(parse_scene(scene), step_graph=step_graph, cpu_threads=threads, **settings)
    solver = model.solver()
    box = next(o for o in scene["obstacles"])
    centre = [0.5 * (a + b) for a, b in zip(box["lo"], box["hi"])] + [0.0]
    wrench = BodyWrench(solver, 0, centre)
    columns = ColumnMeans(solver, [[0.1, 0.0, 0.0], [0.25, 0.0, 0.0]], [0.03, 0.03])
    blocks = PressureBlockForce(solver, (0.3, 0.0, 0.0), (0.34, 0.06, 0.0))
    h = hashlib.sha256()
    for k in range(1, OUTPUTS + 1):
        if case == "driven":
            pose = solver.body_poses()[0]
            solver.drive(0, solver.time, pose["position"], pose["quaternion"], (0.02 * (-1) ** k, 0.0, 0.0),
                         (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
        solver.advance(INTERVAL * k)
        force, torque = wrench.sample()
        means = columns.sample()
        _record(h, force, torque, means["vel"], means["count"], list(blocks.sample().values()))
        _record(h, *[[*s["position"], *s["velocity"], *s["quaternion"], *s["angular_momentum"]]
                     for s in solver.body_states() if s is not None])
        _record(h, solver._census_host, solver.clock.numpy())
    snap = solver.snapshot()
    _record(h, snap["pos"], snap["vel"], snap["rho"], snap["ptype"])
    return solver.steps, h.hexdigest()


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_same_bits_replayed_and_eager_on_1_2_and_3_threads(case):
    with strict():
        runs = {(graph, threads): run(case, graph, threads) for graph, threads in
                (("on", 1), ("off", 1), ("off", 2), ("off", 3))}
    steps, digest = runs[("on", 1)]
    assert steps >= 200
    assert all(r == (steps, digest) for r in runs.values()), runs
