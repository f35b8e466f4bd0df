"""Monaghan-Kajtar repulsive boundary particles: Monaghan & Kajtar 2009; thesis Eq. 2.26-2.27, in
the form GPUSPH ran it (``MKForce``, forces_kernel.cu of 2011, the code the thesis validated):

f = K / beta r / (r (r - d)) W(q) 2 m_b / (m_a + m_b), K = g H, d = 1.1 dx / beta, with W the
Wendland shape (1 - q/2)^4 (1 + 2q) scaled to W(0) = 1.8 (the paper's Section 4 scales its kernel
to 1.77), so that f is an acceleration. The paper's r - d (the thesis prints r^2) puts a
singularity just outside the boundary particles' own spacing: the force grows without bound as a
fluid particle nears a boundary particle, which is what stops an impact; r - d is clipped at
d / 100 (TrixiParticles' clip) so that a particle a step carried past it is still pushed out.
Boundary particles are spaced dx / beta along a wall (default beta = 2), which smooths the summed
force along it. The paper is 2D, where K / beta keeps the force per unit wall length independent of
beta; a 3D wall holds beta^2 boundary particles per fluid particle's footprint, so 3D divides by
beta^2 (``mk_beta`` = beta^(dim - 1), as TrixiParticles) to keep the force per unit wall area the
same.
"""
import functools
from types import SimpleNamespace

import warp as wp

from .. import kernels
from .model import BoundaryModel

WENDLAND = kernels.WENDLAND
MK_W0 = 1.8  # W(0) of the force's kernel, GPUSPH's scale


class MonaghanKajtar(BoundaryModel):
    name = "monaghan_kajtar"
    repulsive = True

    def spacing(self, dx: float, mk_beta: float) -> float:
        return dx / mk_beta


MODEL = MonaghanKajtar()


def constants(g: float, depth: float, dx: float, mk_beta: float, dim: int) -> dict:
    """K = g H (Eq. 2.27), the spacing ratio beta^(dim - 1) (force per unit wall area, above) and
    the singular distance d = 1.1 dx / beta (GPUSPH's MK_d), named as in Params."""
    return {"mk_k": g * depth, "mk_beta": mk_beta ** (dim - 1), "mk_d": 1.1 * dx / mk_beta}


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    shape = kernels.build(scalar).shape

    @wp.func
    def force(k_coef: scalar, beta: scalar, d: scalar, inv_h: scalar, m_a: scalar, m_b: scalar, r_ab: vec,
              r: scalar) -> vec:
        """Repulsion of a boundary particle of mass m_b on a fluid one of mass m_a (Eq. 2.26)."""
        if r * inv_h >= scalar(2.0) or r <= scalar(0.0):
            return vec(scalar(0.0))
        wq = scalar(MK_W0) * shape(WENDLAND, r * inv_h)
        gap = wp.max(r - d, scalar(0.01) * d)
        return k_coef / beta * wq / (r * gap) * scalar(2.0) * m_b / (m_a + m_b) * r_ab

    @wp.func
    def potential(k_coef: scalar, beta: scalar, d: scalar, inv_h: scalar, m_a: scalar, m_b: scalar,
                  r: scalar) -> scalar:
        """The energy per unit fluid mass that the force stores at distance r: its integral from r
        to the support 2h, taken in u = ln(s - d), where the integrand K / beta W(s)
        2 m_b / (m_a + m_b) is smooth (16-point midpoint rule); from 1.01 d inwards, where the force
        is clipped, nothing more is counted."""
        support = scalar(2.0) / inv_h
        lo = wp.max(r, scalar(1.01) * d)
        if lo >= support:
            return scalar(0.0)
        u0 = wp.log(lo - d)
        du = (wp.log(support - d) - u0) / scalar(16.0)
        total = scalar(0.0)
        for k in range(16):
            s = d + wp.exp(u0 + (scalar(k) + scalar(0.5)) * du)
            total += shape(WENDLAND, s * inv_h)
        return k_coef / beta * scalar(MK_W0) * total * du * scalar(2.0) * m_b / (m_a + m_b)

    return SimpleNamespace(force=force, potential=potential)
