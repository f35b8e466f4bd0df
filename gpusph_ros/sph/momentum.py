"""The pressure term of the momentum equation (thesis Eq. 2.15: Du/Dt = -grad(p) / rho + g + Theta).

-(grad p / rho)_a = -sum_b m_b (p_a / rho_a^2 + p_b / rho_b^2) grad_a W_ab, the symmetric form that
conserves linear momentum pairwise (Monaghan 1992, as GPUSPH and DualSPHysics). p / rho^2 is
computed once per particle (``p_rho2``) instead of once per pair. Gravity is added once per
particle; the diffusion term Theta is viscosity.py's.
"""

import functools
from types import SimpleNamespace

import warp as wp


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.func
    def pressure_gradient(m_b: scalar, p_rho2_a: scalar, p_rho2_b: scalar, grad: vec) -> vec:
        return -m_b * (p_rho2_a + p_rho2_b) * grad

    return SimpleNamespace(pressure_gradient=pressure_gradient)
