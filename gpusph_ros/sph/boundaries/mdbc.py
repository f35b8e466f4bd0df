"""Modified dynamic boundary condition, mDBC (English, Rogers, Domínguez, Crespo, Stansby, Lind &
Gómez-Gesteira 2021, Comp. Part. Mech. 9:1-15; DualSPHysics 5.4, ``JSphCpu::InteractionMdbc2CorrectionT2``).

Under plain dynamic boundaries (Crespo et al. 2007) a wall particle's density grows by the
continuity equation only while fluid pushes into it and keeps what it gained, so in a flow the fluid
stands off the wall (about 1.5 h in English et al.'s tests) and the wall's pressure is noisy. mDBC
instead gives each boundary particle, once a step before the first force pass (DualSPHysics with
MdbcCorrector off; the half step inherits it), the density the fluid has at the particle's mirror
image across the wall face (its ghost node, x_g = 2 x_w - x_b, x_w the nearest point of the face):

    A [rho_g, grad rho]^T = [sum_j m_j W_gj, sum_j m_j grad_g W_gj]^T, over its level's fluid j, with
    A = sum_j V_j [W_gj; grad_g W_gj] (x) [1, x_j - x_g],  V_j = m_j / rho_j

(a first-order kernel-corrected sum, Liu & Liu 2006: interpolate.py), solved for rho_g where A is well
conditioned: its determinant at least 1e-3 and its condition number, scaled by dx^2, at most 50;
elsewhere the Shepard density sum m W / sum V W; where the ghost's kernel sum sum V W is a thin
film's (below 0.1) the Shepard sum no lower than rho0; rho0 with no fluid near. The ghost's
pressure is then cloned to the particle with the hydrostatic difference, p_b = p_g + rho0 g.(x_b -
x_g), and the particle takes the Tait density of p_b, within the fluid's density bounds (health.py).
This is DualSPHysics 5.4's improved mDBC (``JSphCpu::InteractionMdbc2CorrectionT2``). The first
formulation extrapolated the density with its gradient, rho_b = rho_g + grad rho . (x_b - x_g), up
to 2.5 dx behind the face: over the thin sheets a jet sends along a wall that gave the wall
pressures down to -0.9 rho U^2 / 2 where the truth is about 0, and the net force on the wall 12%
low (docs/results/wall_pressure.md). In 2D the unused third axis is padded with the identity, so
one 4 x 4 system serves both dimensions.

The ghost node is the particle's mirror image across the scene's nearest wall face (faces.py).

The boundary velocity (English et al. 2021, Section 2.3; DualSPHysics' SlipMode), ``mdbc_slip``:
- ``none``: the wall's own velocity, zero for the fixed walls here (DualSPHysics' default "DBC vel=0");
- ``no_slip``: minus the fluid's Shepard velocity at the ghost, so the velocity is zero at the face;
- ``free_slip``: the ghost velocity with its normal component reversed: no penetration, no shear.
"""

import functools
from types import SimpleNamespace

import warp as wp

from .. import eos, interpolate, kernels, neighbours, state
from . import faces
from .model import BoundaryModel

FLUID = state.FLUID
BOUNDARY = state.BOUNDARY
SLIPS = ("none", "no_slip", "free_slip")  # the run setting mdbc_slip
SLIP_ID = {name: k for k, name in enumerate(SLIPS)}
NO_SLIP, FREE_SLIP = SLIP_ID["no_slip"], SLIP_ID["free_slip"]
# DualSPHysics 5.4's mDBC (JSphCpu::InteractionMdbc2CorrectionT2): below this kernel sum at the ghost
# (a thin film) the Shepard density, floored at rho0
FILM_SUM = 0.1


class Mdbc(BoundaryModel):
    name = "mdbc"
    volume = True

    def prepare(self, solver):
        """The ghost-node offsets, once: the walls do not move."""
        faces.ghost_offsets(solver, solver.ghost)

    def before_forces(self, solver, fields):
        """Once a step, before the first force pass, as DualSPHysics (MdbcCorrector off): the half
        step's boundary particles inherit it through the integrator. With multirate, once each of
        the finest level's steps: each level's walls read their own level's fluid in ``fields``."""
        nl = solver.neighbours
        solver.launch(build(solver.scalar).boundary_state, solver.n,
                      [solver.params, nl.grid, nl.walk, fields, solver.ghost])

    def face_pressure(self, scalar):
        return build(scalar).face_pressure


MODEL = Mdbc()


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    interp = interpolate.build(scalar)
    vec4, mat44, no_sums = interp.vec4, interp.mat44, interp.no_sums
    ghost_term, corrected_density = interp.corrected_term, interp.corrected_density
    occupied, wet_share = interp.occupied, interp.wet_share
    same_level = kernels.build(scalar).same_level
    N = neighbours.grid(scalar)
    Grid, cell_coord, cells_around, cell_around = N.Grid, N.cell_coord, N.cells_around, N.cell_around
    Walk, walk_from, walk_cells, walk_span, walk_at = N.Walk, N.walk_from, N.walk_cells, N.walk_span, N.walk_at
    S = state.build(scalar)
    Params, Fields = S.Params, S.Fields
    E = eos.build(scalar)
    eos_pressure, eos_density = E.pressure, E.density

    @wp.func
    def ghost_density(p: Params, a: mat44, rhs: vec4, h_g: scalar) -> scalar:
        """The fluid's density at the ghost node from its sums (interpolate.py); where the ghost's
        kernel sum is a thin film's (below FILM_SUM) the Shepard sum no lower than rho0; rho0 where
        no fluid is near."""
        if a[0, 0] <= scalar(0.0):
            return p.rho0
        if a[0, 0] < scalar(FILM_SUM):
            return wp.max(p.rho0, rhs[0] / a[0, 0])
        return corrected_density(p, a, rhs, h_g)

    @wp.func
    def cloned_pressure(p: Params, rho_g: scalar, d: vec) -> scalar:
        """The pressure at x_g + d: the ghost node's plus the hydrostatic difference across d,
        p_g + rho0 g.d (pressure cloning; the walls do not accelerate)."""
        return eos_pressure(rho_g, p.rho0, p.eos_b, p.gamma) + p.rho0 * wp.dot(p.gravity, d)

    @wp.kernel(enable_backward=False, module="unique")
    def boundary_state(p: Params, grid: Grid, nb: Walk,
                       f: Fields, ghost: wp.array(dtype=vec), chunk: int, stride: int):
        """Each boundary particle's density (and velocity, with a slip mode) from its ghost node,
        over its neighbour list (which holds the fluid near the ghost node: neighbours.py)."""
        i = wp.tid() * stride + chunk
        if f.ptype[i] != BOUNDARY:
            return
        off = ghost[i]
        xg = f.pos[i] + off
        a, rhs, u = no_sums()
        h_g = f.hsml[i]
        cell_i, reach_i = walk_from(grid, nb, i)
        for w in range(walk_cells(reach_i)):
            span = walk_span(grid, nb, i, cell_i, reach_i, w)
            for slot in range(span[0], span[1]):
                j = walk_at(grid, nb, i, slot)
                if j >= 0:
                    # a slot vacated this step may still be listed (levels.py)
                    if state.carries_fluid(f.ptype[j]) and same_level(p, h_g, f.hsml[j]):
                        a, rhs, u = ghost_term(p, grid, f, xg, h_g, j, a, rhs, u)
        f.rho[i] = eos_density(cloned_pressure(p, ghost_density(p, a, rhs, h_g), -off), p.rho0, p.eos_b, p.gamma,
                               p.rho_min, p.rho_max)
        u_b = vec(scalar(0.0))
        if a[0, 0] > scalar(0.0):
            u_g = u / a[0, 0]
            if p.mdbc_slip == NO_SLIP:
                u_b = -u_g
            elif p.mdbc_slip == FREE_SLIP:
                n = off / wp.length(off)
                u_b = u_g - scalar(2.0) * wp.dot(u_g, n) * n
        f.vel[i] = u_b

    @wp.kernel(enable_backward=False, module="unique")
    def face_pressure(p: Params, grid: Grid, start: wp.array(dtype=wp.int32), end: wp.array(dtype=wp.int32),
                      order: wp.array(dtype=wp.int32), f: Fields, points: wp.array(dtype=vec),
                      normals: wp.array(dtype=vec), spacing: wp.array(dtype=scalar), pressure: wp.array(dtype=scalar),
                      weight: wp.array(dtype=scalar)):
        """The pressure on a wall face at each point (inward normal n): the ghost node's pressure, one
        spacing in front of the face, cloned to the face as mDBC clones it to its boundary particles;
        0, with weight 0, where no fluid is near. Each point reads at its own spacing (the level that is
        the flow where it stands: levels.spacing_at).
        A measurement: the fluid is found through the cell grid (``order`` maps its slots)."""
        k = wp.tid()
        off = spacing[k] * normals[k]
        h_g = p.h * spacing[k] / p.dx  # a point reads at its own spacing
        xg = points[k] + off
        a, rhs, u = no_sums()
        ci = cell_coord(grid, xg)
        for c in range(cells_around(grid)):
            cell = cell_around(grid, ci, c)
            if cell >= 0:
                for s in range(start[cell], end[cell]):
                    if f.ptype[order[s]] == FLUID:
                        a, rhs, u = ghost_term(p, grid, f, xg, h_g, order[s], a, rhs, u)
        weight[k] = a[0, 0]
        pressure[k] = scalar(0.0)
        if a[0, 0] > scalar(0.0):
            # weighted by the wet share at the face, as the extrapolated-pressure wall's reading
            # (adami.py): the ghost's Shepard-normalised sums fill a dry part of the support
            fluid = scalar(0.0)
            wall = scalar(0.0)
            cf = cell_coord(grid, points[k])
            for c in range(cells_around(grid)):
                cell = cell_around(grid, cf, c)
                if cell >= 0:
                    for s in range(start[cell], end[cell]):
                        fluid, wall = occupied(p, grid, f, points[k], h_g, order[s], fluid, wall)
            pressure[k] = wet_share(fluid, wall) * cloned_pressure(p, ghost_density(p, a, rhs, h_g), -off)

    return SimpleNamespace(boundary_state=boundary_state,
                           face_pressure=face_pressure)
