"""Obstacle shapes (scenes/shapes.py): the particles that line a round body, its solid's volume,
centroid and inertia against the closed forms, the fields a shape is refused for, and how a round
body is drawn. Round bodies in water: tests/test_bodies.py."""
import math

import numpy as np
import pytest

from gpusph_ros.scenes import shapes
from gpusph_ros.scenes.schema import parse_scene
from gpusph_ros.sph.config import ConfigError

WEDGE_H = 0.2 * math.tan(math.radians(30))  # a 30-degree wedge 0.4 m wide, as tall as its sides


def obstacle(shape: str, lo, hi, dim: int, **more):
    scene = {"name": "shape", "dim": dim, "tank": [1.0] * dim,
             "fluid": [{"name": "water", "lo": [0.0] * dim, "hi": [1.0] * (dim - 1) + [0.2]}],
             "obstacles": [{"name": "body", "lo": lo, "hi": hi, "shape": shape, "floating": {"density": 500.0},
                            **more}]}
    return parse_scene(scene).obstacles[0]


@pytest.mark.unit
@pytest.mark.parametrize("shape, lo, hi, dim, more, volume, moments", [
    # a 2D disc of radius 0.1: pi R^2; R^2 / 4 about x and y, R^2 / 2 about z (per unit mass)
    ("cylinder", [0.4, 0.4], [0.6, 0.6], 2, {}, math.pi * 0.01, (0.0025, 0.0025, 0.005)),
    # a cylinder of radius 0.1 and length 0.4 along y: R^2 / 2 about its axis, R^2 / 4 + L^2 / 12 across
    ("cylinder", [0.4, 0.3, 0.4], [0.6, 0.7, 0.6], 3, {"axis": "y"}, math.pi * 0.01 * 0.4,
     (0.0025 + 0.16 / 12, 0.005, 0.0025 + 0.16 / 12)),
    # a sphere of radius 0.1: 4/3 pi R^3, 2 R^2 / 5
    ("sphere", [0.4, 0.4, 0.4], [0.6, 0.6, 0.6], 3, {}, 4 / 3 * math.pi * 0.001, (0.004, 0.004, 0.004)),
    # a 30-degree wedge 0.4 wide whose sides reach its box's top: a triangle of height h = 0.2 tan 30,
    # area 0.2 h, <x^2> = (0.4)^2 / 24, <y^2> = h^2 / 18
    ("wedge", [0.3, 0.5], [0.7, 0.5 + WEDGE_H], 2, {"deadrise_deg": 30.0}, 0.2 * WEDGE_H,
     (WEDGE_H ** 2 / 18, 0.16 / 24, 0.16 / 24 + WEDGE_H ** 2 / 18)),
])
def test_a_shapes_solid_has_its_closed_form_volume_and_inertia(shape, lo, hi, dim, more, volume, moments):
    solid = shapes.solid(obstacle(shape, lo, hi, dim, **more), dim)
    assert solid.volume == pytest.approx(volume, rel=1e-12)
    assert np.diag(solid.inertia) == pytest.approx(moments, rel=1e-12)
    centre = np.zeros(3)
    centre[:dim] = 0.5 * (np.asarray(lo) + np.asarray(hi))
    if shape == "wedge":  # the triangle's centroid two thirds of the way up from its apex
        centre[1] = lo[1] + 2 / 3 * (hi[1] - lo[1])
    assert solid.centroid == pytest.approx(tuple(centre), abs=1e-12)


@pytest.mark.unit
@pytest.mark.parametrize("shape, lo, hi, dim, more", [
    ("cylinder", [0.4, 0.4], [0.6, 0.6], 2, {}),
    ("cylinder", [0.4, 0.3, 0.4], [0.6, 0.7, 0.6], 3, {"axis": "y"}),
    ("sphere", [0.4, 0.4, 0.4], [0.6, 0.6, 0.6], 3, {}),
])
def test_a_round_body_is_lined_a_spacing_apart_under_its_surface(shape, lo, hi, dim, more):
    """Its particles lie inside it, the outer ones half a spacing under its surface, none closer to
    another than 0.6 dx (a lattice's neighbours are dx apart; rings and Fibonacci shells come close
    to that), and a wall's layers deep: each stands for dx^dim, so the outer shell's particles cover
    its surface at one per dx^(dim-1) within 10%. A cylinder's ends are discs filled to its axis."""
    dx, layers = 0.01 if dim == 2 else 0.02, 3
    o = obstacle(shape, lo, hi, dim, **more)
    pts, volume = shapes.particles(o, dx, dim, layers)
    assert volume == pytest.approx(dx ** dim)
    centre = 0.5 * (np.asarray(o.lo) + np.asarray(o.hi))
    d = pts - centre
    axis = o.axis if shape == "cylinder" else None
    radial = np.linalg.norm(d if axis is None else np.delete(d, axis, axis=1), axis=1)
    assert radial.max() == pytest.approx(0.1 - 0.5 * dx, abs=1e-9)
    rim = radial > 0.1 - dx
    if shape == "cylinder" and dim == 3:
        rim &= np.abs(d[:, axis]) < 0.2 - layers * dx
        area = 2 * math.pi * (0.1 - dx / 2) * (0.4 - 2 * layers * dx)
    else:
        area = 2 * math.pi * (0.1 - dx / 2) if dim == 2 else 4 * math.pi * (0.1 - dx / 2) ** 2
    assert rim.sum() == pytest.approx(area / dx ** (dim - 1), rel=0.1)
    side = np.ones(len(pts), dtype=bool) if axis is None or dim == 2 else np.abs(d[:, axis]) < 0.2 - layers * dx
    rings = np.unique(np.round(radial[side] / dx - 0.5, 6))
    assert rings == pytest.approx([0.1 / dx - layers + k for k in range(layers)])  # R / dx - 1/2 - k
    gaps = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=2) + np.eye(len(pts))
    assert gaps.min() > 0.6 * dx


@pytest.mark.unit
@pytest.mark.parametrize("shape, lo, hi, dim, more, field, allowed", [
    ("cylinder", [0.4, 0.4], [0.6, 0.7], 2, {}, "obstacles[0].hi", "a box as wide along x, y"),
    ("sphere", [0.4, 0.4], [0.6, 0.6], 2, {}, "obstacles[0].shape", "box, wedge, cylinder or points in 2D"),
    ("cylinder", [0.4, 0.3, 0.4], [0.6, 0.7, 0.6], 3, {}, "obstacles[0].axis", "one of x, y, z"),
    ("cylinder", [0.4, 0.3, 0.4], [0.6, 0.7, 0.6], 3, {"axis": "w"}, "obstacles[0].axis", "one of x, y, z"),
    ("cylinder", [0.4, 0.3, 0.4], [0.6, 0.7, 0.6], 3, {"axis": "x"}, "obstacles[0].hi", "along y, z"),
    ("box", [0.4, 0.4], [0.6, 0.6], 2, {"axis": "x"}, "obstacles[0].axis", "cylinder in 3D only"),
    ("ball", [0.4, 0.4], [0.6, 0.6], 2, {}, "obstacles[0].shape", "box, wedge, cylinder, sphere"),
])
def test_a_bad_shape_is_refused_naming_its_field(shape, lo, hi, dim, more, field, allowed):
    with pytest.raises(ConfigError) as err:
        obstacle(shape, lo, hi, dim, **more)
    assert err.value.field == field and allowed in str(err.value)


@pytest.mark.unit
@pytest.mark.parametrize("dim, shape, lo, hi, more, axis", [
    (2, "cylinder", [0.4, 0.4], [0.6, 0.6], {}, (0.0, 1.0, 0.0)),  # the scene's z is published as y
    (3, "cylinder", [0.3, 0.4, 0.4], [0.7, 0.6, 0.6], {"axis": "x"}, (1.0, 0.0, 0.0)),
    (3, "sphere", [0.4, 0.4, 0.4], [0.6, 0.6, 0.6], {}, (0.0, 0.0, 1.0)),
])
def test_a_round_body_is_drawn_round_along_its_axis(dim, shape, lo, hi, more, axis):
    """~/geometry draws a cylinder as RViz's cylinder turned onto its axis (its 0.2 m diameter
    across it), a sphere as a sphere."""
    from visualization_msgs.msg import Marker

    from gpusph_ros.output import markers
    from gpusph_ros.sph.bodies import quaternion_matrix

    scene = parse_scene({"name": "shape", "dim": dim, "tank": [1.0] * dim,
                         "fluid": [{"name": "water", "lo": [0.0] * dim, "hi": [1.0] * (dim - 1) + [0.2]}],
                         "obstacles": [{"name": "body", "lo": lo, "hi": hi, "shape": shape,
                                        "floating": {"density": 500.0}, **more}]})
    m = next(m for m in markers.geometry(scene, 0.02, "world").markers if m.ns == "obstacles")
    assert m.type == (Marker.CYLINDER if shape == "cylinder" else Marker.SPHERE)
    q = m.pose.orientation
    assert np.abs(quaternion_matrix((q.x, q.y, q.z, q.w)) @ [0.0, 0.0, 1.0]) == pytest.approx(axis, abs=1e-12)
    assert (m.scale.x, m.scale.y) == pytest.approx((0.2, 0.2))


@pytest.mark.physics
def test_a_fixed_disc_leaves_the_water_beside_it_in_its_box():
    """A fixed disc of radius 5 cm standing on the floor of 0.2 m of water, dx = 1 cm: the water in
    its box's corners, outside the disc, stays (the build takes only what is within a quarter spacing
    of the disc), and the disc's box is not a solid the health check keeps the fluid out of, so the
    tank steps to 0.1 s with that water where it is."""
    from gpusph_ros.scenes.build import build
    from gpusph_ros.sph import Solver

    scene = parse_scene({"name": "disc", "dim": 2, "tank": [0.6, 0.4],
                         "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.6, 0.2]}],
                         "obstacles": [{"name": "disc", "shape": "cylinder", "lo": [0.25, 0.0], "hi": [0.35, 0.1],
                                        "displaces_fluid": True}]})
    model = build(scene, dx=0.01)
    assert model.config.solids == []
    solver = Solver(model.config, model.particles)
    solver.advance(0.1)
    snap = solver.snapshot()
    pos = snap["pos"][snap["ptype"] == 0]
    in_box = (np.abs(pos[:, 0] - 0.3) < 0.05) & (pos[:, 1] < 0.1)
    outside = np.hypot(pos[:, 0] - 0.3, pos[:, 1] - 0.05) > 0.05
    assert (in_box & outside).sum() > 10 and (in_box & ~outside).sum() == 0
    assert solver.excluded_particles == 0
