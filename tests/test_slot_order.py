"""A run's answer does not depend on the slots its particles stand in (issue 69, item 2's
foundation: a rank holds a subset of the particles, in its own slots). The cell sort keys each cell's
particles by id (neighbours.cell_keys), so every neighbour sum adds its terms in one order.

Two runs of a scene: at the same times each puts its particles in another slot order and builds
its lists again (Solver.permute), one in the order they stand in, the other in a random order.
Positions, velocities and densities agree bit for bit at the end (by particle). With the sort keyed
on the cell alone (a cell's particles in slot order), the same two runs differ in some hundred
particles' last bits.

Both runs rebuild their lists at the same times: a list orders its neighbours by the cells they
stood in at its build, so a list built at another time adds the same terms in another order. So
ranks build their lists together: any rank's stale flag is every rank's, as one rank's is the OR
over its particles.
"""
import numpy as np
import pytest

from gpusph_ros.scenes.build import build_run
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.scenes.settings import resolve

pytestmark = pytest.mark.unit


def _run(scene: str, dx: float, times, shuffle: bool, **sets) -> dict:
    sc = load_scene(scene)
    solver = build_run(sc, resolve(sc, dx=dx, end_time=times[-1], **sets)).solver()
    rng = np.random.default_rng(7)
    for t in times[:-1]:
        solver.advance(t)
        solver.permute(rng.permutation(solver.n) if shuffle else np.arange(solver.n))
    solver.advance(times[-1])
    snap = solver.snapshot()  # in the particles' own order, whatever their slots
    return {key: snap[key] for key in ("pos", "vel", "rho")}


@pytest.mark.parametrize("scene, dx, times, sets", [
    ("collapse_2d", 0.005, (0.03, 0.06, 0.1), {}),
    ("dambreak1_lab", 0.05, (0.05, 0.1, 0.15), {}),
    ("dambreak1_lab", 0.05, (0.05, 0.1), {"boundary": "mdbc", "shifting": True, "neighbour_search": "cells"}),
])
def test_a_run_steps_bit_for_bit_whatever_slots_its_particles_stand_in(scene, dx, times, sets):
    kept = _run(scene, dx, times, shuffle=False, **sets)
    shuffled = _run(scene, dx, times, shuffle=True, **sets)
    assert np.abs(kept["vel"]).max() > 0.1  # the water moves
    for key in kept:
        assert np.array_equal(kept[key], shuffled[key]), (key, int((kept[key] != shuffled[key]).any(axis=-1).sum()
                                                                   if kept[key].ndim > 1 else
                                                                   (kept[key] != shuffled[key]).sum()))


def test_a_permutation_is_checked():
    sc = load_scene("collapse_2d")
    solver = build_run(sc, resolve(sc, dx=0.01, end_time=0.01)).solver()
    with pytest.raises(ValueError, match="order: a permutation"):
        solver.permute(np.zeros(solver.n, dtype=int))
