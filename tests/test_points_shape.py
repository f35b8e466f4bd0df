"""A body given as its particles (``shape: points``: scenes/shapes.py, schema._points, build's
spacing check): the same run as the box it copies, its spacing, its file, and what is refused."""
import numpy as np
import pytest
import yaml
from test_bodies import DX, piston_tank

from gpusph_ros.scenes import shapes
from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene, parse_scene
from gpusph_ros.sph import Solver
from gpusph_ros.sph.config import ConfigError

SWING = {"type": "sinusoid", "amplitude": [0.02, 0.0], "angle_deg": -4.0, "period": 1.0, "phase_deg": -90.0,
         "centre": [0.07, 0.0]}


def paddle_points(dx: float = DX) -> list:
    """The particles a moving box paddle of piston_tank has (shapes.block_particles, with a bottom)."""
    pts, _ = shapes.block_particles((0.04, 0.0, 0.0), (0.1, 0.6, 0.0), dx, 2, 3, bottom=True)
    return [[float(x), float(y)] for x, y in pts[:, :2]]


def points_tank(points, motion=SWING, **more) -> dict:
    scene = piston_tank(motion)
    scene["obstacles"][0].update({"shape": "points", "points": points, **more})
    return scene


@pytest.mark.unit
def test_a_points_spacing_is_the_median_distance_to_the_nearest_point():
    """A lattice a spacing apart gives that spacing (a shell of a 3D box, and a 2D one); scattered
    points give what comparing every pair gives."""
    shell, _ = shapes.block_particles((0.0, 0.0, 0.0), (0.2, 0.2, 0.1), 0.01, 3, 3, bottom=True)
    assert shapes.median_spacing(shell, 3) == pytest.approx(0.01, rel=1e-9)
    assert shapes.median_spacing(np.array([[x, y, 0.0] for x, y in paddle_points()]), 2) == pytest.approx(DX)
    scattered = np.random.default_rng(7).random((1500, 3)) * [1.0, 0.1, 3.0]
    gaps = np.linalg.norm(scattered[:, None] - scattered[None], axis=2)
    np.fill_diagonal(gaps, np.inf)
    assert shapes.median_spacing(scattered, 3) == pytest.approx(np.median(gaps.min(axis=1)), rel=1e-12)
    assert shapes.median_spacing(np.zeros((1, 3)), 3) == np.inf


@pytest.mark.physics
def test_a_paddle_given_as_the_particles_of_its_box_runs_as_the_box_does():
    """The piston tank's swinging paddle given as the very particles its box has: the same model and,
    to 0.3 s, the same run, bit for bit."""
    runs = []
    for scene in (piston_tank(SWING), points_tank(paddle_points())):
        model = build(parse_scene(scene), dx=DX)
        solver = Solver(model.config, model.particles)
        solver.advance(0.3)
        runs.append((model.particles.pos, solver.snapshot()))
    assert np.array_equal(runs[0][0], runs[1][0])
    for name in ("pos", "vel", "rho"):
        assert np.array_equal(runs[0][1][name], runs[1][1][name])


@pytest.mark.unit
def test_a_points_file_beside_the_scene_file_is_read_into_the_scene(tmp_path):
    pts = paddle_points()
    (tmp_path / "paddle.csv").write_text("# the paddle's particles\nx,y\n" + "".join(f"{x!r},{y!r}\n" for x, y in pts))
    scene = piston_tank(SWING)
    scene["obstacles"][0].update({"shape": "points", "file": "paddle.csv"})
    (tmp_path / "tank.yaml").write_text(yaml.safe_dump(scene))
    loaded = load_scene(tmp_path / "tank.yaml")
    assert loaded.obstacles[0].points == parse_scene(points_tank(pts)).obstacles[0].points
    assert parse_scene(yaml.safe_load(loaded.text)).obstacles[0].points == loaded.obstacles[0].points


@pytest.mark.unit
@pytest.mark.parametrize("change, field, allowed", [
    (lambda s: s["obstacles"][0]["points"].append([0.2, 0.1]), "obstacles[0].points[", "inside the body's box"),
    (lambda s: s["obstacles"][0].pop("points"), "obstacles[0].points", "for shape: points only"),
    (lambda s: s["obstacles"][0].update(shape="box"), "obstacles[0].points", "for shape: points only"),
    (lambda s: s["obstacles"][0].update(points=[[0.05, 0.1, 0.2]]), "obstacles[0].points[0]", "a list of 2"),
    (lambda s: s["obstacles"][0].update(file="paddle.csv"), "obstacles[0].file", "read from a scene file"),
    (lambda s: (s["obstacles"][0].pop("motion"), s["obstacles"][0].update(floating={"density": 500.0})),
     "obstacles[0].floating.mass", "its solid is not known"),
])
def test_a_bad_points_body_is_refused_naming_its_field(change, field, allowed):
    scene = points_tank(paddle_points())
    change(scene)
    with pytest.raises(ConfigError) as err:
        parse_scene(scene)
    assert err.value.field.startswith(field) and allowed in str(err.value)


@pytest.mark.unit
def test_points_a_spacing_other_than_the_runs_are_refused_at_build():
    """Each particle stands for dx^dim: the paddle's particles at 2 cm in a run at 1 cm (or 4 cm)
    would carry four times (a quarter) the mass they are given."""
    for dx in (0.01, 0.04):
        with pytest.raises(ConfigError) as err:
            build(parse_scene(points_tank(paddle_points())), dx=dx)
        assert err.value.field == "obstacles[0].points" and "median spacing is 0.02 m" in str(err.value)


@pytest.mark.unit
def test_a_points_file_without_a_coordinate_is_refused(tmp_path):
    (tmp_path / "paddle.csv").write_text("x\n0.05\n0.07\n")
    scene = piston_tank(SWING)
    scene["obstacles"][0].update({"shape": "points", "file": "paddle.csv"})
    (tmp_path / "tank.yaml").write_text(yaml.safe_dump(scene))
    with pytest.raises(ConfigError) as err:
        load_scene(tmp_path / "tank.yaml")
    assert err.value.field == "obstacles[0].file" and "columns x, y" in str(err.value)
