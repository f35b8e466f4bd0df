"""Refinement levels coupled through passive particles: adaptive particle refinement, APR (Barcarolo,
Le Touzé, Oger & de Vuyst 2014, JCP 273:640-657; Chiron, Oger, de Leffe & Le Touzé 2018, JCP
354:552-575).

Each refinement level is a particle set of one spacing, and a particle interacts only with
particles of its own level (kernels.same_level), so every sum an active particle takes is over one
spacing and keeps the consistency of a uniform run: no zeroth-order error where the spacing jumps.
A level reaches past its region through its passive particles (state.PASSIVE): the coarse level's
particles inside a finer zone and the fine level's in a band one kernel support wide outside it.
Their own level reads them as fluid; they have no rates of their own. Before each force pass a
passive particle takes the density and velocity of the level that is active where it stands, by
the first-order corrected interpolation of interpolate.py over that level's active particles
(Chiron et al. 2018, Section 3: the passive particles' fields interpolated from the other level),
and it moves with that velocity.

What this gives up: across an interface momentum passes by interpolation, not by pair forces, so it
is conserved to the interpolation's accuracy, not to round-off; mass is each level's active
particles', exact while no particle changes level.
"""

import functools
from types import SimpleNamespace

import warp as wp

from . import interpolate, kernels, neighbours, state

FLUID = state.FLUID
PASSIVE = state.PASSIVE


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    vec4 = wp.types.vector(4, scalar)
    mat44 = wp.types.matrix((4, 4), scalar)
    same_level = kernels.build(scalar).same_level
    interp = interpolate.build(scalar)
    corrected_term, corrected_density = interp.corrected_term, interp.corrected_density
    Grid = neighbours.grid(scalar).Grid
    S = state.build(scalar)
    Params, Fields = S.Params, S.Fields

    @wp.kernel(enable_backward=False, module="unique")
    def passive_state(p: Params, grid: Grid, nbr: wp.array(dtype=wp.int32), count: wp.array(dtype=wp.int32),
                      f: Fields, chunk: int, stride: int):
        """Each passive particle's density (first order, within the fluid's bounds) and velocity
        (Shepard) from the active fluid of the other levels in its list; unchanged where none is
        near."""
        i = wp.tid() * stride + chunk
        if f.ptype[i] != PASSIVE:
            return
        h_i = f.hsml[i]
        x = f.pos[i]
        a = mat44(scalar(0.0))
        rhs = vec4(scalar(0.0))
        u = vec(scalar(0.0))
        base = i * grid.max_neighbours
        for k in range(count[i]):
            j = nbr[base + k]
            if f.ptype[j] == FLUID and not same_level(p, h_i, f.hsml[j]):
                a, rhs, u = corrected_term(p, grid, f, x, h_i, j, a, rhs, u)
        if a[0, 0] > scalar(0.0):
            f.rho[i] = wp.clamp(corrected_density(p, a, rhs, h_i), p.rho_min, p.rho_max)
            f.vel[i] = u / a[0, 0]

    return SimpleNamespace(passive_state=passive_state)
