"""Linear wavemaker theory (Biesel 1951; as Dean & Dalrymple 1991, Water Wave Mechanics for Engineers
and Scientists, Section 6.2): the height H of the progressive wave a paddle of stroke S makes in
water of depth h, far enough from the paddle for its evanescent modes to have died (a few depths).

    dispersion:  omega^2 = g k tanh(k h)
    piston:      H / S = 2 (cosh 2kh - 1) / (sinh 2kh + 2kh)                          (Eq. 6.22)
    flap hinged at the bed:
                 H / S = 4 sinh(kh) / (kh) (kh sinh kh - cosh kh + 1) / (sinh 2kh + 2kh)  (Eq. 6.23)

S is the paddle's full stroke at the still water level (twice its amplitude there).
"""
import math


def wavenumber(period: float, depth: float, g: float = 9.81) -> float:
    """k [1/m] of a wave of ``period`` [s] in water ``depth`` [m] deep: the dispersion relation,
    solved by Newton's method from the deep-water k."""
    omega = 2.0 * math.pi / period
    k = max(omega * omega / g, omega / math.sqrt(g * depth))
    for _ in range(100):
        t = math.tanh(k * depth)
        f = g * k * t - omega * omega
        df = g * t + g * k * depth * (1.0 - t * t)
        step = f / df
        k -= step
        if abs(step) < 1.0e-14 * k:
            break
    return k


def piston_ratio(kh: float) -> float:
    """H / S of a piston paddle (Biesel)."""
    return 2.0 * (math.cosh(2.0 * kh) - 1.0) / (math.sinh(2.0 * kh) + 2.0 * kh)


def flap_ratio(kh: float) -> float:
    """H / S of a flap hinged at the bed, S its stroke at the still water level (Biesel)."""
    return (4.0 * math.sinh(kh) / kh * (kh * math.sinh(kh) - math.cosh(kh) + 1.0)
            / (math.sinh(2.0 * kh) + 2.0 * kh))


def group_velocity(period: float, depth: float, g: float = 9.81) -> float:
    """c_g [m/s] = c (1 + 2kh / sinh 2kh) / 2 (Dean & Dalrymple Eq. 4.77): the speed a wave train's
    energy, and its front, travels at."""
    k = wavenumber(period, depth, g)
    kh = k * depth
    return 2.0 * math.pi / period / k * 0.5 * (1.0 + 2.0 * kh / math.sinh(2.0 * kh))
