"""Boundary forces on fluid particles, chosen by name.

- lennard_jones: Monaghan 1994; thesis Eq. 2.24-2.25. f = D ((r0/r)^p1 - (r0/r)^p2) r / r^2 with
  p1 = 12, p2 = 6 (GPUSPH's choice) for r < r0 (zero beyond: no attraction), D = 5 g H, r0 = dx.
- monaghan_kajtar: Monaghan & Kajtar 2009; thesis Eq. 2.26-2.27, in the form GPUSPH ran it
  (``MKForce``, forces_kernel.cu of 2011, the code the thesis validated):
  f = K / beta r / (r (r - d)) W(q) 2 m_b / (m_a + m_b), K = g H, d = 1.1 dx / beta, with W the
  Wendland shape (1 - q/2)^4 (1 + 2q) scaled to W(0) = 1.8 (the paper's Section 4 scales its
  kernel to 1.77), so that f is an acceleration. The paper's r - d (the thesis prints r^2) puts a
  singularity just outside the boundary particles' own spacing: the force grows without bound as a
  fluid particle nears a boundary particle, which is what stops an impact; r - d is clipped at
  d / 100 (TrixiParticles' clip) so that a particle a step carried past it is still pushed out.
  Boundary particles are spaced dx / beta along a wall (default beta = 2), which smooths the summed
  force along it. The paper is 2D, where K / beta keeps the force per unit wall length independent
  of beta; a 3D wall holds beta^2 boundary particles per fluid particle's footprint, so 3D divides
  by beta^2 (``mk_beta`` = beta^(dim - 1), as TrixiParticles) to keep the force per unit wall area
  the same.
- dynamic: Crespo et al. 2007 (the DualSPHysics default). Boundary particles obey the
  continuity equation and the equation of state but never move; the fluid sees them through the
  ordinary pressure and viscous terms. No function here: the pair terms are the fluid ones.
- mdbc: English et al. 2021, the modified dynamic boundary: the same particles and pair terms,
  but each boundary particle's density is extrapolated from the fluid at its mirror image across
  the wall (mdbc.py) instead of integrated by the continuity equation.
- planes (particle-less walls, given by a point and an inward normal): the fluid's own kernel
  sums are completed by the mirror image of the fluid across the wall, integrated analytically
  over the half-space behind it. With Gamma'(d) = the kernel integrated over the wall plane at
  distance d, the mirror adds 2 p_a / rho_a Gamma'(d) n to the acceleration and
  -2 rho_a (u_a . n) Gamma'(d) to drho/dt, which balances a hydrostatic column exactly as the
  truncated kernel would have lacked. A Lennard-Jones term with r0 = dx/2 (the lattice's
  distance to the wall) stops penetration where the pressure is near zero.
  Where two orthogonal planes meet (a tank's edge; a corner in 2D) the region behind both lies in
  both half-spaces: its mirrored pressure would be counted twice, and the fluid in the corner was
  thrown out of it (a still 2D tank's corner particle: 44 m/s^2 in the first step against 14 at one
  wall, tests/test_wall_forces.py). So the pressure term of that region is taken off once
  (``plane_overlap``) and, where three planes meet, the region behind all three put back
  (inclusion-exclusion, ``plane_corners``). The density term needs no such
  correction: the two mirror velocities of the region sum to its point image's.

The wall constants (D, r0, K, the plane's r0) follow from the scene's g, depth and dx
(``wall_constants``).
"""

import functools
from types import SimpleNamespace

import numpy as np
import warp as wp

from . import kernels

# ids >= DYNAMIC are walls of particles that carry a density and a fluid volume
BOUNDARY_ID = {"lennard_jones": 0, "monaghan_kajtar": 1, "dynamic": 2, "mdbc": 3}
WENDLAND = kernels.WENDLAND
LENNARD_JONES = BOUNDARY_ID["lennard_jones"]
MK_W0 = 1.8  # W(0) of the Monaghan-Kajtar force's kernel, GPUSPH's scale


def wall_constants(g: float, depth: float, dx: float, mk_beta: float, dim: int) -> dict:
    """The wall models' constants for gravity ``g``, fluid depth H and spacing dx, named as in Params:
    Lennard-Jones D = 5 g H (Eq. 2.25) and r0 = dx; Monaghan-Kajtar K = g H (Eq. 2.27), the
    spacing ratio beta^(dim - 1) (see above: force per unit wall area) and the singular distance
    d = 1.1 dx / beta (GPUSPH's MK_d); the plane's r0 = dx / 2."""
    return {"lj_d": 5.0 * g * depth, "lj_r0": dx, "mk_k": g * depth, "mk_beta": mk_beta ** (dim - 1),
            "mk_d": 1.1 * dx / mk_beta, "plane_r0": 0.5 * dx}


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    K = kernels.build(scalar)
    shape, w = K.shape, K.w

    @wp.func
    def lennard_jones(d_coef: scalar, r0: scalar, r_ab: vec, r: scalar) -> vec:
        """Repulsion of a boundary particle at -r_ab on a fluid one (Eq. 2.24): an acceleration."""
        if r >= r0 or r <= scalar(0.0):
            return vec(scalar(0.0))
        s2 = (r0 / r) * (r0 / r)
        s6 = s2 * s2 * s2
        return d_coef * (s6 * s6 - s6) / (r * r) * r_ab

    @wp.func
    def monaghan_kajtar(k_coef: scalar, beta: scalar, d: scalar, inv_h: scalar, m_a: scalar, m_b: scalar,
                        r_ab: vec, r: scalar) -> vec:
        """Repulsion of a boundary particle of mass m_b on a fluid one of mass m_a (Eq. 2.26)."""
        if r * inv_h >= scalar(2.0) or r <= scalar(0.0):
            return vec(scalar(0.0))
        wq = scalar(MK_W0) * shape(WENDLAND, r * inv_h)
        gap = wp.max(r - d, scalar(0.01) * d)
        return k_coef / beta * wq / (r * gap) * scalar(2.0) * m_b / (m_a + m_b) * r_ab

    @wp.func
    def lennard_jones_potential(d_coef: scalar, r0: scalar, r: scalar) -> scalar:
        """The energy per unit fluid mass that the Lennard-Jones force stores at distance r: its
        integral from r to r0, D (((r0/r)^12 - 1) / 12 - ((r0/r)^6 - 1) / 6)."""
        if r >= r0 or r <= scalar(0.0):
            return scalar(0.0)
        s2 = (r0 / r) * (r0 / r)
        s6 = s2 * s2 * s2
        return d_coef * ((s6 * s6 - scalar(1.0)) / scalar(12.0) - (s6 - scalar(1.0)) / scalar(6.0))

    @wp.func
    def monaghan_kajtar_potential(k_coef: scalar, beta: scalar, d: scalar, inv_h: scalar, m_a: scalar,
                                  m_b: scalar, r: scalar) -> scalar:
        """The energy per unit fluid mass that the Monaghan-Kajtar force stores at distance r: its
        integral from r to the support 2h, taken in u = ln(s - d), where the integrand K / beta W(s)
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
                   rho_a: scalar, u_a: vec, lj_d: scalar, r0: scalar):
        """What a plane at distance d along its inward normal n does to a fluid particle of pressure
        p_a (clipped at 0), density rho_a and velocity u_a: (acceleration, drho/dt), the mirror
        terms plus the Lennard-Jones term with r0 = dx / 2."""
        flux = plane_kernel_flux(kernel, norm, inv_h, dim, d)
        if flux <= scalar(0.0):
            return vec(scalar(0.0)), scalar(0.0)
        acc = scalar(2.0) * p_a / rho_a * flux * n + lennard_jones(lj_d, r0, d * n, d)
        return acc, scalar(-2.0) * rho_a * wp.dot(u_a, n) * flux

    @wp.kernel(enable_backward=False, module="unique")
    def evaluate_repulsion(model: int, k_coef: scalar, beta: scalar, d: scalar, r0: scalar, inv_h: scalar,
                           mass: scalar, points: wp.array(dtype=vec), wall: wp.array(dtype=vec),
                           acc: wp.array(dtype=vec), energy: wp.array(dtype=scalar)):
        i = wp.tid()
        a = vec(scalar(0.0))
        e = scalar(0.0)
        for j in range(wall.shape[0]):
            r_ab = points[i] - wall[j]
            r = wp.length(r_ab)
            if model == LENNARD_JONES:
                a += lennard_jones(k_coef, r0, r_ab, r)
                e += lennard_jones_potential(k_coef, r0, r)
            else:
                a += monaghan_kajtar(k_coef, beta, d, inv_h, mass, mass, r_ab, r)
                e += monaghan_kajtar_potential(k_coef, beta, d, inv_h, mass, mass, r)
        acc[i] = a
        energy[i] = e

    return SimpleNamespace(lennard_jones=lennard_jones, monaghan_kajtar=monaghan_kajtar, plane_wall=plane_wall,
                           plane_corners=plane_corners, lennard_jones_potential=lennard_jones_potential,
                           monaghan_kajtar_potential=monaghan_kajtar_potential, evaluate_repulsion=evaluate_repulsion)


def repulsion(boundary: str, points, wall, g: float, depth: float, dx: float, hdx: float = 1.3,
              mk_beta: float = 2.0, dim: int = 2, device: str = None):
    """What the boundary particles at ``wall`` do to a fluid particle (of their mass) at each of
    ``points`` under the repulsive model ``boundary`` (lennard_jones, monaghan_kajtar), with the
    scene's constants (``wall_constants``): (accelerations, the energy per unit mass they store),
    host arrays computed by the device functions in float64."""
    from .config import default_device

    device = device or default_device()
    c = wall_constants(g, depth, dx, mk_beta, dim)
    kern = build(wp.float64).evaluate_repulsion
    pts = wp.array(np.asarray(points, dtype=np.float64), dtype=wp.vec3d, device=device)
    walls = wp.array(np.asarray(wall, dtype=np.float64), dtype=wp.vec3d, device=device)
    acc = wp.zeros(len(pts), dtype=wp.vec3d, device=device)
    energy = wp.zeros(len(pts), dtype=wp.float64, device=device)
    k_coef = c["lj_d"] if boundary == "lennard_jones" else c["mk_k"]
    wp.launch(kern, dim=len(pts), inputs=[BOUNDARY_ID[boundary], k_coef, c["mk_beta"], c["mk_d"], c["lj_r0"],
                                          1.0 / (hdx * dx), 1.0, pts, walls, acc, energy], device=device)
    return acc.numpy(), energy.numpy()
