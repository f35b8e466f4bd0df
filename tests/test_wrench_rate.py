"""Each body's wrench, pose and twist at a rate of their own (``wrench_rate``, issue 57): a controller
at 200 Hz gets them without the cloud, each wrench the mean over the steps since the last.

``paddle_2d`` at 4 cm (20 outputs a second) with ``wrench_rate: 200``, the paddle pushed at
0.3 m/s from the start so that its wrench changes within an output, recorded:

- 200 wrench messages (and poses, odometry) per simulated second, stamped k / 200 s;
- each output's wrench is the mean of the ten fast ones over its interval to float32 round-off
  (both sums are the device's, over the same steps: each fast time ends a step), the torques
  taken about one point (each is about where the paddle stood at its time);
- the recording holds them all;
- a rate outside 0 or [0.001, 10,000] Hz is refused naming the field.
"""
import numpy as np
import pytest

from gpusph_ros.analysis import bag
from gpusph_ros.runner import Run
from gpusph_ros.scenes.schema import ConfigError, load_scene
from gpusph_ros.scenes.settings import resolve

pytestmark = pytest.mark.physics

RATE, END = 200.0, 0.3  # [Hz], [s] simulated


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    scene = load_scene("paddle_2d")
    run = Run(scene, resolve(scene, dx=0.04, end_time=END, wrench_rate=RATE, particle_rate=0.0))
    taken, why = run.command("paddle", "twist", 0.0, (0.3, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert taken, why
    path = tmp_path_factory.mktemp("wrench_rate") / "bag"
    result = run.execute(run.open_recording(path))
    assert result["status"] == "completed"
    return run, bag.read(path)


def test_the_wrench_comes_at_its_rate_as_the_mean_over_each_output(recorded):
    run, rec = recorded
    fast, output = rec.topic("paddle/wrench_fast"), rec.topic("paddle/wrench")
    n = int(round(END * RATE))
    assert len(fast["t"]) == n and np.allclose(fast["t"], np.arange(1, n + 1) / RATE, atol=1e-9)
    for kind in ("pose_fast", "odom_fast"):
        assert np.allclose(rec.topic(f"paddle/{kind}")["t"], fast["t"], atol=1e-9), kind
    every = int(round(RATE / run.output.output_rate))  # 10 fast messages an output
    force, torque = np.asarray(fast["force"]), np.asarray(fast["torque"])
    # each torque is about where the paddle's reference point stood at its time (it does not turn):
    # moved about the world's origin, the fast ones average to the output's
    at = np.asarray(rec.topic("paddle/pose_fast")["position"])
    at_output = np.asarray(rec.topic("paddle/pose")["position"])
    about_origin = torque + np.cross(at, force)
    scale = np.abs(force).max()
    changed = 0
    for t, f, m, x in zip(output["t"][1:], np.asarray(output["force"])[1:], np.asarray(output["torque"])[1:],
                          at_output[1:]):
        k = int(round(t * RATE))
        window = slice(k - every, k)  # the ten intervals, 5 ms each, that make this output's
        assert f == pytest.approx(force[window].mean(axis=0), abs=2e-6 * scale), t
        assert m + np.cross(x, f) == pytest.approx(about_origin[window].mean(axis=0), abs=2e-6 * scale), t
        changed += np.ptp(force[window, 0]) > 0.02 * abs(f[0])
    assert changed >= 3  # the paddle's push makes the fast ones differ within an output


@pytest.mark.parametrize("rate", [-1.0, 1.0e-4, 2.0e4, float("inf"), float("nan")])
def test_a_wrench_rate_out_of_range_is_refused_naming_it(rate):
    scene = load_scene("paddle_2d")
    with pytest.raises(ConfigError, match="wrench_rate"):
        resolve(scene, wrench_rate=rate)
