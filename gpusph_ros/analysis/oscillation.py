"""A floating body's heave record: its whole periods (between upward crossings of its mean), over
which its mean draft is taken, and its free decay's period and damping ratio, fitted with

    z(t) = z0 + e^(-zeta omega_d t / sqrt(1 - zeta^2)) (a cos omega_d t + b sin omega_d t)

by a scan of omega_d and zeta, z0, a and b by least squares at each."""
import numpy as np


def free_decay(t, z, omegas=np.linspace(3.0, 20.0, 341), zetas=np.linspace(0.0, 0.5, 101)) -> dict:
    """The damped period [s], damping ratio, mean z0 and residual RMS of z(t) (arrays), the best of
    the ``omegas`` [rad/s] x ``zetas`` scanned."""
    t, z = np.asarray(t, dtype=float), np.asarray(z, dtype=float)
    best = (np.inf, 0.0, 0.0, 0.0)
    for omega in omegas:
        for zeta in zetas:
            decay = np.exp(-zeta * omega / np.sqrt(1.0 - zeta * zeta) * t)
            a = np.column_stack([np.ones_like(t), decay * np.cos(omega * t), decay * np.sin(omega * t)])
            coef, *_ = np.linalg.lstsq(a, z, rcond=None)
            rms = float(np.sqrt(np.mean((z - a @ coef) ** 2)))
            if rms < best[0]:
                best = (rms, omega, zeta, float(coef[0]))
    return {"period": 2.0 * np.pi / best[1], "damping_ratio": best[2], "mean": best[3], "rms": best[0]}


def whole_periods(t, z, after: float = 0.5) -> tuple:
    """(the samples over z's whole periods, the number of upward crossings): between the first and
    the last upward crossing of z's mean after ``after`` [s]."""
    t, z = np.asarray(t, dtype=float), np.asarray(z, dtype=float)
    below = z - z[t >= after].mean() < 0.0
    up = np.flatnonzero(below[:-1] & ~below[1:])
    return (slice(up[0] + 1, up[-1] + 1) if len(up) else slice(0, 0)), len(up)
