"""What the step path asks of the device, counted on the CPU: every kernel launch, sort, scan,
copy, fill, host read and allocation around a small scene's steps (sph/device_calls.py).

- An ordinary step (uniform, dynamic walls, lists fresh, no reorder or census due) makes at most
  12 launches and one fill, and sorts nothing; with extrapolated-pressure walls (the default) two
  launches more, the wall's pressure before each of the step's two force evaluations.
- A step whose lists are stale sorts once; a reorder step sorts once too (the build reads the
  reorder's sort).
- Between two outputs the host reads nothing and nothing is allocated: the host reads the clock
  and the flags once before the loop and once after it (Solver._sync), eager or replayed. Replayed,
  no branch takes its flag to the host; eager, six a step do (the loop's RUNNING, REORDER_DUE, the
  lists' stale flag, LISTS_HOLD, CENSUS_DUE, SHEPARD_DUE) and the loop's last test: a GPU without
  conditional graph nodes waits for its stream that often (docs/results/speed.md).
"""
import collections

import numpy as np
import pytest

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import parse_scene
from gpusph_ros.sph import Solver
from gpusph_ros.sph.device_calls import counting
from gpusph_ros.sph.state import CENSUS_DUE, REORDER_DUE

pytestmark = pytest.mark.unit

COLUMN = {"name": "tank", "dim": 2, "tank": [0.6, 0.32],
          "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.12, 0.2]}]}


def solver(**settings):
    # one thread: a heavy pass is one launch, not one per core (launch.py)
    return build(parse_scene(COLUMN), dx=0.01, cpu_threads=1, **settings).solver()


def flags(s) -> dict:
    return {"stale": int(s.neighbours.stale.numpy()[0]), "reorder": int(s.flag(REORDER_DUE).numpy()[0]),
            "census": int(s.flag(CENSUS_DUE).numpy()[0])}


def one_step(s) -> collections.Counter:
    with counting(Solver) as counts:
        s.loop_body(block=2 ** 31 - 1)
    return counts


@pytest.mark.parametrize("boundary, launches", [("dynamic", 12), ("adami", 14)])
def test_an_ordinary_step_makes_at_most_12_launches_and_sorts_nothing(boundary, launches):
    s = solver(boundary=boundary)
    s.advance(0.05)  # the surge under way: the lists go stale every few steps
    s.aim(1.0)
    seen = set()
    for _ in range(64):
        state = flags(s)
        counts = one_step(s)
        if not any(state.values()):
            assert counts["launch"] <= launches and counts["fill"] <= 1, counts
            assert counts["sort"] == counts["scan"] == counts["copy"] == 0, counts
            assert counts["host_read"] == counts["allocation"] == 0, counts
            seen.add("ordinary")
        elif state["stale"] and not state["reorder"]:
            assert counts["sort"] == 1, counts
            seen.add("list build")
        elif state["reorder"]:
            assert counts["sort"] == 1, counts  # the reorder's, which the build reads
            seen.add("reorder")
    assert seen == {"ordinary", "list build", "reorder"}


@pytest.mark.parametrize("step_graph", ["off", "on"])
def test_between_outputs_the_host_reads_nothing_and_nothing_is_allocated(step_graph):
    s = solver(step_graph=step_graph)
    s.advance(0.01)  # loads every kernel and, replayed, captures the loop
    s.advance(0.02)
    for k in range(3, 6):
        steps = s.steps
        with counting(Solver) as counts:
            s.advance(0.01 * k)
        assert s.steps - steps >= 20
        assert counts["sync"] == 2, counts  # before the loop and after it
        assert counts["host_read"] == counts["allocation"] == 0, counts
        assert counts["branch"] == (0 if step_graph == "on" else 6 * (s.steps - steps) + 1), counts


def test_an_output_sorts_only_where_the_lists_are_stale_and_changes_nothing():
    """Lobovsky's tank: four pressure sensors and four gauges read the device at each output through
    one measurement view, one pressure pass and the cells of the lists' last build (each measurement
    made its own pass and sort): an output sorts only where the lists are stale, making the build
    the next step would make at the same positions; a state read again sorts nothing, and a run
    measured at every output steps bit for bit as one that is not."""
    from gpusph_ros.runner import Run
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve

    scene = load_scene("lobovsky_2d")
    measured, plain = [Run(scene, resolve(scene, sets=["dx=0.03", "cpu_threads=1"])) for _ in range(2)]
    stale, view_sorts = 0, 0
    for k in range(8):
        for run in (measured, plain):
            run.solver.advance(k / run.output.output_rate)
        stale += int(measured.solver.neighbours.stale.numpy()[0])
        with counting(Solver) as counts:
            msgs = measured.output_messages(k)
        view_sorts += counts["sort"]
        assert len(msgs) >= 9
        with counting(Solver) as counts:
            measured.output_messages(k)
        assert counts["sort"] == 0, counts
    assert view_sorts == stale < 8
    for name in ("pos", "vel", "rho"):
        np.testing.assert_array_equal(measured.solver.snapshot()[name], plain.solver.snapshot()[name])
