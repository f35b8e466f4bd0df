"""Scene to particles: free surfaces at their stated heights at any dx (thesis Section 4.3,
Fig. 41 and 46: a lattice that put the top layer elsewhere cost up to 20% of bore velocity),
mass = rho0 x volume, wet beds around footprints, walls as particles or planes per wall."""
import numpy as np
import pytest

from gpusph_ros.scenes.build import build, floor_rectangles
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.scenes.shapes import block_particles

pytestmark = pytest.mark.unit

RHO0 = 1000.0


def box_particles(model, box):
    p = model.particles
    fluid = p.ptype == 0
    inside = np.all((p.pos >= np.asarray(box.lo) - 1e-9) & (p.pos <= np.asarray(box.hi) + 1e-9), axis=1)
    return fluid & inside


@pytest.mark.parametrize("dx", [0.006, 0.0075, 0.01, 0.0125, 0.015, 0.03])
@pytest.mark.parametrize("name", ["dambreak2_010", "dambreak2_015"])
def test_dambreak2_surfaces_sit_at_their_heights(name, dx):
    scene = load_scene(name)
    # the full flume at 6 mm is 3.5 million particles: a 0.3 m wide slice of it is the same fill
    scene.tank = (scene.tank[0], 0.3, scene.tank[2])
    for box in scene.fluid:
        box.hi = (box.hi[0], 0.3, box.hi[2])
    scene.probes = []
    model = build(scene, dx=dx)
    volume = 0.0
    for box in scene.fluid:
        sel = box_particles(model, box)
        top = model.particles.pos[sel, 2].max()
        assert 0.0 < box.hi[2] - top <= 0.5 * dx + 1e-12, (box.name, top)
        box_volume = np.prod(np.subtract(box.hi, box.lo))
        assert model.particles.mass[sel].sum() == pytest.approx(RHO0 * box_volume, rel=1e-9)
        volume += box_volume
    fluid = model.particles.ptype == 0
    assert model.particles.mass[fluid].sum() == pytest.approx(RHO0 * volume, rel=0.01)


def test_dambreak2_walls_are_planes_and_the_bed_particles():
    model = build(load_scene("dambreak2_010"), dx=0.05)
    normals = sorted(tuple(p.normal) for p in model.config.planes)
    assert normals == sorted([(1.0, 0, 0), (-1.0, 0, 0), (0, 1.0, 0), (0, -1.0, 0)])
    wall = model.particles.pos[model.particles.ptype == 1]
    assert (wall[:, 2] < 0.0).all()  # only the bed
    assert (wall[:, 0] > 0.0).all() and (wall[:, 0] < 16.6).all()
    assert (wall[:, 1] > 0).all() and (wall[:, 1] < 1.6).all()


@pytest.mark.parametrize("name, column_height", [("dambreak1_thesis", 0.4), ("dambreak1_lab", 0.3)])
@pytest.mark.parametrize("dx", [0.01, 0.015, 0.02, 0.03])
def test_dambreak1_column_wet_bed_and_obstruction(name, column_height, dx):
    scene = load_scene(name)
    model = build(scene, dx=dx)
    p = model.particles
    fluid = p.ptype == 0
    column = fluid & (p.pos[:, 0] < 0.4)
    assert 0.0 < column_height - p.pos[column, 2].max() <= 0.5 * dx + 1e-12
    bed = fluid & (p.pos[:, 0] > 0.4)
    if dx > 0.01:  # a bed thinner than one spacing is one layer where any first layer lies, dx/2 up
        assert np.allclose(p.pos[bed, 2], 0.5 * dx)
    else:
        assert 0.0 < 0.01 - p.pos[bed, 2].max() <= 0.5 * dx + 1e-12
    obstacle = scene.obstacles[0]
    in_obstacle = np.all((p.pos[:, :2] > obstacle.lo[:2]) & (p.pos[:, :2] < obstacle.hi[:2]), axis=1)
    assert not (fluid & in_obstacle).any()
    above_floor = p.pos[:, 2] > 0.0
    assert (p.body[in_obstacle & above_floor & (p.ptype == 1)] == model.bodies["obstruction"]).all()
    wet_area = 1.2 * 0.67 - 0.12 * 0.12
    assert p.mass[fluid].sum() == pytest.approx(RHO0 * (0.4 * 0.67 * column_height + wet_area * 0.01), rel=1e-9)


def test_floor_rectangles_cover_the_floor_outside_the_footprints_once():
    footprints = [((0.0, 0.0), (0.4, 0.67)), ((0.9, 0.24), (1.02, 0.36))]
    rects = floor_rectangles((1.6, 0.67), footprints, 3)
    area = sum((hi[0] - lo[0]) * (hi[1] - lo[1]) for lo, hi in rects)
    assert area == pytest.approx(1.2 * 0.67 - 0.12 * 0.12, rel=1e-12)
    rng = np.random.default_rng(1)
    for x, y in rng.uniform((0, 0), (1.6, 0.67), size=(2000, 2)):
        inside = sum(lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1] for lo, hi in rects)
        covered = any(lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1] for lo, hi in footprints)
        assert inside == (0 if covered else 1)
    assert floor_rectangles((2.0,), [((0.5,), (1.0,))], 2) == [((0.0,), (0.5,)), ((1.0,), (2.0,))]


@pytest.mark.parametrize("dx", [0.015, 0.02, 0.03])
def test_an_obstacle_of_any_size_has_its_outer_layer_within_dx_2_of_every_face(dx):
    # 0.13 x 0.11 x 0.25 m is no whole number of dx at any of these spacings (a dx lattice from the
    # block's corner left one face up to dx inside or outside the box); the shell is three layers
    # thick (a dynamic wall's kernel support), its lid too, and weighs rho0 x the volume of its cells
    lo, hi, layers = (0.5, 0.2, 0.0), (0.63, 0.31, 0.25), 3
    pts, volume = block_particles(lo, hi, dx, 3, layers)
    assert (pts >= np.asarray(lo)).all() and (pts <= np.asarray(hi)).all()
    for ax in range(3):
        n = int(np.ceil((hi[ax] - lo[ax]) / dx - 1e-9))
        coords = np.unique(np.round(pts[:, ax], 9))
        assert len(coords) == n
        assert 0.0 < coords[0] - lo[ax] <= 0.5 * dx + 1e-12 and 0.0 < hi[ax] - coords[-1] <= 0.5 * dx + 1e-12
    counts = [int(np.ceil((hi[ax] - lo[ax]) / dx - 1e-9)) for ax in range(3)]
    hollow = max(0, counts[0] - 2 * layers) * max(0, counts[1] - 2 * layers) * (counts[2] - layers)
    assert len(pts) == np.prod(counts) - hollow
    assert volume * np.prod(counts) == pytest.approx(np.prod(np.subtract(hi, lo)), rel=1e-12)
