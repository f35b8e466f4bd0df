"""Measurements on a still 2D tank with an obstruction, against hydrostatics: the thesis's
pressure blocks (Section 3.2) give rho0 g d^2 / 2 per unit depth on each face and no net force,
the depth-averaged column (Section 3.3) the mean of a linear velocity profile, the surface gauge
the stated depth, also under spray, and nothing for spray over a dry floor. The state is the
scene's hydrostatic start; nothing is stepped."""
import numpy as np
import pytest

from gpusph_ros.measure.blocks import PressureBlockForce, face_blocks
from gpusph_ros.measure.columns import ColumnMeans
from gpusph_ros.measure.suite import Measurements
from gpusph_ros.measure.surface import elevation, floor_under
from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import Obstacle, parse_scene
from gpusph_ros.sph import Solver

pytestmark = pytest.mark.physics

DX, DEPTH, G = 0.01, 0.24, 9.81
TANK = {
    "dim": 2, "tank": [0.6, 0.3], "depth": DEPTH, "walls": "particles",
    "fluid": [{"name": "left", "lo": [0.0, 0.0], "hi": [0.3, DEPTH]},
              {"name": "right", "lo": [0.36, 0.0], "hi": [0.6, DEPTH]}],
    "obstacles": [{"name": "wall", "lo": [0.3, 0.0], "hi": [0.36, 0.3], "block_offsets": [0.0, 0.06]}],
    "probes": {"eta": {"type": "gauge", "position": [0.15]}, "col": {"type": "column", "position": [0.15]}},
}


@pytest.fixture(scope="module")
def still_tank():
    model = build(parse_scene(TANK), dx=DX, precision="float64", boundary="lennard_jones")
    fluid = model.particles.ptype == 0
    model.particles.vel[fluid, 0] = 0.5 + 2.0 * model.particles.pos[fluid, 1]  # u = 0.5 + 2 y
    return model, Solver(model.config, model.particles)


def test_pressure_blocks_give_the_hydrostatic_face_load(still_tank):
    model, solver = still_tank
    obstacle = model.scene.obstacles[0]
    forces = PressureBlockForce(solver, obstacle.lo, obstacle.hi, obstacle.block_offsets).sample()
    face = 1000.0 * G * DEPTH ** 2 / 2  # per unit depth
    for offset, (net, upstream, downstream) in forces.items():
        assert upstream == pytest.approx(face, rel=0.01), offset
        assert downstream == pytest.approx(face, rel=0.01), offset
        assert abs(net) < 1e-6 * face


def test_blocks_tile_a_3d_face_exactly():
    lo, hi, sign, area = face_blocks((0.9, 0.24, 0.0), (1.02, 0.36, 0.4), 0.015, 3, 0.06)
    assert area[sign > 0].sum() == pytest.approx(0.12 * 0.4) and area[sign < 0].sum() == pytest.approx(0.12 * 0.4)
    assert np.allclose(hi[sign > 0, 0], 0.84) and np.allclose(lo[sign > 0, 0], 0.84 - 4 * 0.015)
    assert np.allclose(lo[sign < 0, 0], 1.08)
    assert (hi[:, 1:] - lo[:, 1:] <= 3 * 0.015 + 1e-12).all()


def test_column_mean_of_a_linear_profile(still_tank):
    _, solver = still_tank
    out = ColumnMeans(solver, [(0.15, 0.0, 0.0)], [3 * DX]).sample()
    # layers are evenly spaced over the whole depth, so the mean height is DEPTH / 2
    assert out["vel"][0, 0] == pytest.approx(0.5 + 2.0 * DEPTH / 2, rel=1e-9)
    assert out["count"][0] == 6 * round(DEPTH / DX)  # 6 columns of particles within 3 dx
    assert ColumnMeans(solver, [(0.33, 0.0, 0.0)], [0.5 * DX]).sample()["count"][0] == 0  # inside the wall


def test_spray_over_the_gauge_is_not_the_water_at_it():
    # a blob 4 cm thick held 6 cm above the surface, as spray or an overturning jet over an air
    # pocket: going up from the floor the gauge stops where the water column ends (DualSPHysics'
    # GaugeSwl), not at the top of the blob
    scene = {**TANK, "tank": [0.6, 0.4],
             "fluid": TANK["fluid"] + [{"name": "spray", "lo": [0.12, 0.30], "hi": [0.18, 0.34]}]}
    model = build(parse_scene(scene), dx=DX, precision="float64", boundary="lennard_jones")
    sample = Measurements(Solver(model.config, model.particles), model).sample()
    assert sample["gauges"]["eta"] == pytest.approx(DEPTH, abs=0.25 * DX)


def test_surface_gauge_reads_the_stated_depth(still_tank):
    model, solver = still_tank
    sample = Measurements(solver, model).sample()
    assert sample["gauges"]["eta"] == pytest.approx(DEPTH, abs=0.25 * DX)
    assert sample["columns"]["col"]["vel"][0] == pytest.approx(0.74, rel=1e-9)
    assert sample["blocks"]["wall"][0.0][1] == pytest.approx(1000.0 * G * DEPTH ** 2 / 2, rel=0.01)


def test_spray_over_a_dry_floor_is_no_water_at_the_gauge():
    # a blob 4 cm thick 30 cm above the dry floor at the gauge (water only beyond the wall): the
    # level reads 0, as a dry gauge; a gauge that reads the top particle sees the blob's top
    scene = {**TANK, "tank": [0.6, 0.4],
             "fluid": [TANK["fluid"][1], {"name": "spray", "lo": [0.12, 0.30], "hi": [0.18, 0.34]}],
             "probes": {"eta": {"type": "gauge", "position": [0.15]},
                        "top": {"type": "gauge", "position": [0.15], "reading": "top"},
                        "beyond": {"type": "gauge", "position": [0.48]},
                        "beyond_top": {"type": "gauge", "position": [0.48], "reading": "top"}}}
    model = build(parse_scene(scene), dx=DX, precision="float64", boundary="lennard_jones")
    gauges = Measurements(Solver(model.config, model.particles), model).sample()["gauges"]
    assert gauges["eta"] == 0.0
    assert gauges["top"] == pytest.approx(0.34, abs=0.25 * DX)
    assert gauges["beyond"] == pytest.approx(DEPTH, abs=0.25 * DX)
    assert gauges["beyond_top"] == pytest.approx(DEPTH, abs=0.25 * DX)


def test_water_on_an_obstacles_top_is_read_from_the_top_not_the_tank_floor():
    # a line through a solid block 0.28 m tall reads water standing 4 cm deep on it (the block's
    # top is the floor under the gauge), where over the tank's floor it would be spray
    heights = np.arange(0.0, 0.4, DX / 4)
    weight = np.where((heights > 0.281) & (heights < 0.318), 1.0, 0.0)
    reach = 2 * 1.3 * DX
    assert elevation(heights, weight, floor=0.0, reach=reach) == 0.0
    assert elevation(heights, weight, floor=floor_under((0.15, 0.0, 0.0), [Obstacle("b", (0.1, 0.0, 0.0),
                                                                                        (0.2, 0.28, 0.0))], 2),
                     reach=reach) == pytest.approx(0.3175, abs=DX / 4)
    assert floor_under((0.25, 0.0, 0.0), [Obstacle("b", (0.1, 0.0, 0.0), (0.2, 0.28, 0.0))], 2) == 0.0
