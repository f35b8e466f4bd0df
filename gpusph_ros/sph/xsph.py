"""XSPH (Monaghan 1989; thesis Eq. 2.22-2.23): particles move with a velocity smoothed over their
neighbours, dr_a/dt = u_a + eps sum_b m_b / rho_ab u_ba W_ab, rho_ab = (rho_a + rho_b) / 2.

The correction moves particles only; the momentum equation keeps u_a. Off when eps = 0
(``SolverConfig.xsph``; the thesis ran eps = 0.5).
"""

import functools
from types import SimpleNamespace

import warp as wp


def params(cfg) -> dict:
    """The Params field of XSPH under ``cfg`` (a SolverConfig): epsilon, 0 when XSPH is off."""
    return {"xsph_eps": cfg.xsph_eps if cfg.xsph else 0.0}


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.func
    def xsph_velocity(eps: scalar, m_b: scalar, rho_a: scalar, rho_b: scalar, w_ab: scalar, u_ab: vec) -> vec:
        """Neighbour b's share of the correction; u_ba = -u_ab."""
        return -eps * m_b / (scalar(0.5) * (rho_a + rho_b)) * w_ab * u_ab

    return SimpleNamespace(xsph_velocity=xsph_velocity)
