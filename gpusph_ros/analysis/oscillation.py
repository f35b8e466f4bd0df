"""A damped oscillation's period and damping ratio from a record: the free decay of a floating
body's heave, say, fitted with

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
