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
and it moves with that velocity. Two levels or more above the active fluid it reads the passive
particles of the level between (``passive_state``).

Particles change level where they stand, after every committed step (``relevel``): a particle
inside a finer zone is passive; a zone's own particle is active in its zone, passive within its
band (one kernel support, 2 h + half a spacing, outside the zone) and removed beyond it (VACANT);
the scene's level is active everywhere else. An active particle that comes within half its spacing
of a finer level's band gets 2^dim passive daughters on its cell's sub-lattice (``spawn``), once
until it leaves the band's neighbourhood, into slots the build reserved (scenes/refine.py). Fluid
entering a zone so brings its fine particles with it, and fluid leaving one finds the coarse
particles that followed it there. Slots are numbered by prefix sums, not atomics, so a run is
reproducible bit for bit on the CPU.

A wall whose density follows the continuity equation (dynamic boundaries) reads only its level's
active fluid. Inside a finer zone a coarse wall's own fluid is passive, so a coarse wall whose band
reaches into the zone reads the coarse fluid beyond the zone's face only: fluid running past it
there (a run-up leaving a zone along a wall) drew its density down without bound, and the fluid
onto it. Such a wall keeps rho0 or above (``floor_walls``), as DualSPHysics 5.4 keeps every
dynamic wall ("to prevent absorption of fluid particles by boundaries",
JSphCpu::ComputeSymplecticPre). A fine wall near its zone's face reads one side too, but flooring
those lifted the fine side of a still 3D tank by 0.5% of hydrostatic near the surface, and no run
has failed there; every other wall is as a uniform run has it.

What this gives up: across an interface momentum passes by interpolation, not by pair forces, so it
is conserved to the interpolation's accuracy, not to round-off; the active mass changes by what
the levels exchange, as the particles that cross an edge are not each other's exact mass.
"""

import functools
from types import SimpleNamespace

import numpy as np
import warp as wp

from . import interpolate, kernels, neighbours, state

FLUID = state.FLUID
BOUNDARY = state.BOUNDARY
PASSIVE = state.PASSIVE
VACANT = state.VACANT
carries_fluid = state.carries_fluid
FAR = 1.0e30


def band_width(spacing: float, hdx: float) -> float:
    """How far outside its zone a level of ``spacing`` keeps passive particles: its kernel support
    (2 h, h = hdx x spacing) and half its spacing (the build's band, scenes/refine.py)."""
    return 2.0 * hdx * spacing + 0.5 * spacing


def edge_margin(spacing: float, hdx: float) -> float:
    """How far a moving body stays from the faces of a zone of ``spacing``, inside it or out: the
    zone's band and the parent level's kernel support (2 h at twice the spacing). A body is not
    carried across a face: a passive particle follows the fluid of another level and nothing keeps
    it out of a wall, so a body running into a level's band meets particles it has overrun (a 2D
    box pushed into a zone at 0.2 m/s read 2.6 times the drag of a uniform run at the zone's
    spacing and lost a third of its buoyancy, and under multirate the run blew up)."""
    return band_width(spacing, hdx) + 4.0 * hdx * spacing


def spacing_at(points, zones, dx: float) -> np.ndarray:
    """The particle spacing where each point (n x 3) stands: that of the finest zone
    (SolverConfig.zones: lo, hi, spacing) holding it, else the scene's dx. A measurement reads there
    at the level that is the flow."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    out = np.full(len(pts), float(dx))
    for lo, hi, spacing in zones or ():
        inside = np.all((pts >= np.asarray(lo)) & (pts <= np.asarray(hi)), axis=1)
        out[inside] = np.minimum(out[inside], spacing)
    return out


def finest_in(lo, hi, zones, dx: float) -> float:
    """The finest spacing in the box [lo, hi] (3-vectors): the finest zone overlapping it, else dx;
    what a measurement tiling the box (a body's faces, a gauge's line) samples at."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    overlapping = [spacing for z_lo, z_hi, spacing in zones or ()
                   if np.all(lo <= np.asarray(z_hi)) and np.all(hi >= np.asarray(z_lo))]
    return float(min([dx, *overlapping]))


def sub_offsets(k: int, dim: int) -> np.ndarray:
    """The k^dim daughters' offsets from their parent's centre in units of its spacing."""
    c = (np.arange(k) + 0.5) / k - 0.5
    grids = np.meshgrid(*([c] * dim), indexing="ij")
    out = np.zeros((grids[0].size, 3))
    for ax in range(dim):
        out[:, ax] = grids[ax].ravel()
    return out


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    interp = interpolate.build(scalar)
    no_sums, corrected_term, corrected_density = interp.no_sums, interp.corrected_term, interp.corrected_density
    K = kernels.build(scalar)
    same_level, finest_level = K.same_level, K.finest_level
    N = neighbours.grid(scalar)
    Grid = N.Grid
    Walk, walk_from, walk_cells, walk_span, walk_at = N.Walk, N.walk_from, N.walk_cells, N.walk_span, N.walk_at
    S = state.build(scalar)
    Params, Fields = S.Params, S.Fields

    @wp.func
    def box_distance(p: Params, x: vec, lo: vec, hi: vec) -> scalar:
        """The distance from x to the box [lo, hi] over the run's axes (0 inside it)."""
        d2 = scalar(0.0)
        for ax in range(p.dim):
            gap = wp.max(lo[ax] - x[ax], scalar(0.0)) + wp.max(x[ax] - hi[ax], scalar(0.0))
            d2 += gap * gap
        return wp.sqrt(d2)

    @wp.func
    def band(p: Params, h: scalar) -> scalar:
        """``band_width`` on the device, for a level of smoothing length h."""
        return scalar(2.0) * h + scalar(0.5) * h * p.dx * p.inv_h

    @wp.func
    def edge(p: Params, h: scalar) -> scalar:
        """``edge_margin`` on the device, for a zone of smoothing length h."""
        return band(p, h) + scalar(4.0) * h

    @wp.func
    def place(p: Params, x: vec, h_i: scalar, zone_lo: wp.array(dtype=vec), zone_hi: wp.array(dtype=vec),
              zone_h: wp.array(dtype=scalar)):
        """Where a particle of smoothing length h_i at x stands among the zones: (1 inside a finer zone,
        its distance from its own level's nearest zone, its distance beyond the band of the next
        finer level's nearest zone)."""
        finer = int(0)
        own = scalar(FAR)
        child = scalar(FAR)
        for k in range(p.n_zones):
            h_k = zone_h[k]
            d = box_distance(p, x, zone_lo[k], zone_hi[k])
            if h_k < h_i * scalar(0.999):
                if d <= scalar(0.0):
                    finer = 1
                if wp.abs(scalar(2.0) * h_k - h_i) < scalar(0.001) * h_i:
                    child = wp.min(child, d - band(p, h_k))
            elif wp.abs(h_k - h_i) < scalar(0.001) * h_i:
                own = wp.min(own, d)
        return finer, own, child

    @wp.kernel(enable_backward=False, module="unique")
    def passive_state(p: Params, grid: Grid, nb: Walk,
                      f: Fields, zone_lo: wp.array(dtype=vec), zone_hi: wp.array(dtype=vec),
                      zone_h: wp.array(dtype=scalar), level_h: scalar, chunk: int, stride: int):
        """Each passive particle of the level of smoothing length ``level_h``: its density (first
        order, within the fluid's bounds) and velocity (Shepard) from its donors in its list, the
        neighbouring levels' active fluid and the next finer level's passive fluid that stands in a
        zone finer still (the solver runs the levels finest first, so those have their values);
        unchanged where none is near. So a coarse particle two levels above the active fluid reads
        it through the level between, each interpolation across one level, within the support of
        h_ab = 1.5 h of the finer."""
        i = wp.tid() * stride + chunk
        h_i = f.hsml[i]
        if f.ptype[i] != PASSIVE or wp.abs(h_i - level_h) > scalar(0.01) * level_h:
            return
        x = f.pos[i]
        a, rhs, u = no_sums()
        cell_i, reach_i = walk_from(grid, nb, i)
        for w in range(walk_cells(reach_i)):
            span = walk_span(grid, nb, i, cell_i, reach_i, w)
            for slot in range(span[0], span[1]):
                j = walk_at(grid, nb, i, slot)
                if j >= 0:
                    h_j = f.hsml[j]
                    donor = f.ptype[j] == FLUID and not same_level(p, h_i, h_j)
                    if f.ptype[j] == PASSIVE and h_j < h_i * scalar(0.999) and not finest_level(p, h_j):
                        # (the finest level has no zone finer still)
                        finer, own, child = place(p, f.pos[j], h_j, zone_lo, zone_hi, zone_h)
                        donor = finer == 1
                    if donor:
                        a, rhs, u = corrected_term(p, grid, f, x, h_i, j, a, rhs, u)
        if a[0, 0] > scalar(0.0):
            f.rho[i] = wp.clamp(corrected_density(p, a, rhs, h_i), p.rho_min, p.rho_max)
            f.vel[i] = u / a[0, 0]

    @wp.kernel(enable_backward=False, module="unique")
    def mark_spawned(p: Params, pos: wp.array(dtype=vec), hsml: wp.array(dtype=scalar),
                     ptype: wp.array(dtype=wp.int32), zone_lo: wp.array(dtype=vec), zone_hi: wp.array(dtype=vec),
                     zone_h: wp.array(dtype=scalar), spawned: wp.array(dtype=wp.int32)):
        """At the start: the fluid near a finer level's band has its daughters already (the build's)."""
        i = wp.tid()
        spawned[i] = 0
        if carries_fluid(ptype[i]):
            finer, own, child = place(p, pos[i], hsml[i], zone_lo, zone_hi, zone_h)
            if child <= hsml[i] * p.dx * p.inv_h:
                spawned[i] = 1

    @wp.kernel(enable_backward=False, module="unique")
    def relevel(p: Params, pos: wp.array(dtype=vec), hsml: wp.array(dtype=scalar),
                ptype: wp.array(dtype=wp.int32), needs_list: wp.array(dtype=wp.int32),
                zone_lo: wp.array(dtype=vec), zone_hi: wp.array(dtype=vec), zone_h: wp.array(dtype=scalar),
                spawned: wp.array(dtype=wp.int32), want: wp.array(dtype=wp.int32), vacant: wp.array(dtype=wp.int32)):
        """Each fluid particle's kind from where it stands; ``want`` the active ones to give
        daughters, ``vacant`` the free slots.

        No change of kind makes the lists stale: a particle is removed two spacings past its band,
        beyond every active particle's list, and a particle turned passive keeps its values until
        the next build lists the other level for it."""
        i = wp.tid()
        want[i] = 0
        vacant[i] = 0
        t = ptype[i]
        if t == VACANT:
            vacant[i] = 1
            return
        if not carries_fluid(t):
            return
        h_i = hsml[i]
        s_i = h_i * p.dx * p.inv_h
        finer, own, child = place(p, pos[i], h_i, zone_lo, zone_hi, zone_h)
        kind = FLUID
        if finer != 0:
            kind = PASSIVE
        elif h_i < p.h * scalar(0.999) and own > scalar(0.0):
            kind = PASSIVE
            if own > band(p, h_i) + scalar(2.0) * s_i:  # past where a parent's daughters are made
                kind = VACANT
        ptype[i] = kind
        if kind == VACANT:
            needs_list[i] = 0
            vacant[i] = 1
            return
        if child > scalar(2.0) * s_i:  # its last daughters are gone: a return makes new ones
            spawned[i] = 0
        elif kind == FLUID and spawned[i] == 0 and child <= scalar(0.5) * s_i:
            want[i] = 1

    @wp.kernel(enable_backward=False, module="unique")
    def floor_walls(p: Params, pos: wp.array(dtype=vec), hsml: wp.array(dtype=scalar),
                    ptype: wp.array(dtype=wp.int32), rho: wp.array(dtype=scalar), zone_lo: wp.array(dtype=vec),
                    zone_hi: wp.array(dtype=vec), zone_h: wp.array(dtype=scalar)):
        """Each dynamic wall particle whose level's band reaches into a finer zone: its density no
        lower than rho0 (the module's docstring)."""
        i = wp.tid()
        h_i = hsml[i]
        if ptype[i] != BOUNDARY or p.wall_continuity == 0:
            return
        for k in range(p.n_zones):
            if zone_h[k] < h_i * scalar(0.999) and box_distance(p, pos[i], zone_lo[k], zone_hi[k]) < band(p, h_i):
                rho[i] = wp.max(rho[i], p.rho0)
                return

    @wp.kernel(enable_backward=False, module="unique")
    def bodies_off_edges(p: Params, pos: wp.array(dtype=vec), ptype: wp.array(dtype=wp.int32),
                         body: wp.array(dtype=wp.int32), moves: wp.array(dtype=wp.int32),
                         ids: wp.array(dtype=wp.int32), zone_lo: wp.array(dtype=vec), zone_hi: wp.array(dtype=vec),
                         zone_h: wp.array(dtype=scalar), fail: wp.array(dtype=wp.int32), fail_slot: int):
        """Flags ``fail_slot`` with a moving body's particle within ``edge_margin`` of a zone's
        face, from inside (its open faces, beyond the tank, far) or from outside."""
        i = wp.tid()
        b = body[i]
        if b < 0 or ptype[i] != BOUNDARY:
            return
        if moves[b] == 0:
            return
        x = pos[i]
        for k in range(p.n_zones):
            d = box_distance(p, x, zone_lo[k], zone_hi[k])
            if d <= scalar(0.0):
                d = scalar(FAR)
                for ax in range(p.dim):
                    d = wp.min(d, wp.min(x[ax] - zone_lo[k][ax], zone_hi[k][ax] - x[ax]))
            if d < edge(p, zone_h[k]):
                wp.atomic_min(fail, fail_slot, ids[i])

    @wp.kernel(enable_backward=False, module="unique")
    def free_slots(vacant: wp.array(dtype=wp.int32), vacant_rank: wp.array(dtype=wp.int32),
                   free: wp.array(dtype=wp.int32)):
        """free[r] = the r-th vacant slot."""
        j = wp.tid()
        if vacant[j] != 0:
            free[vacant_rank[j]] = j

    @wp.kernel(enable_backward=False, module="unique")
    def spawn(p: Params, want: wp.array(dtype=wp.int32), want_rank: wp.array(dtype=wp.int32),
              vacant: wp.array(dtype=wp.int32), vacant_rank: wp.array(dtype=wp.int32), free: wp.array(dtype=wp.int32),
              offsets: wp.array(dtype=vec), pos: wp.array(dtype=vec), vel: wp.array(dtype=vec),
              rho: wp.array(dtype=scalar), mass: wp.array(dtype=scalar), hsml: wp.array(dtype=scalar),
              ptype: wp.array(dtype=wp.int32), body: wp.array(dtype=wp.int32), needs_list: wp.array(dtype=wp.int32),
              spawned: wp.array(dtype=wp.int32), ids: wp.array(dtype=wp.int32), x_build: wp.array(dtype=vec),
              fail: wp.array(dtype=wp.int32), fail_slot: int):
        """Each wanting particle's 2^dim passive daughters, into the free slots in rank order; a
        particle finding too few left flags ``fail_slot``. The daughters, made past every active
        particle's list, join the lists at their next build, which their ``x_build`` does not
        hasten."""
        i = wp.tid()
        if want[i] == 0:
            return
        n = want.shape[0]
        count = offsets.shape[0]
        base = want_rank[i] * count
        if base + count > vacant_rank[n - 1] + vacant[n - 1]:
            wp.atomic_min(fail, fail_slot, ids[i])
            return
        s_i = hsml[i] * p.dx * p.inv_h
        for q in range(count):
            j = free[base + q]
            pos[j] = pos[i] + s_i * offsets[q]
            vel[j] = vel[i]
            rho[j] = rho[i]
            mass[j] = mass[i] / scalar(count)
            hsml[j] = scalar(0.5) * hsml[i]
            ptype[j] = PASSIVE
            body[j] = -1
            needs_list[j] = 1
            spawned[j] = 0
            x_build[j] = pos[j]
        spawned[i] = 1

    return SimpleNamespace(passive_state=passive_state, mark_spawned=mark_spawned, relevel=relevel,
                           floor_walls=floor_walls, bodies_off_edges=bodies_off_edges, free_slots=free_slots,
                           spawn=spawn)
