"""A body moved by a series of displacements and angles (bodies.series_table, scenes/schema.py
_series and read_series): the spline, the body on it, the file, and what is refused."""
import math

import numpy as np
import pytest
import yaml
from test_bodies import DX, piston_tank, rotated

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene, parse_scene
from gpusph_ros.sph import Solver, bodies
from gpusph_ros.sph.config import ConfigError

START, SPAN, SHIFT, TURN = 0.2, 1.0, 0.1, math.radians(-4.0)  # [s], [s], [m], [rad]
TIMES = START + SPAN * np.linspace(0.0, 1.0, 9) ** 1.3  # unevenly spaced


def smoothstep(u):
    """3 u^2 - 2 u^3 and its first two derivatives in u: a cubic at rest at both ends, which a
    clamped spline through any of its samples reproduces exactly."""
    u = np.clip(u, 0.0, 1.0)
    return 3 * u ** 2 - 2 * u ** 3, 6 * u * (1 - u), 6 - 12 * u


@pytest.mark.unit
def test_a_clamped_spline_reproduces_a_cubic_at_rest_at_its_ends_and_is_c2_at_its_knots():
    coef = bodies.clamped_spline(TIMES, smoothstep((TIMES - START) / SPAN)[0])
    h = np.diff(TIMES)
    for k, t0 in enumerate(TIMES[:-1]):
        tau = np.linspace(0.0, h[k], 7)
        value = coef[k, 0] + tau * (coef[k, 1] + tau * (coef[k, 2] + tau * coef[k, 3]))
        assert value == pytest.approx(smoothstep((t0 + tau - START) / SPAN)[0], abs=1.0e-12)
    # value, slope and curvature at the end of each interval are the next one's at its start
    end = np.column_stack([coef[:, 0] + h * (coef[:, 1] + h * (coef[:, 2] + h * coef[:, 3])),
                           coef[:, 1] + h * (2 * coef[:, 2] + 3 * h * coef[:, 3]), 2 * coef[:, 2] + 6 * h * coef[:, 3]])
    start = np.column_stack([coef[:, 0], coef[:, 1], 2 * coef[:, 2]])
    assert end[:-1] == pytest.approx(start[1:], abs=1.0e-9)
    assert coef[0, 1] == 0.0 and end[-1, 1] == pytest.approx(0.0, abs=1.0e-12)


def series_law(times=TIMES) -> dict:
    s = smoothstep((np.asarray(times) - START) / SPAN)[0]
    return {"type": "series", "time": [float(t) for t in times], "x": [float(v) for v in SHIFT * s],
            "angle_deg": [float(v) for v in math.degrees(TURN) * s], "centre": [0.07, 0.0]}


@pytest.mark.physics
def test_a_paddle_on_a_series_moves_as_the_law_sampled_and_rests_outside_it():
    """The paddle of a 2D piston tank given nine uneven samples of a slide of 0.1 m and a turn of
    -4 degrees about its foot, both 3 u^2 - 2 u^3 of u = (t - 0.2) / 1 s: between the samples its
    particles stand and move as the law itself does (the clamped spline is exact for it), within
    float32's round-off (1e-6 m, 1e-5 m/s); before 0.2 s and after 1.2 s they stand still."""
    model = build(parse_scene(piston_tank(series_law())), dx=DX)
    solver = Solver(model.config, model.particles)
    paddle = model.particles.body == 0
    r0 = model.particles.pos[paddle, :2] - [0.07, 0.0]
    for t in (0.1, 0.37, 0.71, 1.05, 1.4):
        solver.advance(t)
        t = solver.time
        f, df, _ = smoothstep((t - START) / SPAN)
        df = df / SPAN if START < t < START + SPAN else 0.0
        arm = rotated(r0, TURN * f)
        snap = solver.snapshot()
        assert np.abs(snap["pos"][paddle, :2] - (arm + [0.07 + SHIFT * f, 0.0])).max() < 1.0e-6
        v_exact = np.column_stack([-arm[:, 1], arm[:, 0]]) * TURN * df + [SHIFT * df, 0.0]
        assert np.abs(snap["vel"][paddle, :2] - v_exact).max() < 1.0e-5
    assert solver.excluded_particles == 0


@pytest.mark.unit
def test_a_series_file_beside_the_scene_file_is_read_into_the_scene_and_its_text(tmp_path):
    """A CSV of the columns (a header, # comments) beside a scene file gives the motion the same
    series as the columns written in the scene, and the scene's text (what a recording keeps)
    carries them."""
    law = series_law()
    rows = zip(law["time"], law["x"], law["angle_deg"])
    (tmp_path / "paddle.csv").write_text("# slide and turn\ntime, x, angle_deg\n"
                                         + "".join(f"{t!r},{x!r},{a!r}\n" for t, x, a in rows))
    scene = piston_tank({"type": "series", "file": "paddle.csv", "centre": [0.07, 0.0]})
    (tmp_path / "tank.yaml").write_text(yaml.safe_dump(scene))
    loaded = load_scene(tmp_path / "tank.yaml")
    inline = parse_scene(piston_tank(law))
    assert loaded.obstacles[0].motion == inline.obstacles[0].motion
    assert parse_scene(yaml.safe_load(loaded.text)).obstacles[0].motion == inline.obstacles[0].motion


def bad_file(tmp_path, text: str):
    (tmp_path / "bad.csv").write_text(text)
    return {"type": "series", "file": str(tmp_path / "bad.csv")}


@pytest.mark.unit
@pytest.mark.parametrize("change, field, allowed", [
    (lambda law, p: {**law, "time": law["time"][::-1]}, "obstacles[0].motion.time[1]", "after the one before"),
    (lambda law, p: {**law, "x": law["x"][:-1]}, "obstacles[0].motion.x", "a list of 9 numbers"),
    (lambda law, p: {**law, "x": [0.01] + law["x"][1:]}, "obstacles[0].motion.x[0]", "starts where the scene"),
    (lambda law, p: {**law, "z": law["x"]}, "obstacles[0].motion.z", "no z in 2D"),
    (lambda law, p: {"type": "series", "time": law["time"]}, "obstacles[0].motion", "at least one of x"),
    (lambda law, p: {"type": "series", "x": law["x"]}, "obstacles[0].motion.time", "a list of 2 to"),
    (lambda law, p: {**law, "x": [-v for v in law["x"]]}, "obstacles[0].motion", "keeps the box in the tank"),
    (lambda law, p: {"type": "series", "file": "paddle.csv"}, "obstacles[0].motion.file", "read from a scene file"),
    (lambda law, p: bad_file(p, "time,x,speed\n0,0,0\n"), "obstacles[0].motion.file", "a header naming time"),
    (lambda law, p: bad_file(p, "time,x\n0,0\n1,0.1,3\n"), "obstacles[0].motion.file", "line 3 of its data"),
    (lambda law, p: bad_file(p, ""), "obstacles[0].motion.file", "a CSV file"),
    (lambda law, p: {"type": "series", "file": str(p / "none.csv")}, "obstacles[0].motion.file", "a CSV file beside"),
])
def test_a_bad_series_is_refused_naming_its_field(tmp_path, change, field, allowed):
    """Each refusal names the field and what it allows; a file is read only from a scene file."""
    motion = change(series_law(), tmp_path)
    with pytest.raises(ConfigError) as err:
        if "file" in motion and motion["file"] != "paddle.csv":
            (tmp_path / "tank.yaml").write_text(yaml.safe_dump(piston_tank(motion)))
            load_scene(tmp_path / "tank.yaml")
        else:
            parse_scene(piston_tank(motion))
    assert err.value.field == field and allowed in str(err.value)


@pytest.mark.unit
def test_a_series_faster_than_a_tenth_of_the_sound_speed_is_refused_at_build():
    """0.4 m in 0.1 s (its spline's peak 6 m/s, found between the samples) against c0 / 10 = 1.7 m/s."""
    law = {"type": "series", "time": [0.0, 0.05, 0.1], "x": [0.0, 0.2, 0.4]}
    with pytest.raises(ConfigError) as err:
        build(parse_scene(piston_tank(law)), dx=DX)
    assert err.value.field == "obstacles[0].motion" and "c0 / 10" in str(err.value)


@pytest.mark.unit
def test_a_refused_series_file_is_not_quoted(tmp_path):
    """A scene may name any file the node can read: a refusal names the file, never its words."""
    (tmp_path / "secret.csv").write_text("hunter2:x:0:0,passphrase\n")
    scene = piston_tank({"type": "series", "file": "secret.csv"})
    (tmp_path / "tank.yaml").write_text(yaml.safe_dump(scene))
    with pytest.raises(ConfigError) as err:
        load_scene(tmp_path / "tank.yaml")
    assert "secret.csv" in str(err.value) and "hunter2" not in str(err.value) and "passphrase" not in str(err.value)
