"""Where a wall particle's face is: its mirror image across the nearest face of the scene's walls
(mDBC's ghost node, mdbc.py) and that face's inward unit normal (the walls' term of the continuity
equation under ``wall_flux: normal``, density.py), from the scene's geometry, which is boxes, once
at the start: the walls do not move.

A tank wall particle (outside the tank) mirrors through the nearest point of the tank's inside, a
corner particle through the corner (so that its offset is along the mean of its faces' normals, as
DualSPHysics' corner normals are). An obstacle's particle (inside its solid box) mirrors through its nearest
face, or through the edge or corner where two or three faces tie, leaving out the faces that lie on
the tank's floor or walls, which face no fluid, and those across a periodic axis, which the
obstacle does not have: a plate across a periodic tank had its particles near the period's ends
mirrored sideways out of the fluid.
"""
import functools
from types import SimpleNamespace

import warp as wp

from .. import state

BOUNDARY = state.BOUNDARY


def ghost_offsets(solver, out):
    """Each of the solver's boundary particles' ghost-node offset x_g - x_b into ``out`` (mdbc.py)."""
    _launch(solver, 0, out)


def normals(solver, out):
    """Each of the solver's boundary particles' face normal into ``out`` (``wall_flux: normal``)."""
    _launch(solver, 1, out)


def _launch(solver, unit: int, out):
    wp.launch(build(solver.scalar).offsets, dim=solver.n, inputs=[solver.params, solver.pos, solver.ptype,
                                                                  solver.body, solver.solid_lo, solver.solid_hi,
                                                                  unit, out], device=solver.device)


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    Params = state.build(scalar).Params

    @wp.func
    def ghost_offset(p: Params, x: vec, body: int, solid_lo: wp.array(dtype=vec),
                     solid_hi: wp.array(dtype=vec)) -> vec:
        """x_g - x_b for the boundary particle at x (``body`` its obstacle, -1 for the tank)."""
        off = vec(scalar(0.0))
        if body < 0:
            for ax in range(3):
                off[ax] = scalar(2.0) * (wp.clamp(x[ax], p.wall_lo[ax], p.wall_hi[ax]) - x[ax])
            return off
        lo = solid_lo[body]
        hi = solid_hi[body]
        nearest = scalar(1.0e30)
        for ax in range(p.dim):
            if p.periodic[ax] == 0:
                if lo[ax] > p.wall_lo[ax]:
                    nearest = wp.min(nearest, x[ax] - lo[ax])
                if hi[ax] < p.wall_hi[ax]:
                    nearest = wp.min(nearest, hi[ax] - x[ax])
        tie = nearest + scalar(1.0e-3) / p.inv_h
        for ax in range(p.dim):
            if p.periodic[ax] == 0:
                if lo[ax] > p.wall_lo[ax] and x[ax] - lo[ax] <= tie:
                    off[ax] = scalar(-2.0) * (x[ax] - lo[ax])
                elif hi[ax] < p.wall_hi[ax] and hi[ax] - x[ax] <= tie:
                    off[ax] = scalar(2.0) * (hi[ax] - x[ax])
        return off

    @wp.kernel(enable_backward=False, module="unique")
    def offsets(p: Params, pos: wp.array(dtype=vec), ptype: wp.array(dtype=wp.int32),
                body: wp.array(dtype=wp.int32), solid_lo: wp.array(dtype=vec), solid_hi: wp.array(dtype=vec),
                unit: int, out: wp.array(dtype=vec)):
        """x_g - x_b of every boundary particle, or with ``unit`` its face's inward unit normal (the
        mean of its faces' at an edge or a corner); zero for the fluid and for an obstacle's
        particle whose faces all lie on the tank's walls."""
        i = wp.tid()
        out[i] = vec(scalar(0.0))
        if ptype[i] == BOUNDARY:
            off = ghost_offset(p, pos[i], body[i], solid_lo, solid_hi)
            if unit == 0:
                out[i] = off
            elif wp.length(off) > scalar(0.0):
                out[i] = wp.normalize(off)

    return SimpleNamespace(offsets=offsets)
