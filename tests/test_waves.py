"""Reading a regular wave at a gauge (analysis/waves.py) on a known series. The SPH flume against
Biesel's height is bench/wavemaker.py's (docs/results/bodies.md): a run of a minute or more."""
import math

import numpy as np
import pytest

from gpusph_ros.analysis import waves
from gpusph_ros.theory import wavemaker


@pytest.mark.unit
def test_a_sinusoid_at_a_known_period_is_read_with_its_height_and_period():
    """eta = 0.2 + 0.015 sin(pi t + 0.7) plus a tenth of its amplitude at twice the frequency,
    sampled at 50 Hz over 2.2 periods of 2 s: the fit at the period gives the amplitude exactly and
    the residual is the harmonic's RMS (its frequency is orthogonal to the fit's over whole periods,
    nearly so over 2.2); the period scan finds 2 s within its step."""
    t = np.arange(0.0, 4.4, 0.02)
    harmonic = 0.0015 * np.cos(2 * math.pi * t + 0.3)
    eta = 0.2 + 0.015 * np.sin(math.pi * t + 0.7) + harmonic
    amplitude, residual = waves.sinusoid(t, eta, 2.0)
    assert amplitude == pytest.approx(0.015, rel=0.01)
    assert residual == pytest.approx(np.sqrt(np.mean(harmonic ** 2)), rel=0.05)
    assert waves.period_of(t, eta, 2.1) == pytest.approx(2.0, abs=0.21 * 2.1 / 200)


@pytest.mark.unit
def test_the_steady_window_waits_for_the_ramp_and_ends_before_the_reflection():
    """kh = 0.68 (T = 2 s in 0.4 m): the window opens when the end of a one-period ramp, carried at
    the group velocity, and one more period have reached the gauge, and closes when the paddle's
    first motion, carried at sqrt(g h) to the far wall and back, can be there."""
    period, depth, gauge, length = 2.0, 0.4, 1.2, 6.0
    start, end = waves.steady_window(period, depth, gauge, length, period)
    cg = wavemaker.group_velocity(period, depth, 9.81)
    assert start == pytest.approx(period + gauge / cg + period)
    assert end * math.sqrt(9.81 * depth) == pytest.approx(2 * length - gauge)
    assert cg < math.sqrt(9.81 * depth)  # dispersion: a finite kh travels slower than a long wave
