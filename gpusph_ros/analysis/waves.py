"""Regular waves in a flume, read at a gauge: when the paddle's steady wave stands there, and its
height and period (bench/wavemaker.py)."""
import math

import numpy as np

from ..theory import wavemaker


def steady_window(period: float, depth: float, gauge: float, length: float, ramp: float,
                  g: float = 9.81) -> tuple:
    """(start, end) [s] of the steady wave at ``gauge`` [m from the paddle] in a flume ``length``
    long: from the end of the paddle's ``ramp`` carried there at the group velocity, plus a period
    for the front to pass; until the far wall's reflection of the paddle's first motion can be back,
    at sqrt(g h), the fastest any linear wave travels: a ramp's long-wave precursors outrun the
    wave (at kh = 1.7, twice its group velocity), and a window ended by the group velocity alone
    read the reflection."""
    start = ramp + gauge / wavemaker.group_velocity(period, depth, g) + period
    end = (2.0 * length - gauge) / math.sqrt(g * depth)
    return start, end


def sinusoid(t, eta, period: float) -> tuple:
    """(amplitude, residual RMS) of eta(t) fitted with its mean and a sinusoid of ``period`` (least
    squares): a wave's height is twice the amplitude."""
    t = np.asarray(t, dtype=float)
    omega = 2.0 * math.pi / period
    a = np.column_stack([np.ones_like(t), np.sin(omega * t), np.cos(omega * t)])
    coef, *_ = np.linalg.lstsq(a, np.asarray(eta, dtype=float), rcond=None)
    return math.hypot(coef[1], coef[2]), float(np.sqrt(np.mean((eta - a @ coef) ** 2)))


def period_of(t, eta, near: float, spread: float = 0.1, count: int = 201) -> float:
    """The period within ``spread`` of ``near`` whose sinusoid fits eta(t) best."""
    scan = np.linspace((1.0 - spread) * near, (1.0 + spread) * near, count)
    return float(scan[np.argmin([sinusoid(t, eta, p)[1] for p in scan])])
