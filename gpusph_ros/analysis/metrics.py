"""The thesis's metrics (Section 4), as plain functions of time series.

- moving_average: the 0.04 s moving time average applied to every numerical series (4.2.1).
- percent_error: Eq. 4.1, (numerical - experimental) / experimental x 100.
- peak and align_to: peak value and time; the numerical series is shifted in time so that its
  peak falls at the experimental peak's time, as the thesis did for velocity and force (4.2.1-2).
- rms_error: RMS of numerical minus experimental at the experimental points' times (4.2.1-2).
- forward_return: max forward and max return velocity and their time difference (4.2.3, point D).
- bore_arrival: the time of greatest acceleration (4.3.1), and mean_behind: the mean over the 6 s
  behind it (3.3).
- first_impact: when a wall-pressure series' first impact starts and its pressure-time integral
  (Lobovsky et al. 2014; not in the thesis).
"""
import numpy as np

THESIS_WINDOW = 0.04  # [s] moving average (thesis 4.2.1)
BORE_WINDOW = 6.0  # [s] mean behind the bore (thesis 3.3)
# a first impact on the wall starts when p / (rho g H) first passes IMPACT_START and lasts
# IMPACT_LENGTH in t sqrt(g/H): Lobovsky's sensors at 3-30 mm rise, peak and fall back to the
# quasi-static plateau (~0.6 rho g H) within 0.75 of it
IMPACT_START = 0.25
IMPACT_LENGTH = 0.75
# the windows of t sqrt(g/H) a wall sensor is compared with the converged 2D reference over (De Courcy et
# al. 2024): the first impact, after it, the flow along the wall
REFERENCE_WINDOWS = ((2.3, 3.3), (3.3, 4.5), (4.5, 6.5))


def moving_average(t, y, window: float = THESIS_WINDOW):
    """Centred moving average over ``window`` seconds (samples with |t_j - t_i| <= window/2);
    works for uneven sampling."""
    t, y = np.asarray(t, dtype=np.float64), np.asarray(y, dtype=np.float64)
    order = np.argsort(t, kind="stable")
    t, y = t[order], y[order]
    csum = np.concatenate([[0.0], np.cumsum(y)])
    lo = np.searchsorted(t, t - 0.5 * window - 1e-12, side="left")
    hi = np.searchsorted(t, t + 0.5 * window + 1e-12, side="right")
    return t, (csum[hi] - csum[lo]) / (hi - lo)


def percent_error(numerical: float, experimental: float) -> float:
    return (numerical - experimental) / experimental * 100.0


def peak(t, y):
    """(time, value) of the maximum."""
    k = int(np.argmax(y))
    return float(t[k]), float(y[k])


def align_to(t, y, t_ref_peak: float):
    """``t`` shifted so that the peak of ``y`` falls at ``t_ref_peak``."""
    return np.asarray(t) + (t_ref_peak - peak(t, y)[0])


def rms_error(t, y, t_exp, y_exp) -> float:
    """RMS of the numerical series (interpolated) minus the experimental points, over the points
    that fall within the numerical series' span; NaN if none does."""
    t_exp, y_exp = np.asarray(t_exp), np.asarray(y_exp)
    inside = (t_exp >= t[0]) & (t_exp <= t[-1])
    if not inside.any():
        return float("nan")
    diff = np.interp(t_exp[inside], t, y) - y_exp[inside]
    return float(np.sqrt(np.mean(diff ** 2)))


def forward_return(t, u):
    """Max forward velocity, the max return (most negative) velocity after it, and the time
    between them."""
    k = int(np.argmax(u))
    j = k + int(np.argmin(u[k:]))
    return {"max_forward": float(u[k]), "t_forward": float(t[k]), "max_return": float(u[j]),
            "t_return": float(t[j]), "time_difference": float(t[j] - t[k])}


def bore_arrival(t, u) -> float:
    """Time of the greatest acceleration (end of the steepest rise between two outputs)."""
    accel = np.diff(u) / np.diff(t)
    return float(t[int(np.argmax(accel)) + 1])


def mean_behind(t, u, start: float, window: float = BORE_WINDOW):
    """Mean of ``u`` over [start, start + window], and the length of record it actually covered."""
    inside = (t >= start) & (t <= start + window)
    if not inside.any():
        return float("nan"), 0.0
    return float(np.mean(u[inside])), float(t[inside][-1] - start)


def first_impact(t, p, start: float = IMPACT_START, length: float = IMPACT_LENGTH):
    """(start time, pressure-time integral over ``length`` from it) of the first impact in ``p``
    (trapezoids; both in the series' own units, e.g. t sqrt(g/H) and p / (rho g H)); NaNs when
    ``p`` never reaches ``start`` or the series ends within the impact."""
    t, p = np.asarray(t, dtype=np.float64), np.asarray(p, dtype=np.float64)
    above = np.flatnonzero(p > start)
    if not len(above) or t[-1] < t[above[0]] + length:
        return float("nan"), float("nan")
    t0 = float(t[above[0]])
    inside = (t >= t0) & (t <= t0 + length)
    ti, pi = t[inside], p[inside]
    return t0, float(np.sum(0.5 * (pi[1:] + pi[:-1]) * np.diff(ti)))  # np.trapz is gone from numpy 2


def window_impulse(t, p, lo: float, hi: float) -> float:
    """The trapezoid integral of ``p`` over [lo, hi], the series interpolated onto 2,001 points there
    (an irregular digitised series and a sampled one alike); NaN when the series ends before ``hi``."""
    t, p = np.asarray(t, dtype=np.float64), np.asarray(p, dtype=np.float64)
    if not len(t) or t[-1] < hi:
        return float("nan")
    grid = np.linspace(lo, hi, 2001)
    values = np.interp(grid, t, p)
    return float(np.sum(0.5 * (values[1:] + values[:-1]) * np.diff(grid)))
