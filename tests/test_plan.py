"""gpusph-plan (gpusph_ros.plan): the particle count is the scene's, the memory is what the solver
holds, and the step estimate from a calibration at rest is a lower bound close to the real count."""
import numpy as np
import pytest

from gpusph_ros.plan import plan, text
from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.scenes.settings import resolve
from gpusph_ros.sph import Solver

pytestmark = pytest.mark.unit


@pytest.fixture(scope="module")
def collapse():
    scene = load_scene("collapse_2d")
    config = resolve(scene, dx=0.005, end_time=0.1)
    return scene, config, plan(scene, config, calibration_steps=20)


def test_particles_and_memory(collapse):
    scene, config, p = collapse
    model = build(scene, **config.numerics)
    assert p["particles"] == len(model.particles) == 675 and p["fluid_particles"] == 276
    # at least the state the solver cannot do without: position, velocity (3 x 4 B), density, mass,
    # pressure (4 B), type, body, id (4 B) in the three states of a predictor-corrector step
    assert p["device_bytes"] >= 675 * 3 * (12 + 12 + 4 + 4 + 4)
    # and the neighbour list dominates it: max_neighbours x 4 B a particle at most, plus the rest
    solver = Solver(model.config, model.particles)
    assert p["device_bytes"] == solver.device_bytes()
    assert p["device_bytes"] < 675 * (solver.neighbours.max_neighbours * 4 + 400)


def test_the_step_estimate_is_a_close_lower_bound(collapse):
    scene, config, p = collapse
    model = build(scene, **config.numerics)
    solver = Solver(model.config, model.particles)
    solver.advance(config.output.end_time)
    assert p["steps"] <= solver.steps <= 1.3 * p["steps"], (p["steps"], solver.steps)
    assert np.isfinite(p["wall_s"]) and p["wall_s"] > 0
    assert "about" in text(p) and "675" in text(p)
