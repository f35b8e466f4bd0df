"""Particle shifting (Lind et al. 2012, J. Comput. Phys. 231, Fickian form; the free-surface
treatment and coefficients of DualSPHysics, JSphShifting): particles drift down the gradient of
their own concentration, which keeps the distribution uniform where a laminar or SPS run without
artificial viscosity would let particles pair and clump (issue 15).

    dr_a = A h |u_a| dt grad C_a,   grad C_a = sum_b V_b grad_a W_ab,   V_b = m_b / rho_b,

A = ``shift_coef`` (DualSPHysics' ShiftCoef, -2: down the gradient). The free surface is found by
the divergence of position, div r_a = -sum_b V_b r_ab . grad_a W_ab, which is dim inside the fluid
and falls towards half of that at the surface: below ``shift_tfs`` (1.5 in 2D, 2.75 in 3D) a
particle is not shifted (the surface would diffuse outwards), above it the shift is scaled by
(div r - tfs) / (dim - tfs). Each step's shift is capped at 0.1 dx per axis (DualSPHysics' limit).
Neighbours are the fluid and dynamic boundary particles (which fill the wall's support as fluid
would). Off when A = 0.
"""

import functools
from types import SimpleNamespace

import warp as wp


def params(cfg) -> dict:
    """The Params fields of shifting under ``cfg`` (a SolverConfig): A h (0 when off), the
    free-surface threshold, and the largest shift of one step along an axis, 0.1 dx."""
    return {"shift_a_h": cfg.shift_coef * cfg.h if cfg.shifting else 0.0, "shift_tfs": cfg.free_surface_threshold,
            "shift_cap": 0.1 * cfg.dx}


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.func
    def concentration_terms(v_b: scalar, r_ab: vec, grad: vec):
        """Neighbour b's share of (grad C_a, div r_a); ``grad`` = grad_a W_ab."""
        return v_b * grad, -v_b * wp.dot(r_ab, grad)

    @wp.func
    def shift_velocity(a_h: scalar, speed: scalar, grad_c: vec, div_r: scalar, tfs: scalar, dim: int) -> vec:
        """dr_a / dt: A h |u_a| grad C_a, zero at the free surface, scaled near it; ``a_h`` = A h."""
        if div_r < tfs:
            return vec(scalar(0.0))
        return a_h * speed * (div_r - tfs) / (scalar(dim) - tfs) * grad_c

    @wp.func
    def capped(step: vec, limit: scalar) -> vec:
        """A step of shift, each axis within +-limit (0.1 dx)."""
        out = step
        for ax in range(3):
            out[ax] = wp.clamp(step[ax], -limit, limit)
        return out

    return SimpleNamespace(concentration_terms=concentration_terms, shift_velocity=shift_velocity, capped=capped)
