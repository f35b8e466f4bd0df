"""Extrapolated-pressure wall particles: Adami, Hu & Adams 2012, "A generalized wall boundary
condition for smoothed particle hydrodynamics", J. Comput. Phys. 231, 7057-7075, Eq. 27-28 (GPUSPH's
``DUMMY_BOUNDARY``, TrixiParticles' ``AdamiPressureExtrapolation``, PySPH's ``SolidWallPressureBC``).

Before each force evaluation (the half step's too), every wall particle w takes the pressure of the
fluid f around it, a Shepard mean carried to w with the force balance across the wall:

    p_w = [sum_f p_f W_wf + (g - a_w) . sum_f rho_f r_wf W_wf] / sum_f W_wf,    r_wf = x_w - x_f

(Eq. 27; a_w the wall's acceleration: a moving body's, sph/bodies.py, else zero), over the fluid of
its own refinement level, p_f from the fluid's density by the Tait law; and the density whose Tait
pressure that is (Eq. 28's role, here the inverse of thesis Eq. 2.12), within the fluid's density
bounds. A wall particle with no fluid in its support keeps rho0 (p = 0). A negative extrapolated
pressure is clamped to 0 (ambient): a wall that pulls holds the thin sheets running along it by their
tension, and without a wall friction their particles rattle against it; on the impinging jet
(docs/results/wall_pressure.md) the wall force's scatter from step to step fell from 4.3 to 0.43
times its mean with the clamp, and the sheets no longer wrapped round the wall's ends.
The fluid then sees the wall through the ordinary pressure and viscous terms, as under dynamic
boundaries, with no density diffusion across the wall (passes.pair diffuses between fluid only).
The wall's velocity is its own (a moving body's, else zero): the viscous term is the fluid-wall artificial viscosity of
the other particle walls, not Adami's extrapolated no-slip velocity. A wall is a kernel support of
layers deep.

Nothing but the fluid's pressure holds the fluid out of such a wall, and where a thin, fast layer
runs along it (a bore's front over a floor, the flow round a body after an impact) that pressure is
near zero: particles went through (a 3D bore between plane walls lost 1.2% of its fluid, 13
particles through its particle floor). So each wall particle also pushes a fluid particle that
approaches it within 0.6 spacings with the Lennard-Jones force (thesis Eq. 2.24, r0 = 0.6 dx;
boundaries.backstop), as the planes push within half a spacing. The fluid of an ordinary flow stands
no nearer than 0.71 spacings to a wall particle (the closest in `make run`'s job before the impact,
where the fluid hugs the floor), so the force acts only on a particle already on its way between the
wall's particles; the pressures read against the converged reference moved by 1-2 points with it
(docs/results/wall_pressure.md). It acts only while the two approach, so it takes energy out and
never puts any in: as a conservative force it threw out the daughters that a refinement zone spawns
half a fine spacing from a coarse particle hugging the floor, and its energy failed `make run`'s
zoned job at 0.25 s.
"""
import functools
from types import SimpleNamespace

import warp as wp

from .. import eos, interpolate, kernels, neighbours, state
from .model import BoundaryModel

BOUNDARY = state.BOUNDARY


class Adami(BoundaryModel):
    name = "adami"
    volume = True
    each_evaluation = True
    # no fluid-wall artificial viscosity: on a wall that takes its pressure from the fluid it is a
    # wall friction that made the dam-break surge 0.22 t sqrt(g/H) late and every wall-pressure
    # window low; without it the surge and windows converge on the converged 2D reference
    # (docs/results/wall_reference.md)
    wall_friction = 0.0
    backstop = 0.6

    def before_forces(self, solver, fields):
        nl = solver.neighbours
        solver.launch(build(solver.scalar).boundary_pressure, solver.n,
                      [solver.params, nl.grid, nl.walk, fields])

    def face_pressure(self, scalar):
        return build(scalar).face_pressure


MODEL = Adami()


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    K = kernels.build(scalar)
    kernel_w, smoothing, same_level = K.w, K.smoothing, K.same_level
    N = neighbours.grid(scalar)
    Grid, separation = N.Grid, N.separation
    cell_coord, cells_around, cell_around = N.cell_coord, N.cells_around, N.cell_around
    Walk, walk_from, walk_cells, walk_span, walk_at = N.Walk, N.walk_from, N.walk_cells, N.walk_span, N.walk_at
    S = state.build(scalar)
    Params, Fields = S.Params, S.Fields
    E = eos.build(scalar)
    eos_pressure, eos_density = E.pressure, E.density
    interp = interpolate.build(scalar)
    occupied, wet_share = interp.occupied, interp.wet_share

    @wp.func
    def extrapolated_pressure(p_w_sum: scalar, rho_r_w_sum: vec, w_sum: scalar, g: vec, a_wall: vec) -> scalar:
        """Adami et al. 2012 Eq. 27 from its sums: sum p_f W, sum rho_f r_wf W and sum W over the
        fluid around the wall particle; 0 (ambient) where no fluid is near."""
        if w_sum <= scalar(0.0):
            return scalar(0.0)
        return (p_w_sum + wp.dot(g - a_wall, rho_r_w_sum)) / w_sum

    @wp.func
    def fluid_term(p: Params, grid: Grid, f: Fields, x: vec, h_x: scalar, j: int, p_sum: scalar, rho_r: vec,
                   w_sum: scalar):
        """Particle j's part of Eq. 27's sums at the point x of smoothing length h_x: itself where it
        is fluid of x's level within the support, else nothing."""
        if state.carries_fluid(f.ptype[j]) and same_level(p, h_x, f.hsml[j]):
            r_xf = separation(grid, x, f.pos[j])
            r = wp.length(r_xf)
            h, inv_h, norm, scale = smoothing(p, h_x, f.hsml[j])
            if r < scalar(2.0) * h:
                w = kernel_w(p.kernel, norm, inv_h, r)
                rho_f = f.rho[j]
                p_sum += eos_pressure(rho_f, p.rho0, p.eos_b, p.gamma) * w
                rho_r += rho_f * w * r_xf
                w_sum += w
        return p_sum, rho_r, w_sum

    @wp.kernel(enable_backward=False, module="unique")
    def boundary_pressure(p: Params, grid: Grid, nb: Walk,
                          f: Fields, chunk: int, stride: int):
        """Each boundary particle's density from the pressure extrapolated from its level's fluid."""
        i = wp.tid() * stride + chunk
        if f.ptype[i] != BOUNDARY:
            return
        p_sum = scalar(0.0)
        w_sum = scalar(0.0)
        rho_r = vec(scalar(0.0))
        cell_i, reach_i = walk_from(grid, nb, i)
        for w in range(walk_cells(reach_i)):
            span = walk_span(grid, nb, i, cell_i, reach_i, w)
            for slot in range(span[0], span[1]):
                j = walk_at(grid, nb, i, slot)
                if j >= 0:
                    p_sum, rho_r, w_sum = fluid_term(p, grid, f, f.pos[i], f.hsml[i], j, p_sum, rho_r, w_sum)
        # a wall pushes and never pulls (the module's docstring); a_w: a moving body's (bodies.py)
        pressure = wp.max(extrapolated_pressure(p_sum, rho_r, w_sum, p.gravity, f.wall_acc[i]), scalar(0.0))
        f.rho[i] = eos_density(pressure, p.rho0, p.eos_b, p.gamma, p.rho_min, p.rho_max)

    @wp.kernel(enable_backward=False, module="unique")
    def face_pressure(p: Params, grid: Grid, start: wp.array(dtype=wp.int32), end: wp.array(dtype=wp.int32),
                      order: wp.array(dtype=wp.int32), f: Fields, points: wp.array(dtype=vec),
                      normals: wp.array(dtype=vec), spacing: wp.array(dtype=scalar), pressure: wp.array(dtype=scalar),
                      weight: wp.array(dtype=scalar)):
        """The pressure on a wall face at each point: Eq. 27 at the point itself, the wall's own
        condition read where the face is, times the share of the support's room beside the walls that
        the fluid fills, sum_f V_f W / (1 - sum_w V_w W), at most 1: Eq. 27's Shepard mean carries
        the pressure of the fluid present over the whole support, which is right where the fluid
        meets the wall and wrong where part of the support is dry (air at ambient): a thin tongue
        first touching a face would read its water hammer over a patch 2h around each particle
        (on DamBreak 1 at 3 cm, 3.5 times the impulse that the body's particles received over the
        first contact). Before the wall's clamp (a sensor reads the fluid's tension too; a reading
        clipped at 0 is the caller's choice); 0, with weight 0, where no fluid is near. Each point
        reads at its own spacing (levels.spacing_at). A measurement: the fluid is found through the
        cell grid (``order`` maps its slots)."""
        k = wp.tid()
        x = points[k]
        h_x = p.h * spacing[k] / p.dx
        p_sum = scalar(0.0)
        w_sum = scalar(0.0)
        rho_r = vec(scalar(0.0))
        fluid = scalar(0.0)
        wall = scalar(0.0)
        ci = cell_coord(grid, x)
        for c in range(cells_around(grid)):
            cell = cell_around(grid, ci, c)
            if cell >= 0:
                for s in range(start[cell], end[cell]):
                    p_sum, rho_r, w_sum = fluid_term(p, grid, f, x, h_x, order[s], p_sum, rho_r, w_sum)
                    fluid, wall = occupied(p, grid, f, x, h_x, order[s], fluid, wall)
        weight[k] = w_sum
        pressure[k] = wet_share(fluid, wall) * extrapolated_pressure(p_sum, rho_r, w_sum, p.gravity, vec(scalar(0.0)))

    return SimpleNamespace(extrapolated_pressure=extrapolated_pressure, boundary_pressure=boundary_pressure,
                           face_pressure=face_pressure)
