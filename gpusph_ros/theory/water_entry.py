"""The vertical force on a 2D wedge entering still water at constant speed V, before its chines wet,
from two Wagner-type models (gravity, compressibility and air neglected). The flow is self-similar, so
the force per unit length grows linearly, F = C rho V^3 t, and each model is its coefficient C.

- Wagner (1932; as Faltinsen 2005, Hydrodynamics of High-Speed Marine Vehicles, Section 8.2): the
  wetted half-width with the water's rise, c = pi V t / (2 tan beta), and the flat plate's added mass
  rho pi c^2 / 2, so F = d/dt (rho pi c^2 / 2) V and C = pi^3 / (4 tan^2 beta). It linearises the
  Bernoulli equation and puts the body on the still water line, which overpredicts the force as the
  deadrise beta grows.
- The modified Logvinovich model (Korobkin 2004, Analytical models of water impact, Eur. J. Appl.
  Math. 15, 821-838; used by Hulin et al. 2022, J. Fluid Mech. 944, A8, against fully nonlinear
  solutions): Wagner's c(t) and flat-plate potential phi0 = -V sqrt(c^2 - x^2), carried to the body
  surface y = f(x) - h(t) by a Taylor expansion, phi = phi0 - V (f(x) - h), and the whole Bernoulli
  equation there. With the tangential velocity u = V x / sqrt(c^2 - x^2) - V f'(x):

      p / rho = V c c' / sqrt(c^2 - x^2) - V^2 - u V f' / (1 + f'^2) - (u^2 - V^2) / (2 (1 + f'^2))

  integrated where it is positive (it falls below zero just inside x = c, where the root of the jet
  leaves the body).
"""
import math

import numpy as np


def wagner_coefficient(deadrise_deg: float) -> float:
    """C of Wagner's force on a wedge of deadrise ``deadrise_deg``: F = C rho V^3 t."""
    return math.pi ** 3 / (4.0 * math.tan(math.radians(deadrise_deg)) ** 2)


def wetting_time(half_width: float, deadrise_deg: float, speed: float) -> float:
    """[s] when Wagner's wetted half-width reaches the chine, ``half_width`` [m] from the apex."""
    return 2.0 * half_width * math.tan(math.radians(deadrise_deg)) / (math.pi * speed)


def mlm_coefficient(deadrise_deg: float, points: int = 200_001) -> float:
    """C of the modified Logvinovich model's force on a wedge: F = C rho V^3 t.

    In units of V and c (x = c sin theta, so that the flat plate's inverse square root integrates):
    F / (rho V^2 c) = 2 int_0^pi/2 max(p / (rho V^2), 0) cos theta d theta, and c = k V t with
    k = pi / (2 tan beta)."""
    slope = math.tan(math.radians(deadrise_deg))
    k = math.pi / (2.0 * slope)
    theta = np.linspace(0.0, math.pi / 2.0, points)[:-1]
    s, root = np.sin(theta), np.cos(theta)
    u = s / root - slope
    p = k / root - 1.0 - u * slope / (1.0 + slope ** 2) - (u * u - 1.0) / (2.0 * (1.0 + slope ** 2))
    integrand = np.maximum(p, 0.0) * root
    return 2.0 * k * float(np.sum(0.5 * (integrand[1:] + integrand[:-1])) * (theta[1] - theta[0]))
