"""What a pressure sensor reports between outputs (measure.transducers): the mean over the steps
since the last output, each step weighted by its length, of its face's reading at each step,
clipped at 0 by default and through a first-order response where it has one.

A 2D dam break at dx = 1 cm whose surge runs up the far wall, read by two Measurements of the
same scene on one solver: one sampled after every step (each sample then spans one step: the
step's own reading), the other once over the whole window. The window's report must be the
dt-weighted mean of the step readings to float32 round-off; the clipped report the mean of the
clipped readings; the sensor with a response the exact step of tau dy/dt = x - y over each step;
and a step's reading as the step hook took it (the state it ends on) equal to the one the output
reads of the same state (``sampling: step``).
"""
import numpy as np
import pytest

from gpusph_ros.measure.suite import Measurements
from gpusph_ros.scenes.build import build_run
from gpusph_ros.scenes.schema import ConfigError, parse_scene
from gpusph_ros.scenes.settings import resolve

pytestmark = pytest.mark.physics

TAU = 0.01  # [s]
SENSOR = {"type": "pressure_sensor", "normal": [-1, 0], "diameter": 0.02}
SCENE = {
    "name": "surge_on_a_wall", "dim": 2, "tank": [0.4, 0.3], "depth": 0.15, "walls": "particles",
    "fluid": [{"name": "column", "lo": [0.0, 0.0], "hi": [0.1, 0.15]}],
    "probes": {"low": {**SENSOR, "position": [0.4, 0.02]},
               "high": {**SENSOR, "position": [0.4, 0.06], "clip": False},
               "high_clipped": {**SENSOR, "position": [0.4, 0.06]},
               "high_now": {**SENSOR, "position": [0.4, 0.06], "clip": False, "sampling": "step"},
               "high_slow": {**SENSOR, "position": [0.4, 0.06], "response": TAU},
               "high_smoothed": {**SENSOR, "position": [0.4, 0.06], "reading": "smoothed"}},
}


@pytest.fixture(scope="module")
def surge():
    scene = parse_scene(SCENE)
    built = build_run(scene, resolve(scene, dx=0.01, end_time=0.4))
    solver = built.solver()
    each, window = Measurements(solver, built), Measurements(solver, built)
    solver.advance(0.22)  # the surge reaches the wall at about 0.23 s
    each.sample()
    window.sample()
    t0, times, steps = solver.time, [], []
    while solver.time < 0.34:
        solver.step()
        times.append(solver.time)
        steps.append(each.sample()["sensors"])
    dt = np.diff([t0] + times)
    series = {name: np.array([s[name] for s in steps]) for name in steps[0]}
    return dt, series, window.sample()["sensors"]


def test_a_sensor_reports_the_mean_of_its_step_readings_over_the_output(surge):
    dt, series, report = surge
    for name in ("low", "high", "high_clipped", "high_slow", "high_smoothed"):
        expected = np.sum(dt * series[name]) / np.sum(dt)
        assert report[name] == pytest.approx(expected, rel=1e-5, abs=1e-3), name
    # the face's pressure moves over the window: a report of one step's reading would differ
    assert np.ptp(series["low"]) > 0.5 * np.mean(series["low"]) > 0.0


def test_the_step_hooks_reading_is_the_outputs_reading_of_the_same_state(surge):
    _, series, report = surge
    assert np.allclose(series["high_now"], series["high"], rtol=1e-5, atol=1e-2)
    assert report["high_now"] == pytest.approx(series["high"][-1], rel=1e-5, abs=1e-2)


def test_a_sensor_reads_gauge_pressure_clipped_at_zero_unless_told(surge):
    dt, series, _ = surge
    raw = series["high"]
    assert (raw < 0.0).any(), "the window holds no tension: it tests no clip"
    assert np.allclose(series["high_clipped"], np.maximum(raw, 0.0), rtol=1e-5, atol=1e-2)
    assert (series["high_smoothed"] >= 0.0).all()


def test_a_sensors_response_is_the_exact_step_of_a_first_order_lag(surge):
    dt, series, _ = surge
    x, y = series["high_clipped"], series["high_slow"]
    step = y[:-1] + (1.0 - np.exp(-dt[1:] / TAU)) * (x[1:] - y[:-1])
    assert np.allclose(y[1:], step, rtol=1e-5, atol=1e-2)
    assert np.std(np.diff(y)) < 0.5 * np.std(np.diff(x))  # it does smooth


@pytest.mark.parametrize("probe, field", [({**SENSOR, "position": [0.4, 0.1], "sampling": "instant"}, "sampling"),
                                          ({**SENSOR, "position": [0.4, 0.1], "clip": "yes"}, "clip"),
                                          ({**SENSOR, "position": [0.4, 0.1], "response": -0.1}, "response"),
                                          ({**SENSOR, "position": [0.4, 0.1], "response": 60}, "response"),
                                          ({"type": "gauge", "position": [0.2], "clip": True}, "clip"),
                                          ({"type": "gauge", "position": [0.2], "reading": "wall"}, "reading"),
                                          ({"type": "point", "position": [0.2, 0.1], "reading": "top"}, "reading")])
def test_a_bad_sensor_or_gauge_setting_is_refused_naming_the_field(probe, field):
    with pytest.raises(ConfigError, match=f"probes.s.{field}"):
        parse_scene({**SCENE, "probes": {"s": probe}})
