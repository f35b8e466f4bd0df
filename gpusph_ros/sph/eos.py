"""Tait equation of state (thesis Eq. 2.12-2.14; Monaghan 1994, Batchelor 1967).

p = B ((rho / rho0)^gamma - 1), B = c0^2 rho0 / gamma.
"""

import functools

import numpy as np
import warp as wp


@functools.lru_cache(maxsize=None)
def build(scalar):
    @wp.func
    def pressure(rho: scalar, rho0: scalar, b: scalar, gamma: scalar) -> scalar:
        return b * (wp.pow(rho / rho0, gamma) - scalar(1.0))

    @wp.func
    def sound_speed(rho: scalar, rho0: scalar, c0: scalar, gamma: scalar) -> scalar:
        """Local c = c0 (rho / rho0)^((gamma - 1) / 2), from dp/drho of the Tait law."""
        return c0 * wp.pow(rho / rho0, scalar(0.5) * (gamma - scalar(1.0)))

    @wp.func
    def density_for_pressure(p: scalar, rho0: scalar, b: scalar, gamma: scalar) -> scalar:
        """The inverse of ``pressure``: rho0 (1 + p / B)^(1 / gamma)."""
        return rho0 * wp.pow(scalar(1.0) + p / b, scalar(1.0) / gamma)

    return pressure, sound_speed, density_for_pressure


def hydrostatic_density(depth, rho0: float, b: float, gamma: float, g: float):
    """Density at ``depth`` below a free surface at rest: the Tait law inverted at p = rho0 g d.

    Used to initialise particles so that a tank starts in equilibrium instead of falling onto
    its own pressure (no kernel sum is involved, so the lattice bias of a summed density never
    enters the initial state).
    """
    p = rho0 * g * np.maximum(np.asarray(depth, dtype=np.float64), 0.0)
    return rho0 * (1.0 + p / b) ** (1.0 / gamma)
