"""A solver's state taken and put back (sph/checkpoint.py): a solver restored from a state taken at
0.1 s and stepped to 0.2 s ends bit for bit where the solver it was taken from ends, for each kind of
wall, viscosity and precision, in 2D and 3D; the neighbour lists, of which only the used entries are
stored, come back pair for pair; with a refinement zone too, across the steps where particles change level."""
import numpy as np
import pytest

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene, parse_scene
from gpusph_ros.sph import checkpoint

pytestmark = pytest.mark.physics
# a column collapsing into a refinement zone: between 0.1 and 0.2 s its surge reaches the zone, where
# particles change level and new ones are made in reserved slots (sph/levels.py)
ZONED = {"name": "zoned", "dim": 2, "tank": [0.6, 0.32], "fluid": [{"name": "water", "lo": [0, 0], "hi": [0.12, 0.2]}],
         "refine": [{"name": "downstream", "lo": [0.2, 0.0], "hi": [0.6, 0.32], "ratio": 0.5}]}
# a box floating in a tank, let go 5 mm above its draft, beside a paddle that moves (sph/bodies.py)
BODIES = {"name": "bodies", "dim": 2, "tank": [0.6, 0.4],
          "fluid": [{"name": "water", "lo": [0.1, 0], "hi": [0.6, 0.2]}],
          "obstacles": [{"name": "box", "lo": [0.3, 0.18], "hi": [0.4, 0.23], "displaces_fluid": True,
                         "floating": {"density": 500}},
                        {"name": "paddle", "lo": [0.04, 0.0], "hi": [0.1, 0.4],
                         "motion": {"type": "sinusoid", "amplitude": [0.01, 0.0], "period": 0.5, "phase_deg": -90}}]}


@pytest.mark.parametrize("scene, dx, settings", [
    ("collapse_2d", 0.01, {}),
    ("collapse_2d", 0.01, {"viscosity": "sps", "precision": "float64"}),
    ("dambreak1_thesis", 0.06, {"boundary": "mdbc"}),
    ("dambreak1_thesis", 0.06, {"boundary": "adami"}),
    ("dambreak1_thesis", 0.06, {"boundary": "monaghan_kajtar", "shifting": True}),
    (ZONED, 0.02, {}),
    (BODIES, 0.02, {}),
])
def test_a_restored_solver_steps_as_the_one_it_was_taken_from(scene, dx, settings):
    model = build(load_scene(scene) if isinstance(scene, str) else parse_scene(scene), dx=dx, **settings)
    first = model.solver()
    first.advance(0.1)
    state = checkpoint.capture(first)
    assert "neighbours.nbr" not in state["arrays"]  # built again from the last build's sort
    second = model.solver()
    checkpoint.restore(second, state)
    if not first.neighbours.cells:  # the device's choice: a GPU walks the cells and holds no lists
        count = first.neighbours.count.numpy()
        assert np.array_equal(second.neighbours.count.numpy(), count)
        width = first.neighbours.max_neighbours
        used = np.arange(width)[None, :] < count[:, None]  # the slots past a list's length hold old entries
        lists = [nl.nbr.numpy().reshape(-1, width)[used] for nl in (first.neighbours, second.neighbours)]
        assert np.array_equal(*lists) and count.sum() > 0
    assert second.neighbours.builds.numpy()[0] == first.neighbours.builds.numpy()[0]
    first.advance(0.2)
    second.advance(0.2)
    assert (second.steps, second.time) == (first.steps, first.time)
    a, b = first.snapshot(), second.snapshot()
    assert all(np.array_equal(a[k], b[k]) for k in a)
    for x, y in zip(first.body_states(), second.body_states()):
        assert x is None and y is None or all(np.array_equal(x[k], y[k]) for k in x)


def test_a_state_of_another_solver_is_refused_with_what_differs():
    small = build(load_scene("collapse_2d"), dx=0.01).solver()
    other = build(load_scene("collapse_2d"), dx=0.02).solver()
    with pytest.raises(ValueError, match="checkpoint: .* has shape"):
        checkpoint.restore(other, checkpoint.capture(small))


def _digest(solver) -> dict:
    return checkpoint.fingerprint(checkpoint.capture(solver))


def test_an_edited_state_is_refused_whole_and_changes_nothing():
    # a count or size from the file (n x 100 crashed the node: kernels indexed past the arrays), a
    # shifted position beside a later array of the wrong trailing shape or dtype (the shift was
    # already in when the later array failed), an index out of range, a NaN: each refused by name
    solver = build(parse_scene(BODIES), dx=0.02, neighbour_search="lists").solver()  # a width to edit
    solver.advance(0.01)
    good = checkpoint.capture(solver)
    before = _digest(solver)

    def edited(arrays=None, **host):
        state = {"arrays": {**good["arrays"], **(arrays or {})}, "host": {k: dict(v) for k, v in good["host"].items()}}
        for name, value in host.items():
            holder, key = name.split("__")
            state["host"][holder][key] = value
        return state

    shifted = good["arrays"]["solver.pos"] + np.float32(0.3)
    for state, why in [
            (edited(solver__n=good["host"]["solver"]["n"] * 100), "solver value n differs"),
            (edited(neighbours__n=good["host"]["neighbours"]["n"] * 100), "neighbours value n differs"),
            (edited({"solver.pos": shifted, "solver.vel": good["arrays"]["solver.vel"][:, :2]}),
             "solver.vel has shape"),
            (edited({"solver.pos": shifted, "solver.rho": good["arrays"]["solver.rho"].astype(np.complex128)}),
             "solver.rho holds complex128"),
            (edited({"solver.pos": shifted, "solver.mass": good["arrays"]["solver.mass"].astype(str)}),
             "solver.mass holds <U"),
            (edited({"solver.ids": good["arrays"]["solver.ids"] + 5}), "solver.ids is not an order"),
            (edited({"solver.body": good["arrays"]["solver.body"] + 7}), "solver.body lies outside"),
            (edited({"solver.vel": good["arrays"]["solver.vel"] * np.nan}), "solver.vel holds a value that is not"),
            (edited(solver__time=float("nan")), "solver value time is not a value"),
            (edited(neighbours__max_neighbours=100_000), "lists are 100000 wide"),
            # a failure's slot is read on the host as the index of what failed: a body 13 of none
            # raised an IndexError out of the next advance (the 10-minute fuzz)
            (edited({"solver._fail": np.full_like(good["arrays"]["solver._fail"], 13)}),
             "solver._fail holds a failure"),
            # one particle at 1e30 m/s shrank the step until time stood still (the 10-minute fuzz)
            (edited({"solver.vel": np.where(np.arange(solver.n)[:, None] == 7, np.float32(1e30),
                                            good["arrays"]["solver.vel"])}), "solver.vel holds a speed of 1.73e\\+30")]:
        with pytest.raises(ValueError, match=why):
            checkpoint.restore(solver, state)
        assert _digest(solver) == before, why
    checkpoint.restore(solver, good)  # the state itself still goes in and runs
    solver.advance(0.02)


@pytest.mark.parametrize("search", ["lists", "cells"])
def test_a_state_whose_list_rebuild_data_do_not_follow_from_its_positions_is_refused(search):
    """Issue 66, item 3: the sort reversed, the build positions moved (by 1 m, by 0.3 dx, to 1e30),
    the cell ranges emptied or spread over every particle, the list lengths zeroed or cut, the ids
    shuffled: each loaded with success and moved a resumed run by up to a millimetre, or failed its
    first step.
    Each is refused, naming what does not follow from the positions, and the solver is unchanged."""
    solver = build(parse_scene(BODIES), dx=0.02, neighbour_search=search).solver()
    solver.advance(0.05)
    good = checkpoint.capture(solver)
    before = _digest(solver)
    n, a = solver.n, good["arrays"]

    def edited(**arrays):
        return {"arrays": {**a, **arrays}, "host": good["host"]}

    order = a["neighbours._order"].copy()
    order[:n] = order[:n][::-1]
    x = a["neighbours._x_build"]
    sort, ranges, moved = "is not the cell sort of the build positions", "are not the cell ranges", "from its build"
    positions = f"{sort}|{ranges}|{moved}"  # a moved build position shows first in whichever it breaks
    cases = [(edited(**{"neighbours._order": order}), sort),
             (edited(**{"neighbours._x_build": x + np.float32(1.0)}), positions),
             (edited(**{"neighbours._x_build": x + np.float32([0.006, 0.0, 0.0])}), positions),
             (edited(**{"neighbours._x_build": np.full_like(x, 1e30)}), positions),
             (edited(**{"neighbours._start": np.zeros_like(a["neighbours._start"]),
                        "neighbours._end": np.zeros_like(a["neighbours._end"])}), ranges),
             (edited(**{"neighbours._start": np.zeros_like(a["neighbours._start"]),
                        "neighbours._end": np.full_like(a["neighbours._end"], n)}), ranges),
             # the ids shuffled: the bodies' particles were set on other particles' rest positions
             # at the next step, which shrank until time stood still
             (edited(**{"solver.ids": np.random.default_rng(1).permutation(a["solver.ids"])}),
              "a moving body's particle")]
    if search == "lists":
        cases += [(edited(**{"neighbours.count": np.zeros_like(a["neighbours.count"])}), "neighbours.count is not"),
                  (edited(**{"neighbours.count": np.minimum(a["neighbours.count"], 3)}), "neighbours.count is not")]
    for state, why in cases:
        with pytest.raises(ValueError, match=why):
            checkpoint.restore(solver, state)
        assert _digest(solver) == before, why
    checkpoint.restore(solver, good)
    assert _digest(solver) == before



@pytest.mark.parametrize("major", [False, True])
def test_a_state_holds_no_lists_and_they_are_built_again_as_they_were(major):
    """The lists are built again from what a state keeps of their last build (its sort, the positions
    then, the kinds and h it read, the lengths), entry for entry, in either layout (a GPU's
    neighbour-major one too), after particles were excluded and the lists went stale since (a
    state holds the lists of 10^7 particles in 1-7 GB: now none)."""
    model = build(load_scene("collapse_2d"), dx=0.02, neighbour_search="lists")
    solvers = []
    for _ in range(2):
        solver = model.solver()
        solver.neighbours.neighbour_major = major
        solver.neighbours.resize(solver.neighbours.max_neighbours)
        solvers.append(solver)
    first, second = solvers
    first.advance(0.05)
    first.step()  # between outputs: the lists stale or not, as the step left them
    state = checkpoint.capture(first)
    assert not [path for path in state["arrays"] if "nbr" in path]
    checkpoint.restore(second, state)
    count = first.neighbours.count.numpy()
    assert np.array_equal(second.neighbours.count.numpy(), count) and count.sum() > 0
    width = first.neighbours.max_neighbours
    used = np.arange(width)[None, :] < count[:, None]
    assert np.array_equal(first.neighbours.nbr.numpy()[used], second.neighbours.nbr.numpy()[used])
    for solver in solvers:
        solver.advance(0.08)
    for name in ("pos", "vel", "rho", "ptype"):
        np.testing.assert_array_equal(first.snapshot()[name], second.snapshot()[name])
