"""Lennard-Jones repulsive boundary particles: Monaghan 1994; thesis Eq. 2.24-2.25.

f = D ((r0/r)^p1 - (r0/r)^p2) r / r^2 with p1 = 12, p2 = 6 (GPUSPH's choice) for r < r0 (zero
beyond: no attraction), D = 5 g H, r0 = dx. One layer of wall particles dx apart.
"""
import functools
from types import SimpleNamespace

import warp as wp

from .model import BoundaryModel


class LennardJones(BoundaryModel):
    name = "lennard_jones"
    repulsive = True


MODEL = LennardJones()


def constants(g: float, depth: float, dx: float) -> dict:
    """D = 5 g H (Eq. 2.25) and r0 = dx, named as in Params."""
    return {"lj_d": 5.0 * g * depth, "lj_r0": dx}


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.func
    def force(d_coef: scalar, r0: scalar, r_ab: vec, r: scalar) -> vec:
        """Repulsion of a boundary particle at -r_ab on a fluid one (Eq. 2.24): an acceleration."""
        if r >= r0 or r <= scalar(0.0):
            return vec(scalar(0.0))
        s2 = (r0 / r) * (r0 / r)
        s6 = s2 * s2 * s2
        return d_coef * (s6 * s6 - s6) / (r * r) * r_ab

    @wp.func
    def potential(d_coef: scalar, r0: scalar, r: scalar) -> scalar:
        """The energy per unit fluid mass that the force stores at distance r: its integral from r
        to r0, D (((r0/r)^12 - 1) / 12 - ((r0/r)^6 - 1) / 6)."""
        if r >= r0 or r <= scalar(0.0):
            return scalar(0.0)
        s2 = (r0 / r) * (r0 / r)
        s6 = s2 * s2 * s2
        return d_coef * ((s6 * s6 - scalar(1.0)) / scalar(12.0) - (s6 - scalar(1.0)) / scalar(6.0))

    return SimpleNamespace(force=force, potential=potential)
