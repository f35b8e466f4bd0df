"""Bodies that move on a prescribed path (sph/bodies.py; issue 45): their particles on the law, the
fluid a piston displaces, and the scene's checks of a motion."""
import math

import numpy as np
import pytest

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import parse_scene
from gpusph_ros.sph import Solver
from gpusph_ros.sph.config import ConfigError

DX = 0.02
WATER = 0.27  # [m^2] the section of the piston tank's water: 0.9 m long, 0.3 m deep


def piston_tank(motion: dict, **more) -> dict:
    """A 2D tank 1 m long with a paddle 6 cm thick at x = 0.04-0.10 m and 0.3 m of water beyond it."""
    scene = {"name": "piston", "dim": 2, "tank": [1.0, 0.6], "walls": "particles",
             "fluid": [{"name": "water", "lo": [0.1, 0.0], "hi": [1.0, 0.3]}],
             "obstacles": [{"name": "paddle", "lo": [0.04, 0.0], "hi": [0.1, 0.6], "motion": motion}]}
    scene.update(more)
    return scene


def rotated(r, theta):
    c, s = math.cos(theta), math.sin(theta)
    return np.column_stack([c * r[:, 0] - s * r[:, 1], s * r[:, 0] + c * r[:, 1]])


@pytest.mark.physics
def test_a_flap_and_piston_sinusoid_puts_every_particle_of_the_body_on_its_law():
    """A paddle that swings 4 degrees about its hinge at the floor and slides 2 cm, both at a 1 s
    period from rest (phase -90 degrees): each of its particles, read at the outputs, stands at
    c + d + R(theta)(r0 - c) and moves at d' + theta' z x (x - c - d), the law written here
    independently of the solver's, within float32's round-off (1e-6 m, 1e-5 m/s)."""
    law = {"type": "sinusoid", "amplitude": [0.02, 0.0], "angle_deg": -4.0, "period": 1.0, "phase_deg": -90.0,
           "centre": [0.07, 0.0]}
    model = build(parse_scene(piston_tank(law)), dx=DX)
    solver = Solver(model.config, model.particles)
    paddle = model.particles.body == 0
    r0 = model.particles.pos[paddle, :2] - [0.07, 0.0]
    omega, phase, amp, angle = 2 * math.pi, -math.pi / 2, 0.02, math.radians(-4.0)
    for t in (0.13, 0.4, 0.77):
        solver.advance(t)
        t = solver.time
        f, df = math.sin(omega * t + phase) - math.sin(phase), omega * math.cos(omega * t + phase)
        arm = rotated(r0, angle * f)
        snap = solver.snapshot()
        x_exact = arm + [0.07 + amp * f, 0.0]
        v_exact = np.column_stack([-arm[:, 1], arm[:, 0]]) * angle * df + [amp * df, 0.0]
        assert np.abs(snap["pos"][paddle, :2] - x_exact).max() < 1.0e-6
        assert np.abs(snap["vel"][paddle, :2] - v_exact).max() < 1.0e-5
        walls = ~paddle & (model.particles.ptype == 1)
        assert np.abs(snap["pos"][walls] - model.particles.pos[walls]).max() < 1.0e-6  # the tank's stay put


@pytest.mark.physics
def test_a_piston_raises_the_level_by_the_volume_it_displaces():
    """The paddle moves 0.2 m into the water over 2 s, from rest to rest: the mean level over the free
    length is the water's section over that length, whatever the waves (mass conservation), so at
    each time it is 0.27 / (0.9 - d(t)) m. Measured from the top particle of each column (plus dx/2)
    at dx = 2 cm: within 0.2% at every time; held to 1%. No particle is lost through the moving wall,
    and the fluid's energy check counts the work the paddle does (the level's rise alone is 0.3 M g H,
    six times the check's slack)."""
    law = {"type": "move", "displacement": [0.2, 0.0], "duration": 2.0}
    model = build(parse_scene(piston_tank(law)), dx=DX)
    solver = Solver(model.config, model.particles)
    for t in (1.0, 2.0, 3.0):
        solver.advance(t)
        snap = solver.snapshot()
        fluid = snap["ptype"] == 0
        x, z = snap["pos"][fluid, 0], snap["pos"][fluid, 1]
        u = min(solver.time / 2.0, 1.0)
        d = 0.2 * (u - math.sin(2 * math.pi * u) / (2 * math.pi))
        face = 0.1 + d
        assert snap["pos"][snap["body"] == 0, 0].max() + DX / 2 == pytest.approx(face, abs=1.0e-6)
        columns = np.arange(face + 2 * DX, 1.0 - 2 * DX, DX)
        tops = [z[(x >= a) & (x < a + DX)].max() + DX / 2 for a in columns]
        assert np.mean(tops) == pytest.approx(WATER / (1.0 - face), rel=0.01)
        assert solver.excluded_particles == 0
        assert (x > face).all()


@pytest.mark.unit
@pytest.mark.parametrize("motion, field, allowed", [
    ({"type": "spin"}, "obstacles[0].motion.type", "sinusoid, move"),
    ({"type": "sinusoid", "amplitude": [0.02, 0.0]}, "obstacles[0].motion", "period"),
    ({"type": "sinusoid", "period": 1.0}, "obstacles[0].motion", "non-zero amplitude or angle_deg"),
    ({"type": "sinusoid", "period": 1.0, "angle_deg": 5.0, "axis": [1, 0, 0]}, "obstacles[0].motion.axis",
     "no axis in 2D"),
    ({"type": "move", "displacement": [-0.1, 0.0], "duration": 1.0}, "obstacles[0].motion",
     "keeps the box in the tank"),
    ({"type": "move", "displacement": [0.2, 0.0], "duration": 0.0}, "obstacles[0].motion.duration", "> 0"),
    ({"type": "move", "displacement": [0.2, 0.0], "duration": 1.0, "period": 2.0}, "obstacles[0].motion", "period"),
])
def test_a_bad_motion_is_refused_naming_its_field(motion, field, allowed):
    with pytest.raises(ConfigError) as err:
        parse_scene(piston_tank(motion))
    assert err.value.field.startswith(field) and allowed in str(err.value)


@pytest.mark.unit
@pytest.mark.parametrize("numerics, more, field", [
    ({}, {}, "obstacles[0].motion"),  # 0.4 m in 0.1 s: 8 m/s against c0 / 10 = 1.7 m/s
    ({"boundary": "mdbc"}, {}, "boundary"),
    ({}, {"refine": [{"name": "near", "lo": [0.3, 0.0], "hi": [0.6, 0.4], "ratio": 0.5}]}, "refine"),
])
def test_what_a_moving_body_cannot_run_with_is_refused_at_build(numerics, more, field):
    fast = numerics == {} and not more
    law = {"type": "move", "displacement": [0.4 if fast else 0.2, 0.0], "duration": 0.1 if fast else 2.0}
    with pytest.raises(ConfigError) as err:
        build(parse_scene(piston_tank(law, **more)), dx=DX, **numerics)
    assert err.value.field == field


@pytest.mark.unit
def test_a_scene_with_a_moving_body_is_not_reduced():
    from gpusph_ros.scenes import reduce
    from gpusph_ros.scenes.settings import Reduction

    scene = parse_scene(piston_tank({"type": "move", "displacement": [0.2, 0.0], "duration": 2.0}))
    with pytest.raises(ConfigError) as err:
        reduce.apply(scene, Reduction(crop=True), 1.0, DX, 1.3)
    assert err.value.field == "model" and "moving obstacle" in str(err.value)
