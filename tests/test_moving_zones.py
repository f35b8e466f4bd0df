"""Bodies that move in a scene with refinement zones (issue 45, build item 2): a moving body stays in
its zone or clear of it (refine.check_paths at build, health's zone_edge while it runs), is lined at
the zone's spacing wherever it goes there, and steps on its law at every stage of multirate."""
import math

import numpy as np
import pytest

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import parse_scene
from gpusph_ros.sph import HealthError, Solver
from gpusph_ros.sph.config import ConfigError
from gpusph_ros.sph.levels import edge_margin
from gpusph_ros.sph.state import BOUNDARY

DX = 0.02
ZONE = {"name": "near", "lo": [0.3, 0.12], "hi": [0.7, 0.6], "ratio": 0.5}  # to the tank's top


def tank(obstacles: list, zones=(ZONE,)) -> dict:
    """A 2D tank 1 m long of 0.3 m of water, with ``obstacles`` and a zone about its middle."""
    return {"name": "zoned", "dim": 2, "tank": [1.0, 0.6], "walls": "particles",
            "fluid": [{"name": "water", "lo": [0, 0], "hi": [1.0, 0.3]}],
            "obstacles": obstacles, "refine": list(zones)}


def fine_particles(model, body: int) -> np.ndarray:
    """The positions of body ``body``'s particles at half the scene's spacing, sorted."""
    p = model.particles
    mine = (p.body == body) & (p.ptype == BOUNDARY) & np.isclose(p.spacing, 0.5 * DX)
    return p.pos[mine][np.lexsort(p.pos[mine].T[::-1])]


def body_particles(model, body: int) -> np.ndarray:
    p = model.particles
    mine = (p.body == body) & (p.ptype == BOUNDARY)
    return p.pos[mine][np.lexsort(p.pos[mine].T[::-1])]


@pytest.mark.unit
def test_the_margin_is_the_zones_band_and_its_parents_kernel_support():
    # h = 1.3 x 1 cm: band 2h + dx/2 = 3.1 cm, the parent level's 2h = 5.2 cm
    assert edge_margin(0.01, 1.3) == pytest.approx(0.026 + 0.005 + 0.052)


@pytest.mark.unit
@pytest.mark.parametrize("lo, hi, motion, ok", [
    # a box 0.1 m inside the zone's sides and 0.14 m above its floor; the margin at 1 cm is 0.083 m
    ((0.4, 0.26), (0.6, 0.36), {"type": "sinusoid", "amplitude": [0.01, 0.0], "period": 1.0}, True),
    ((0.4, 0.26), (0.6, 0.36), {"type": "sinusoid", "amplitude": [0.03, 0.0], "period": 1.0}, False),
    ((0.4, 0.26), (0.6, 0.36), {"type": "sinusoid", "amplitude": [0.0, 0.1], "period": 2.0}, False),
    ((0.4, 0.26), (0.6, 0.36), {"type": "sinusoid", "angle_deg": 5.0, "period": 1.0}, True),  # corners: 1 cm
    ((0.4, 0.26), (0.6, 0.36), {"type": "sinusoid", "angle_deg": 30.0, "period": 1.0}, False),  # 5.9 cm
    ((0.4, 0.26), (0.6, 0.36), {"type": "move", "displacement": [-0.3, 0.0], "duration": 3.0}, False),
    ((0.04, 0.0), (0.1, 0.5), {"type": "sinusoid", "amplitude": [0.02, 0.0], "period": 1.0}, True),  # clear
    ((0.04, 0.0), (0.1, 0.5), {"type": "move", "displacement": [0.15, 0.0], "duration": 3.0}, False),
])
def test_a_path_that_crosses_a_zones_face_is_refused_naming_the_zone(lo, hi, motion, ok):
    box = {"name": "box", "lo": list(lo), "hi": list(hi), "displaces_fluid": True, "motion": motion}
    scene = parse_scene(tank([box]))
    if ok:
        build(scene, dx=DX)
        return
    with pytest.raises(ConfigError) as err:
        build(scene, dx=DX)
    assert err.value.field == "refine[0]" and "'box'" in str(err.value) and "edge_margin" in str(err.value)


@pytest.mark.unit
@pytest.mark.parametrize("motion", [
    {"type": "sinusoid", "amplitude": [0.01, 0.0], "period": 1.0},
    {"type": "driven", "max_speed": 0.1, "max_acceleration": 1.0},
])
def test_a_body_in_a_zone_is_lined_at_its_spacing_all_over_as_a_uniform_build_lines_it(motion):
    """Its daughters, its bottom face's too, are the uniform build's particles at the zone's spacing,
    as many layers deep; a round obstacle before it in the list does not take its faces (each
    obstacle's own)."""
    disc = {"name": "disc", "shape": "cylinder", "lo": [0.8, 0.0], "hi": [0.9, 0.1], "displaces_fluid": True}
    box = {"name": "box", "lo": [0.4, 0.26], "hi": [0.6, 0.36], "displaces_fluid": True, "motion": motion}
    zoned = build(parse_scene(tank([disc, box])), dx=DX)
    uniform = build(parse_scene(tank([disc, box], zones=())), dx=0.5 * DX)
    assert np.abs(fine_particles(zoned, 1) - body_particles(uniform, 1)).max() < 1e-9


@pytest.mark.physics
def test_a_body_swinging_in_a_zone_stands_on_its_law_at_every_level_under_multirate():
    """A box swinging 5 degrees about its centre and sliding 1 cm at a 1 s period in a zone at 1 cm
    0.15 m about it (multirate: the zone steps twice for the scene's once): its particles of both
    levels, read at the outputs, stand at c + d + R(theta)(r0 - c), within float32's round-off."""
    law = {"type": "sinusoid", "amplitude": [0.01, 0.0], "angle_deg": 5.0, "period": 1.0, "phase_deg": -90.0}
    box = {"name": "box", "lo": [0.4, 0.26], "hi": [0.6, 0.36], "displaces_fluid": True, "motion": law}
    model = build(parse_scene(tank([box], zones=[{**ZONE, "lo": [0.25, 0.1], "hi": [0.75, 0.6]}])), dx=DX)
    assert model.config.multirate
    solver = Solver(model.config, model.particles)
    mine = model.particles.body == 0
    assert len(np.unique(model.particles.spacing[mine])) == 2
    r0 = model.particles.pos[mine, :2] - [0.5, 0.31]
    omega, phase = 2 * math.pi, -math.pi / 2
    for t in (0.11, 0.32):
        solver.advance(t)
        f = math.sin(omega * solver.time + phase) - math.sin(phase)
        c, s = math.cos(math.radians(5.0) * f), math.sin(math.radians(5.0) * f)
        exact = np.column_stack([c * r0[:, 0] - s * r0[:, 1], s * r0[:, 0] + c * r0[:, 1]]) + [0.5 + 0.01 * f, 0.31]
        assert np.abs(solver.snapshot()["pos"][mine, :2] - exact).max() < 1.0e-6
    assert solver.excluded_particles == 0


@pytest.mark.physics
def test_a_floating_box_in_a_zone_floats_at_archimedes_draft():
    """The 2D box of tests/test_bodies.py (0.2 x 0.1 m, 500 kg/m^3, draft 0.05 m) let go 1 cm above
    its draft at dx = 2 cm, in a zone at 1 cm 0.1 m about it (multirate): its draft over its whole
    heave periods, against the level the gauges read at 2 cm far from it, is Archimedes' within 2%.
    Measured -1.5% (multirate or not), where the uniform runs read -2.6% at 2 cm and -0.9% at 1 cm."""
    from test_bodies import heave

    box = {"name": "box", "lo": [0.4, 0.26], "hi": [0.6, 0.36], "displaces_fluid": True,
           "floating": {"density": 500.0, "rotate": False}}
    model = build(parse_scene(tank([box])), dx=DX)
    solver = Solver(model.config, model.particles)
    heights, levels = heave(solver, DX)
    assert (levels - (heights - 0.05)).mean() == pytest.approx(0.05, rel=0.02)
    assert solver.excluded_particles == 0


@pytest.mark.physics
def test_a_floating_body_that_sinks_to_its_zones_face_stops_the_run_naming_the_check():
    """A box of twice the water's density, let go in a zone whose floor is 0.14 m under it: it
    sinks, and the step that brings it within the margin (0.083 m at 1 cm) of the face stops the
    run on zone_edge, well before the body meets the face."""
    box = {"name": "box", "lo": [0.4, 0.26], "hi": [0.6, 0.36], "displaces_fluid": True,
           "floating": {"density": 2000.0, "rotate": False}}
    model = build(parse_scene(tank([box])), dx=DX)
    solver = Solver(model.config, model.particles)
    with pytest.raises(HealthError) as err:
        solver.advance(1.0)
    assert err.value.check == "zone_edge" and "refinement zone" in str(err.value)
    bottom = solver.snapshot()["pos"][model.particles.body == 0, 1].min()
    margin = edge_margin(0.01, model.config.hdx)
    assert 0.12 + margin - 0.001 < bottom < 0.12 + margin  # a step moves it far less than 1 mm
