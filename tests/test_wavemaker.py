"""A 2D piston wavemaker against linear wavemaker theory (Biesel; theory/wavemaker.py): the height
of the wave it makes, read by gauges 2 and 3 depths from the paddle (past its evanescent modes),
and its period. The short wave (T = 1 s, kh = 1.72) and the longer flumes are bench/wavemaker.py's
(docs/results/wavemaker.csv, docs/results/bodies.md): that run alone took a ninth of the suite."""
import math

import numpy as np
import pytest

from gpusph_ros.analysis import waves
from gpusph_ros.runner import Run
from gpusph_ros.scenes.flume import PADDLE, wave_flume
from gpusph_ros.scenes.settings import resolve

DEPTH, HEIGHT = 0.4, 0.03  # [m]
GAUGES = (2 * DEPTH, 3 * DEPTH)  # [m] from the paddle's face
# a wave flume's settings (docs/scenes.md): under the default cubic spline at 1.3 dx a wave loses a
# sixth of its height in its first metre
SETTINGS = ["alpha=0.01", "kernel=wendland", "hdx=2.0"]


@pytest.mark.physics
def test_a_piston_makes_biesels_wave_height_at_its_period():
    """kh = 0.68 (T = 2 s, one period read, dx = 2.5 cm, 5,520 particles): 3 cm waves in 0.4 m of
    water from a piston ramped in over a period, in a flume long enough that the far wall's
    reflection cannot return to the gauges within the window (analysis.waves.steady_window: 6.1 m).
    Each gauge's height, fitted with a sinusoid at the paddle's period, is Biesel's within 5%
    (measured +0.9% and +0.7%); the best-fitting period, over the window and the period before it
    (the front passing), is the paddle's within 2% (measured 2.006 s at both gauges)."""
    period, dx, periods = 2.0, 0.025, 1
    start = waves.steady_window(period, DEPTH, GAUGES[-1], 1.0, period)[0]
    end = start + periods * period
    # the far wall's reflection back at the last gauge at sqrt(g h) no sooner than the window's end
    length = PADDLE[1] + (end * math.sqrt(9.81 * DEPTH) + GAUGES[-1]) / 2.0
    assert waves.steady_window(period, DEPTH, GAUGES[-1], length - PADDLE[1], period)[1] == pytest.approx(end)
    scene = wave_flume(length, DEPTH, period, HEIGHT, GAUGES, ramp=period)
    run = Run(scene, resolve(scene, sets=[f"dx={dx}", f"end_time={end:.3f}", "output_rate=50", *SETTINGS]))
    times, levels = [], []
    while not run.done:
        msgs = run.step_output()
        if msgs is not None and run.solver.time >= start - period - 1e-9:
            levels.append([m.point.z for topic, m in msgs if topic.rsplit("/", 1)[-1] in ("g1", "g2")])
            times.append(run.solver.time)
    times, levels = np.array(times), np.array(levels)
    steady = times >= start - 1e-9
    assert steady.sum() >= 50 * periods * period
    for n in range(len(GAUGES)):
        assert 2 * waves.sinusoid(times[steady], levels[steady, n], period)[0] == pytest.approx(HEIGHT, rel=0.05)
        assert waves.period_of(times, levels[:, n], period) == pytest.approx(period, rel=0.02)
    assert run.solver.excluded_particles == 0
