"""Dynamic boundary particles: Crespo, Gómez-Gesteira & Dalrymple 2007 (the DualSPHysics default).

Boundary particles obey the continuity equation (thesis Eq. 2.11) and the equation of state but
never move; the fluid sees them through the ordinary pressure and viscous terms, so they need no
pair term of their own. A wall is a kernel support of layers deep.
"""
import functools
from types import SimpleNamespace

import warp as wp

from .. import density, kernels
from .model import BoundaryModel


class Dynamic(BoundaryModel):
    name = "dynamic"
    volume = True
    continuity = True


MODEL = Dynamic()


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    grad_factor = kernels.build(scalar).grad_factor
    continuity = density.build(scalar).continuity

    @wp.func
    def density_rate(kernel: int, norm: scalar, inv_h: scalar, m_f: scalar, u_wall: vec, u_f: vec, r_fw: vec,
                     r: scalar) -> scalar:
        """What a fluid particle of mass m_f at r_fw from a wall particle adds to the wall
        particle's drho/dt: the continuity equation seen from the wall particle."""
        grad = -r_fw * grad_factor(kernel, norm, inv_h, r)
        return continuity(m_f, u_wall - u_f, grad)

    return SimpleNamespace(density_rate=density_rate)
