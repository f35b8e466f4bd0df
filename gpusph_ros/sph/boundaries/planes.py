"""Particle-less walls (``wall_planes``), each a point on it and its inward normal.

The fluid's own kernel sums are completed by the mirror image of the fluid across the wall,
integrated analytically over the half-space behind it. With Gamma'(d) = the kernel integrated over the wall plane at
distance d, the mirror adds 2 p_a / rho_a Gamma'(d) n to the acceleration and
-2 rho_a (u_a . n) Gamma'(d) to drho/dt, which balances a hydrostatic column exactly as the
truncated kernel would have lacked. The mirrored fluid also carries the hydrostatic pressure
gradient along the plane: with V(d) = the kernel integrated over the half-space behind the plane
(1/2 at d = 0), it adds -V(d) (g - (g . n) n). Without it the fluid beside a vertical plane sank:
the first column at 2.40 m/s^2 where the tank's interior accelerates at 0.18 (V = 0.25 at d = dx/2),
which a particle floor that does not stiffen as the fluid nears it (the extrapolated-pressure
wall) let through at the plane's foot (docs/results/wall_pressure.md). A Lennard-Jones term with
r0 = dx/2 (the lattice's distance to the wall) stops penetration where the pressure is near zero.
Where two orthogonal planes meet (a tank's edge; a corner in 2D) the region behind both lies in
both half-spaces: its mirrored pressure would be counted twice, and the fluid in the corner was
thrown out of it (a still 2D tank's corner particle: 44 m/s^2 in the first step against 14 at one
wall, tests/test_wall_forces.py). So the pressure term of that region is taken off once
(``plane_overlap``) and, where three planes meet, the region behind all three put back
(inclusion-exclusion, ``plane_corners``). The density term needs no such
correction: the two mirror velocities of the region sum to its point image's.
"""
import functools
from types import SimpleNamespace

import warp as wp

from .. import kernels
from . import lennard_jones
from .model import BoundaryModel


class Planes(BoundaryModel):
    name = "planes"

    def run_settings(self) -> dict:
        return {"wall_planes": True}


MODEL = Planes()


def constants(dx: float) -> dict:
    """The Lennard-Jones term's r0 = dx / 2 (its D is lennard_jones.constants'), named as in Params."""
    return {"plane_r0": 0.5 * dx}


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    w = kernels.build(scalar).w
    repel = lennard_jones.build(scalar).force

    @wp.func
    def plane_kernel_flux(kernel: int, norm: scalar, inv_h: scalar, dim: int, d: scalar) -> scalar:
        """|Gamma'(d)|: W integrated over the plane at distance d (midpoint rule in s)."""
        support = scalar(2.0) / inv_h
        if d >= support:
            return scalar(0.0)
        s_max = wp.sqrt(support * support - d * d)
        ds = s_max / scalar(16.0)  # 16-point midpoint rule: far below the SPH error
        total = scalar(0.0)
        for k in range(16):
            s = (scalar(k) + scalar(0.5)) * ds
            wk = w(kernel, norm, inv_h, wp.sqrt(d * d + s * s))
            if dim == 3:
                total += wk * scalar(6.283185307179586) * s * ds
            else:
                total += wk * scalar(2.0) * ds
        return total

    @wp.func
    def plane_kernel_volume(kernel: int, norm: scalar, inv_h: scalar, dim: int, d: scalar) -> scalar:
        """W integrated over the half-space beyond the plane at distance d: the share of the
        support the plane stands for (1/2 at d = 0; midpoint rule in the depth over Gamma)."""
        support = scalar(2.0) / inv_h
        if d >= support:
            return scalar(0.0)
        dz = (support - d) / scalar(16.0)
        total = scalar(0.0)
        for k in range(16):
            total += plane_kernel_flux(kernel, norm, inv_h, dim, d + (scalar(k) + scalar(0.5)) * dz) * dz
        return total

    @wp.func
    def plane_flux_part(kernel: int, norm: scalar, inv_h: scalar, dim: int, d: scalar, lo1: scalar,
                        lo2: scalar) -> scalar:
        """W integrated over the part of the plane at distance d where the in-plane coordinates s1
        (and in 3D s2) exceed lo1 (lo2): a region behind another plane, seen from the particle
        (midpoint rules, 16 points an axis); lo below -2h means no limit along that axis."""
        support = scalar(2.0) / inv_h
        if d >= support:
            return scalar(0.0)
        r1 = wp.sqrt(support * support - d * d)
        a1 = wp.max(lo1, -r1)
        if a1 >= r1:
            return scalar(0.0)
        ds1 = (r1 - a1) / scalar(16.0)
        total = scalar(0.0)
        for k in range(16):
            s1 = a1 + (scalar(k) + scalar(0.5)) * ds1
            rho2 = d * d + s1 * s1
            if dim == 2:
                total += w(kernel, norm, inv_h, wp.sqrt(rho2)) * ds1
            elif rho2 < support * support:
                r2 = wp.sqrt(support * support - rho2)
                a2 = wp.max(lo2, -r2)
                if a2 < r2:
                    ds2 = (r2 - a2) / scalar(16.0)
                    for m in range(16):
                        s2 = a2 + (scalar(m) + scalar(0.5)) * ds2
                        total += w(kernel, norm, inv_h, wp.sqrt(rho2 + s2 * s2)) * ds1 * ds2
        return total

    @wp.func
    def plane_overlap(kernel: int, norm: scalar, inv_h: scalar, dim: int, d_k: scalar, d_l: scalar, lo: scalar,
                      n_k: vec, n_l: vec, p_a: scalar, rho_a: scalar) -> vec:
        """The mirrored pressure that planes k and l (orthogonal, at distances d_k, d_l along their
        inward normals) each gave the region behind both of them, once; ``lo`` limits that region
        along the third axis (3D: behind a third plane at that distance; below -2h: no limit)."""
        # behind plane l (s > d_l along -n_l) on plane k, and behind k on plane l
        g = (plane_flux_part(kernel, norm, inv_h, dim, d_k, d_l, lo) * n_k
             + plane_flux_part(kernel, norm, inv_h, dim, d_l, d_k, lo) * n_l)
        return scalar(2.0) * p_a / rho_a * g

    @wp.func
    def plane_corners(kernel: int, norm: scalar, inv_h: scalar, dim: int, x: vec, plane_point: wp.array(dtype=vec),
                      plane_normal: wp.array(dtype=vec), n_planes: int, p_a: scalar, rho_a: scalar) -> vec:
        """The overlap corrections of every pair and triple of orthogonal planes within the support
        2h of a fluid particle at x: each pair's overlap subtracted once; the region behind a triple,
        which its three pairs took away once too often, added back (inclusion-exclusion)."""
        support = scalar(2.0) / inv_h
        none = scalar(-2.0) * support
        acc = vec(scalar(0.0))
        for k in range(n_planes):
            n_k = plane_normal[k]
            d_k = wp.dot(x - plane_point[k], n_k)
            if d_k < support:
                for q in range(k + 1, n_planes):
                    n_l = plane_normal[q]
                    d_l = wp.dot(x - plane_point[q], n_l)
                    if d_l < support and wp.abs(wp.dot(n_k, n_l)) < scalar(1.0e-6):
                        acc -= plane_overlap(kernel, norm, inv_h, dim, d_k, d_l, none, n_k, n_l, p_a, rho_a)
                        for m in range(q + 1, n_planes):
                            n_m = plane_normal[m]
                            d_m = wp.dot(x - plane_point[m], n_m)
                            if (d_m < support and wp.abs(wp.dot(n_k, n_m)) < scalar(1.0e-6)
                                    and wp.abs(wp.dot(n_l, n_m)) < scalar(1.0e-6)):
                                acc += plane_overlap(kernel, norm, inv_h, dim, d_k, d_l, d_m, n_k, n_l, p_a, rho_a)
                                acc += (scalar(2.0) * p_a / rho_a
                                        * plane_flux_part(kernel, norm, inv_h, dim, d_m, d_k, d_l) * n_m)
        return acc

    @wp.func
    def plane_wall(kernel: int, norm: scalar, inv_h: scalar, dim: int, d: scalar, n: vec, p_a: scalar,
                   rho_a: scalar, u_a: vec, lj_d: scalar, r0: scalar, g: vec):
        """What a plane at distance d along its inward normal n does to a fluid particle of pressure
        p_a (clipped at 0), density rho_a and velocity u_a: (acceleration, drho/dt), the mirror
        terms, the hydrostatic pressure gradient along the plane that the mirrored fluid carries,
        and the Lennard-Jones term with r0 = dx / 2."""
        flux = plane_kernel_flux(kernel, norm, inv_h, dim, d)
        if flux <= scalar(0.0):
            return vec(scalar(0.0)), scalar(0.0)
        along = g - wp.dot(g, n) * n
        acc = (scalar(2.0) * p_a / rho_a * flux * n - plane_kernel_volume(kernel, norm, inv_h, dim, d) * along
               + repel(lj_d, r0, d * n, d))
        return acc, scalar(-2.0) * rho_a * wp.dot(u_a, n) * flux

    return SimpleNamespace(plane_wall=plane_wall, plane_corners=plane_corners)
