"""Density treatments: the continuity equation, delta-SPH diffusion, the Shepard filter.

- continuity: thesis Eq. 2.11, drho_a/dt = sum_b m_b u_ab . grad_a W_ab.
- delta: density diffusion of Molteni & Colagrossi 2009 (delta = 0.1) with the (linearised) hydrostatic
  correction of Fourtakas et al. 2019 (DualSPHysics' DDT type 2), so that the diffusion does not
  erode the hydrostatic density gradient of a tank at rest:
  D_a = delta h c0 sum_b 2 ((rho_b - rho_a) - rho^H_ba) (r_ba . grad_a W_ab) / (r^2 + 0.01 h^2) V_b.
- Shepard filter: thesis Eq. 2.28, rho_a = sum_b m_b W_ab / sum_b (m_b / rho_b) W_ab. It is a
  normalised sum, so a lattice whose plain kernel sum is not 1 leaves a uniform density unchanged.
  The particle itself is included; boundary neighbours count only when they carry a density
  (dynamic boundaries).
"""

import functools
from types import SimpleNamespace

import warp as wp

from . import kernels, neighbours, state

DIFFUSIONS = ("none", "delta")  # the run setting ``density_diffusion``
DENSITY_DIFFUSION_ID = {name: k for k, name in enumerate(DIFFUSIONS)}
WALL_FLUXES = ("full", "normal")  # the run setting ``wall_flux``
WALL_FLUX_ID = {name: k for k, name in enumerate(WALL_FLUXES)}
FLUID = state.FLUID
BOUNDARY = state.BOUNDARY


def params(cfg) -> dict:
    """The Params field of the density treatment of ``cfg`` (a SolverConfig): delta h c0, 0 when
    diffusion is off (the Shepard filter's period is the solver's)."""
    return {"delta_hc0": cfg.delta * cfg.h * cfg.sound_speed if DENSITY_DIFFUSION_ID[cfg.density_diffusion] else 0.0,
            "wall_flux": WALL_FLUX_ID[cfg.wall_flux]}


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    K = kernels.build(scalar)
    kernel_w, smoothing, same_level = K.w, K.smoothing, K.same_level
    S = state.build(scalar)
    Params, Fields = S.Params, S.Fields
    N = neighbours.grid(scalar)
    Grid, separation = N.Grid, N.separation
    Walk, walk_from, walk_cells, walk_span, walk_at = N.Walk, N.walk_from, N.walk_cells, N.walk_span, N.walk_at

    @wp.func
    def continuity(m_b: scalar, u_ab: vec, grad: vec) -> scalar:
        return m_b * wp.dot(u_ab, grad)

    @wp.func
    def wall_flux(u_ab: vec, n_a: vec) -> vec:
        """The relative velocity a wall particle's term of the continuity equation takes: its part
        along n_a, the normal of the flat wall face under the fluid particle a (``wall_flux:
        normal``, passes.wall_normal_at), or all of it where n_a is zero (``wall_flux: full``, and
        near an edge or a corner)."""
        if wp.length_sq(n_a) == scalar(0.0):
            return u_ab
        return wp.dot(u_ab, n_a) * n_a

    @wp.func
    def delta_diffusion(delta_hc0: scalar, rho_a: scalar, rho_b: scalar, m_b: scalar, r_ab: vec,
                        grad: vec, r2_eta: scalar, gravity: vec, rho0: scalar, c0: scalar) -> scalar:
        """``r2_eta`` = r^2 + 0.01 h^2."""
        # hydrostatic density difference rho^H_b - rho^H_a for b at r_b = r_a - r_ab, the Tait law
        # linearised (Fourtakas et al. 2019): rho0 g.(r_b - r_a) / c0^2
        rho_h = rho0 * wp.dot(gravity, -r_ab) / (c0 * c0)
        psi = scalar(2.0) * ((rho_b - rho_a) - rho_h) * wp.dot(-r_ab, grad) / r2_eta
        return delta_hc0 * psi * m_b / rho_b

    @wp.func
    def shepard(p: Params, grid: Grid, nb: Walk, i: int,
                f: Fields) -> scalar:
        """The Shepard density of particle i over its neighbour list (the walls' particles too
        where they carry a fluid volume)."""
        h, inv_h, norm, scale = smoothing(p, f.hsml[i], f.hsml[i])
        w0 = kernel_w(p.kernel, norm, inv_h, scalar(0.0))
        num = f.mass[i] * w0
        den = f.mass[i] / f.rho[i] * w0
        cell_i, reach_i = walk_from(grid, nb, i)
        for w in range(walk_cells(reach_i)):
            span = walk_span(grid, nb, i, cell_i, reach_i, w)
            for slot in range(span[0], span[1]):
                j = walk_at(grid, nb, i, slot)
                if j >= 0:
                    # the lists may still hold a particle excluded this step
                    t_j = f.ptype[j]
                    if (state.carries_fluid(t_j) or (p.wall_volume != 0 and t_j == BOUNDARY)) \
                            and same_level(p, f.hsml[i], f.hsml[j]):
                        h, inv_h, norm, scale = smoothing(p, f.hsml[i], f.hsml[j])
                        wk = kernel_w(p.kernel, norm, inv_h, wp.length(separation(grid, f.pos[i], f.pos[j])))
                        num += f.mass[j] * wk
                        den += f.mass[j] / f.rho[j] * wk
        return num / den

    return SimpleNamespace(continuity=continuity, wall_flux=wall_flux, delta_diffusion=delta_diffusion, shepard=shepard)
