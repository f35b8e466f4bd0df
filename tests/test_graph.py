"""The step loop replayed from a captured graph (sph/graph.py) takes the steps the eager loop takes,
bit for bit, on the CPU (Warp's API capture), over more than 200 steps and eight outputs: dynamic
walls with the Shepard filter, mDBC, a zone under multirate (the list builds, reorders, census,
filter and level changes all branches of the captured step), and bodies that move and float, alone
and in a zone. A
replayed loop stops for the host every 64 steps when it can be interrupted, and a reconfigure takes
effect in the next replay."""
import hashlib

import numpy as np
import pytest

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import parse_scene

pytestmark = pytest.mark.unit

TANK = {"name": "tank", "dim": 2, "tank": [0.6, 0.32]}
COLUMN = {**TANK, "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.12, 0.2]}]}
DOWNSTREAM = {"name": "downstream", "lo": [0.2, 0.0], "hi": [0.6, 0.32], "ratio": 0.5}
CASES = {"dynamic": (COLUMN, dict(dx=0.01, shepard_every=30)),
         "mdbc": (COLUMN, dict(dx=0.01, boundary="mdbc")),
         "zoned": ({**COLUMN, "refine": [DOWNSTREAM]}, dict(dx=0.02)),
         # a paddle on a sinusoid and a box floating on the column (sph/bodies.py)
         "bodies": ({**COLUMN, "obstacles": [
             {"name": "paddle", "lo": [0.3, 0.0], "hi": [0.34, 0.32],
              "motion": {"type": "sinusoid", "amplitude": [0.01, 0.0], "period": 0.1, "phase_deg": -90}},
             {"name": "box", "lo": [0.03, 0.18], "hi": [0.09, 0.22], "displaces_fluid": True,
              "floating": {"density": 500.0}}]}, dict(dx=0.01)),
         # both in a zone under multirate, the column running into it
         "zoned_bodies": ({**COLUMN, "refine": [DOWNSTREAM], "obstacles": [
             {"name": "paddle", "lo": [0.5, 0.0], "hi": [0.54, 0.32],
              "motion": {"type": "sinusoid", "amplitude": [0.01, 0.0], "period": 0.1, "phase_deg": -90}},
             {"name": "box", "lo": [0.33, 0.05], "hi": [0.39, 0.09], "floating": {"density": 500.0}}]}, dict(dx=0.02))}


def digest(solver) -> str:
    snap = solver.snapshot()
    h = hashlib.sha256()
    for name in ("pos", "vel", "rho", "ptype"):
        h.update(np.ascontiguousarray(snap[name]).tobytes())
    h.update(solver.clock.numpy().tobytes())
    return h.hexdigest()


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_replayed_loop_is_bit_identical_to_the_eager_loop(case):
    scene, settings = CASES[case]
    runs = {}
    for mode in ("off", "on"):
        solver = build(parse_scene(scene), step_graph=mode, **settings).solver()
        for k in range(1, 9):
            solver.advance(0.01 * k)
        runs[mode] = (solver.steps, int(solver.neighbours.builds.numpy()[0]), digest(solver))
    assert runs["on"] == runs["off"]
    assert runs["on"][0] >= 200


def test_a_replayed_loop_stops_for_an_interrupt_first_and_every_64_steps_and_takes_a_reconfigure():
    solver = build(parse_scene(COLUMN), dx=0.01, step_graph="on").solver()
    asked = []

    def interrupt():
        asked.append(solver.steps)
        return len(asked) >= 3

    solver.advance(1.0, interrupt)
    assert not solver.reached(1.0)
    # asked before the first step, then after each block of 64 launched steps (no step in between on
    # a replay)
    assert asked == [0, 64, 128]
    # asked first, a stop takes no step (a SIGTERM between two outputs that a block each reaches)
    solver.advance(1.0, lambda: True)
    assert solver.steps == 128
    solver.reconfigure(dt_fixed=1.0e-4)
    start = solver.time
    solver.advance(start + 0.001)
    assert solver.steps == 128 + 10 and solver.time == pytest.approx(start + 0.001, abs=1e-12)
