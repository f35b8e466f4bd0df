"""Tait equation of state (thesis Eq. 2.12-2.14; Monaghan 1994, Batchelor 1967).

- pressure: p = B ((rho / rho0)^gamma - 1), B = c0^2 rho0 / gamma (Eq. 2.12-2.13; c0 of Eq. 2.14
  is set as a multiple of sqrt(g H), config.SolverConfig.sound_speed).
- elastic_energy: the work of compression per unit mass, e(rho) = int_rho0^rho p / rho'^2 drho' =
  B / rho0 ((rho / rho0)^(gamma - 1) - 1) / (gamma - 1) + B (1 / rho - 1 / rho0), the Tait law
  integrated; the energy check (health.py) adds it to the kinetic and potential energy.
- density: the Tait law inverted, rho = rho0 (1 + p / B)^(1 / gamma), within the fluid's density
  bounds (health.py): the density of a wall particle whose pressure a boundary model sets (mDBC,
  extrapolated-pressure walls);
- cavitation_floor: a fluid that cavitates at ambient pressure (the run setting ``cavitation``)
  keeps rho >= rho0, so p >= 0: air at ambient fills what would be stretched;
- hydrostatic_density: the Tait law inverted at p = rho0 g d, for the initial state;
  hydrostatic_depth, the depth d at which a fluid at rest has density rho (p(rho) / (rho0 g)).
"""

import functools
from types import SimpleNamespace

import numpy as np
import warp as wp


def params(cfg) -> dict:
    """The Params fields of the equation of state of ``cfg`` (a SolverConfig): rho0, B, gamma, c0."""
    return {"rho0": cfg.rho0, "eos_b": cfg.eos_b, "gamma": cfg.gamma, "c0": cfg.sound_speed,
            "rho_floor": cfg.rho0 if cfg.cavitation else 0.0}


@functools.lru_cache(maxsize=None)
def build(scalar):
    @wp.func
    def pressure(rho: scalar, rho0: scalar, b: scalar, gamma: scalar) -> scalar:
        return b * (wp.pow(rho / rho0, gamma) - scalar(1.0))

    @wp.func
    def elastic_energy(rho: scalar, rho0: scalar, b: scalar, gamma: scalar) -> scalar:
        return (b / rho0 * (wp.pow(rho / rho0, gamma - scalar(1.0)) - scalar(1.0)) / (gamma - scalar(1.0))
                + b * (scalar(1.0) / rho - scalar(1.0) / rho0))

    @wp.func
    def cavitation_floor(rho: scalar, floor: scalar) -> scalar:
        """A fluid particle's density no lower than ``floor`` (Params.rho_floor: rho0 where the fluid
        cavitates, else 0): its Tait pressure is then never below ambient."""
        return wp.max(rho, floor)

    @wp.func
    def density(pressure: scalar, rho0: scalar, b: scalar, gamma: scalar, rho_min: scalar, rho_max: scalar) -> scalar:
        """The density whose Tait pressure is ``pressure``, within [rho_min, rho_max]."""
        base = scalar(1.0) + pressure / b
        if base <= scalar(0.0):
            return rho_min
        return wp.clamp(rho0 * wp.pow(base, scalar(1.0) / gamma), rho_min, rho_max)

    return SimpleNamespace(pressure=pressure, elastic_energy=elastic_energy, density=density,
                           cavitation_floor=cavitation_floor)


def hydrostatic_density(depth, rho0: float, b: float, gamma: float, g: float):
    """Density at ``depth`` below a free surface at rest: the Tait law inverted at p = rho0 g d.

    Used to initialise particles so that a tank starts in equilibrium instead of falling onto
    its own pressure (no kernel sum is involved, so the lattice bias of a summed density never
    enters the initial state).
    """
    p = rho0 * g * np.maximum(np.asarray(depth, dtype=np.float64), 0.0)
    return rho0 * (1.0 + p / b) ** (1.0 / gamma)


def hydrostatic_depth(rho, rho0: float, b: float, gamma: float, g: float):
    """The depth below a free surface at rest at which the density is ``rho``: the Tait law
    (Eq. 2.12) over rho0 g, hydrostatic_density's inverse (0 at rho0, negative below it)."""
    return b * ((np.asarray(rho, dtype=np.float64) / rho0) ** gamma - 1.0) / (rho0 * g)
