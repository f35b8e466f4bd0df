"""Extrapolated-pressure wall particles: Adami, Hu & Adams 2012, "A generalized wall boundary
condition for smoothed particle hydrodynamics", J. Comput. Phys. 231, 7057-7075, Eq. 27-28 (GPUSPH's
``DUMMY_BOUNDARY``, TrixiParticles' ``AdamiPressureExtrapolation``, PySPH's ``SolidWallPressureBC``).

Before each force evaluation (the half step's too), every wall particle w takes the pressure of the
fluid f around it, a Shepard mean carried to w with the force balance across the wall:

    p_w = [sum_f p_f W_wf + (g - a_w) . sum_f rho_f r_wf W_wf] / sum_f W_wf,    r_wf = x_w - x_f

(Eq. 27; a_w the wall's acceleration, zero for the fixed walls of a scene today), over the fluid of
its own refinement level, p_f from the fluid's density by the Tait law; and the density whose Tait
pressure that is (Eq. 28's role, here the inverse of thesis Eq. 2.12), within the fluid's density
bounds. A wall particle with no fluid in its support keeps rho0 (p = 0). Negative pressures are kept
(a wall under a receding sheet pulls, as the fluid does); the density bounds are the only clamp.
The fluid then sees the wall through the ordinary pressure and viscous terms, as under dynamic
boundaries, with no density diffusion across the wall (passes.pair diffuses between fluid only).
The wall's velocity is its own (zero): the viscous term is the fluid-wall artificial viscosity of
the other particle walls, not Adami's extrapolated no-slip velocity. A wall is a kernel support of
layers deep.
"""
import functools
from types import SimpleNamespace

import warp as wp

from .. import eos, kernels, neighbours, state
from .model import BoundaryModel

BOUNDARY = state.BOUNDARY


class Adami(BoundaryModel):
    name = "adami"
    volume = True
    each_evaluation = True

    def before_forces(self, solver, fields):
        nl = solver.neighbours
        solver.launch(build(solver.scalar).boundary_pressure, solver.n,
                      [solver.params, nl.grid, nl.nbr, nl.count, fields])


MODEL = Adami()


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    K = kernels.build(scalar)
    kernel_w, smoothing, same_level = K.w, K.smoothing, K.same_level
    N = neighbours.grid(scalar)
    Grid, separation = N.Grid, N.separation
    S = state.build(scalar)
    Params, Fields = S.Params, S.Fields
    E = eos.build(scalar)
    eos_pressure, eos_density = E.pressure, E.density

    @wp.func
    def extrapolated_pressure(p_w_sum: scalar, rho_r_w_sum: vec, w_sum: scalar, g: vec, a_wall: vec) -> scalar:
        """Adami et al. 2012 Eq. 27 from its sums: sum p_f W, sum rho_f r_wf W and sum W over the
        fluid around the wall particle; 0 (rho0) where no fluid is near."""
        if w_sum <= scalar(0.0):
            return scalar(0.0)
        return (p_w_sum + wp.dot(g - a_wall, rho_r_w_sum)) / w_sum

    @wp.kernel(enable_backward=False, module="unique")
    def boundary_pressure(p: Params, grid: Grid, nbr: wp.array(dtype=wp.int32), count: wp.array(dtype=wp.int32),
                          f: Fields, chunk: int, stride: int):
        """Each boundary particle's density from the pressure extrapolated from its level's fluid."""
        i = wp.tid() * stride + chunk
        if f.ptype[i] != BOUNDARY:
            return
        xi = f.pos[i]
        h_i = f.hsml[i]
        p_sum = scalar(0.0)
        w_sum = scalar(0.0)
        rho_r = vec(scalar(0.0))
        base = i * grid.max_neighbours
        for k in range(count[i]):
            j = nbr[base + k]
            if state.carries_fluid(f.ptype[j]) and same_level(p, h_i, f.hsml[j]):
                r_wf = separation(grid, xi, f.pos[j])
                r = wp.length(r_wf)
                h, inv_h, norm, scale = smoothing(p, h_i, f.hsml[j])
                if r < scalar(2.0) * h:
                    w = kernel_w(p.kernel, norm, inv_h, r)
                    rho_f = f.rho[j]
                    p_sum += eos_pressure(rho_f, p.rho0, p.eos_b, p.gamma) * w
                    rho_r += rho_f * w * r_wf
                    w_sum += w
        pressure = extrapolated_pressure(p_sum, rho_r, w_sum, p.gravity, vec(scalar(0.0)))  # fixed walls
        f.rho[i] = eos_density(pressure, p.rho0, p.eos_b, p.gamma, p.rho_min, p.rho_max)

    return SimpleNamespace(extrapolated_pressure=extrapolated_pressure, boundary_pressure=boundary_pressure)
