"""Neighbour search: a uniform grid of cells one list radius wide, built by a sort of cell keys
(Warp's radix sort), then either one fixed-width neighbour list per particle (as GPUSPH keeps) or
no list at all, every pass walking the cells around a particle (as DualSPHysics does). Every pass
meets a particle's neighbours through one walk (``Walk``: walk_from, walk_cells, walk_span,
walk_at), whichever the search. (Half-width cells searched two each way test 40% fewer candidates
but visit 125 cells instead of 27, and measured slower on a CPU.)

Lists cost 4 B an entry, 168 entries a particle in 3D (of 937 B a particle on DamBreak 1), and are
read by each pass at one index a neighbour; walks hold nothing (253 B a particle) and test every
candidate of the 27 cells, about 6 times the listed pairs, in each pass: 2.5 times the time on a CPU,
where the lists are the default; on a GPU, where memory bounds the run, the walks are
(``config.cell_walks``; docs/results/speed.md). A walk tests each candidate as the lists' build
does, on the particles as they stood at the last sort (their positions, kinds, h and whether they
need a list, copied then), so it meets the pairs a list would hold, in its order: a run steps bit
for bit the same either way.

The lists reach list_skin x the kernel support and are Verlet lists: they are rebuilt only once
some particle, where the next step's force passes will read it, would be more than half the skin
from where it was at the last build, which the device decides by itself: the sort and the build
are a branch of the step on the device's stale flag (``wp.capture_if``: a conditional node of a
captured graph, the flag read in place on a CPU), so no step waits for the host and an ordinary
step sorts nothing. A reorder (solver.py) builds from its own sort.

Periodic axes wrap both the cell search and the separation vector (minimum image).

The lists' width is measured (Solver): a first build into lists one long counts the longest list,
and the lists are then WIDTH_MARGIN times that (the plan prices them at the lattice's estimate,
``default_max_neighbours``, the most they may widen to).
A build that finds a longer list stops its step before any pass writes the state (the loop's
LISTS_HOLD flag, a health flag); the solver widens the lists to WIDTH_MARGIN times the longest and
takes the step again, the same step, so that a run is bit for bit the run of lists wide enough from
the start. They are widened no further than the lattice's estimate: a list longer than that is
clumped particles, not a flow, and the run stops (NeighbourOverflow), as it does when the caller
fixed the width.

Where particles differ in smoothing length (refinement levels, levels.py) the cells are sized by
the smallest and a particle searches as many cells each way as its own list radius needs (a passive
one, the largest's): sized by the largest, a fine particle tested 8x the candidates of a uniform
fine run in 3D, and the list builds took as long as the uniform fine run's. A particle lists its own
level's particles and a passive one its donors too (the neighbouring levels' active fluid and the
next finer level's passive fluid: levels.passive_state), each pair within list_skin x its own
support 2 h_ab (kernels.smoothing), and the lists go stale by the skin of the smallest: a fine
particle's list is as long as in a uniform fine run.
"""

import functools
import math
from types import SimpleNamespace

import numpy as np
import warp as wp

from .state import BOUNDARY, DT, FLUID, PASSIVE, VACANT, carries_fluid

# lists reach LIST_SKIN kernel supports; a list stays valid until some particle has moved half the
# difference since it was built (a Verlet list)
LIST_SKIN = 1.1
# how far ahead of its committed position a particle's next step reads it, in |u| dt: the half step
# (1/2) and, where a launched step spans two of the finest level's (multirate), 3/2; with room for
# the step growing, the acceleration, XSPH and shifting
LOOKAHEAD_SAFETY = 1.5
# a list's width over the longest list the last count measured (at the start, or the build that
# overflowed): 1.6 times the longest at rest held every uniform run measured over its whole course
# (DamBreak 1 at 3 cm: 102 at rest, 133 at most; docs/results/speed.md)
WIDTH_MARGIN = 1.6


def measured_width(longest: int) -> int:
    """The lists' width for a longest list of ``longest``: WIDTH_MARGIN times it, a multiple of 8."""
    return int(8 * math.ceil(WIDTH_MARGIN * max(longest, 1) / 8))


def list_skin(substeps: int = 1) -> float:
    """The list radius over the kernel support where one launched step spans ``substeps`` steps
    of the finest level (2 with multirate): LIST_SKIN's skin for each. Measured on DamBreak 1's
    zoned run after the impact: multirate's lists, read over two steps, were rebuilt at every
    launch with a skin of 0.1 and at one in 2.7 with 0.2 (12 s against 13.5 s for 0.1 s); the
    uniform run is faster with 0.1 (28.6 s against 31.5 s)."""
    return 1.0 + (LIST_SKIN - 1.0) * substeps


def shortest_period(h: float, substeps: int = 1) -> float:
    """The shortest periodic axis for smoothing length h: the cell search wraps one cell (a list
    radius, list_skin x 2h) each way, so a period must hold three whole cells."""
    return 3 * list_skin(substeps) * 2.0 * h


def default_max_neighbours(dim: int, hdx: float, finest: float = 1.0, substeps: int = 1) -> int:
    """Room for 2.5x the neighbours of a uniform lattice (a wall of finer boundary particles adds
    fewer than the half-support of fluid it replaces). With refinement (``finest`` < 1, levels
    halving the spacing) the longest list is a passive coarse particle's among the next level's
    active fluid: its pairs reach 2 x 1.5 h of theirs."""
    if finest < 1.0:
        hdx = 1.5 * hdx
    radius = list_skin(substeps) * 2.0 * hdx
    expected = (4.0 / 3.0 * math.pi * radius ** 3) if dim == 3 else (math.pi * radius ** 2)
    return int(8 * math.ceil(2.5 * expected / 8))


class NeighbourOverflow(RuntimeError):
    """More neighbours than the list holds (particles clumped or the list is too narrow)."""


@functools.lru_cache(maxsize=None)
def grid(scalar):
    """The cell grid (a struct) and the functions that find a point's cell, a cell's neighbours and
    the separation of two points (minimum image on periodic axes): what every neighbour loop needs."""
    vec = wp.types.vector(3, scalar)

    @wp.struct
    class Grid:
        lo: vec
        length: vec  # domain extent, the period on periodic axes
        inv_cell: vec
        dims: wp.vec3i
        periodic: wp.vec3i
        any_periodic: int
        reach: int  # cells searched each way along an axis (by the largest h)
        reach_z: int  # 0 in 2D: one layer of cells
        radius2: scalar  # squared list radius (support plus skin)
        variable: int  # 1: a pair's radius is radius2 x (h_ab / h)^2 (refinement zones)
        inv_h2: scalar  # 1 / h^2 of the largest h
        inv_h_min: scalar  # 1 / the smallest h, whose list radius the cells are wide
        half_skin: scalar  # how far a particle may be from its build position where a pass reads it
        lookahead: scalar  # how far ahead of its committed position the next step reads it, in |u| dt
        max_neighbours: int

    @wp.func
    def separation(grid: Grid, xa: vec, xb: vec) -> vec:
        """x_a - x_b, by the minimum image on periodic axes."""
        r = xa - xb
        if grid.any_periodic == 0:
            return r
        for ax in range(3):
            if grid.periodic[ax] != 0:
                r[ax] = r[ax] - grid.length[ax] * wp.round(r[ax] / grid.length[ax])
        return r

    @wp.func
    def cell_coord(grid: Grid, x: vec) -> wp.vec3i:
        c = wp.vec3i(0, 0, 0)
        for ax in range(3):
            k = int(wp.floor((x[ax] - grid.lo[ax]) * grid.inv_cell[ax]))
            c[ax] = wp.clamp(k, 0, grid.dims[ax] - 1)
        return c

    @wp.func
    def wrap_cell(grid: Grid, ax: int, c: int) -> int:
        """The cell index c along axis ax, wrapped on a periodic axis; -1 outside the grid."""
        if c >= 0 and c < grid.dims[ax]:
            return c
        if grid.periodic[ax] != 0:
            return (c + grid.dims[ax]) % grid.dims[ax]
        return -1

    @wp.func
    def neighbour_cell(grid: Grid, ci: wp.vec3i, dx: int, dy: int, dz: int) -> int:
        """The flat index of the cell at offset (dx, dy, dz) from cell ci, or -1 off the grid."""
        cx = wrap_cell(grid, 0, ci[0] + dx)
        cy = wrap_cell(grid, 1, ci[1] + dy)
        cz = wrap_cell(grid, 2, ci[2] + dz)
        if cx < 0 or cy < 0 or cz < 0:
            return -1
        return (cz * grid.dims[1] + cy) * grid.dims[0] + cx

    @wp.func
    def cells_around(grid: Grid) -> int:
        """How many cells a point's search visits: ``reach`` each way (``reach_z`` on z)."""
        side = 2 * grid.reach + 1
        return side * side * (2 * grid.reach_z + 1)

    @wp.func
    def adjacent_levels(h_a: scalar, h_b: scalar) -> bool:
        """Whether smoothing lengths h_a and h_b are of neighbouring refinement levels (one twice the
        other): a passive particle's donors (levels.passive_state)."""
        tol = scalar(0.01) * wp.max(h_a, h_b)
        return wp.abs(h_a - scalar(2.0) * h_b) < tol or wp.abs(h_b - scalar(2.0) * h_a) < tol

    @wp.func
    def cell_around(grid: Grid, ci: wp.vec3i, k: int) -> int:
        """The k-th of the cells_around cell ci (flat index), or -1 off the grid."""
        side = 2 * grid.reach + 1
        return neighbour_cell(grid, ci, k % side - grid.reach, (k / side) % side - grid.reach,
                              k / (side * side) - grid.reach_z)

    @wp.func
    def search_reach(grid: Grid, h_i: scalar, passive_i: bool, off: vec) -> wp.vec3i:
        """The cells a particle searches each way: one list radius of its own h (a passive one, the
        largest's), and of its ghost node's, ``off`` from it (mdbc.py; zero otherwise)."""
        reach = wp.vec3i(grid.reach, grid.reach, grid.reach_z)
        if grid.variable != 0 and not passive_i:
            # the cells are one smallest list radius wide; the tolerance keeps an exact ratio of 2
            # from rounding up to 3
            r_own = int(wp.ceil(h_i * grid.inv_h_min - scalar(1.0e-4)))
            reach = wp.vec3i(r_own, r_own, wp.min(r_own, grid.reach_z))
        if wp.dot(off, off) > scalar(0.0):
            # cells are at least a list radius wide: reach the ghost's list radius as well (on a
            # periodic axis no further than the cells that are there, each visited once)
            for ax in range(3):
                if ax < 2 or grid.reach_z > 0:
                    r_ax = reach[ax] + int(wp.ceil(wp.abs(off[ax]) * grid.inv_cell[ax]))
                    if grid.periodic[ax] != 0:
                        r_ax = wp.min(r_ax, (grid.dims[ax] - 1) / 2)
                    reach[ax] = r_ax
        return reach

    @wp.func
    def listed(grid: Grid, t_i: int, t_k: int, h_i: scalar, h_k: scalar, r: vec, off: vec) -> bool:
        """Whether particle k, at ``r`` from particle i (x_i - x_k), is i's neighbour: within the
        list radius of i or, for a boundary particle with a ghost node (``off`` from it), of that
        node. A boundary particle needs only its fluid neighbours (active or passive); an excluded
        particle is nobody's neighbour; with levels a particle needs its own level's (a passive one
        too: it may turn active before the next build), a passive one its donors too: the
        neighbouring levels' active fluid and the next finer level's passive fluid
        (levels.passive_state), each pair within the list radius of its own h_ab."""
        ok = carries_fluid(t_k) or (carries_fluid(t_i) and t_k == BOUNDARY)
        radius2 = grid.radius2
        if ok and grid.variable != 0:
            if h_i != h_k:
                ok = t_i == PASSIVE and adjacent_levels(h_i, h_k) and (t_k == FLUID or (t_k == PASSIVE and h_k < h_i))
            h_ab = scalar(0.5) * (h_i + h_k)
            radius2 = radius2 * h_ab * h_ab * grid.inv_h2
        if ok:
            ok = wp.dot(r, r) < radius2
            if not ok and wp.dot(off, off) > scalar(0.0):
                rg = r + off
                ok = wp.dot(rg, rg) < radius2
        return ok

    @wp.struct
    class Walk:
        """What a pass walks to find a particle's neighbours (``walk_from``, ``walk_cells``,
        ``walk_span``, ``walk_at``): its list or, without lists (``cells`` 1), the cells around
        it as of the last sort, each candidate tested as the lists' build tests it, on the
        particles as they were at that build (positions, kinds, h, whether they need a list: the
        ``*_built`` copies): the pairs a list would hold, in its order."""
        cells: int
        nbr: wp.array2d(dtype=wp.int32)
        count: wp.array(dtype=wp.int32)
        start: wp.array(dtype=wp.int32)
        end: wp.array(dtype=wp.int32)
        order: wp.array(dtype=wp.int32)
        x_build: wp.array(dtype=vec)
        ptype: wp.array(dtype=wp.int32)
        hsml: wp.array(dtype=scalar)
        ghost: wp.array(dtype=vec)
        needs_list: wp.array(dtype=wp.int32)

    @wp.func
    def walk_from(grid: Grid, nb: Walk, i: int):
        """(the cell of particle i at the last build, the cells its walk reaches each way): a
        list is one span (reach 0); a particle that needs no list walks nothing (reach -1)."""
        zero = wp.vec3i(0, 0, 0)
        if nb.cells == 0:
            return zero, zero
        if nb.needs_list[i] == 0:
            return zero, wp.vec3i(-1, 0, 0)
        return cell_coord(grid, nb.x_build[i]), search_reach(grid, nb.hsml[i], nb.ptype[i] == PASSIVE, nb.ghost[i])

    @wp.func
    def walk_cells(reach: wp.vec3i) -> int:
        """How many spans a walk of ``reach`` (walk_from) has."""
        if reach[0] < 0:
            return 0
        return (2 * reach[0] + 1) * (2 * reach[1] + 1) * (2 * reach[2] + 1)

    @wp.func
    def walk_span(grid: Grid, nb: Walk, i: int, ci: wp.vec3i, reach: wp.vec3i, c: int) -> wp.vec2i:
        """The slots [lo, hi) of span c of particle i's walk: its list's entries, or the sorted
        slots of cell c of those around ci (x fastest, then y, then z: the lists' order)."""
        if nb.cells == 0:
            return wp.vec2i(0, nb.count[i])
        sx = 2 * reach[0] + 1
        sy = 2 * reach[1] + 1
        cell = neighbour_cell(grid, ci, c % sx - reach[0], (c / sx) % sy - reach[1], c / (sx * sy) - reach[2])
        if cell < 0:
            return wp.vec2i(0, 0)
        return wp.vec2i(nb.start[cell], nb.end[cell])

    @wp.func
    def walk_at(grid: Grid, nb: Walk, i: int, s: int) -> int:
        """The neighbour in slot s of particle i's walk, or -1 where that slot holds none."""
        if nb.cells == 0:
            return nb.nbr[i, s]
        j = nb.order[s]
        if j == i or not listed(grid, nb.ptype[i], nb.ptype[j], nb.hsml[i], nb.hsml[j],
                                separation(grid, nb.x_build[i], nb.x_build[j]), nb.ghost[i]):
            return -1
        return j

    return SimpleNamespace(Grid=Grid, separation=separation, cell_coord=cell_coord, neighbour_cell=neighbour_cell,
                           cells_around=cells_around, cell_around=cell_around, adjacent_levels=adjacent_levels,
                           search_reach=search_reach, listed=listed, Walk=Walk, walk_from=walk_from,
                           walk_cells=walk_cells, walk_span=walk_span, walk_at=walk_at)


@functools.lru_cache(maxsize=None)
def build(scalar):
    """The passes that sort particles into cells and build the neighbour lists, with the grid's
    struct and functions."""
    vec = wp.types.vector(3, scalar)
    G = grid(scalar)
    Grid, separation, cell_coord, neighbour_cell = G.Grid, G.separation, G.cell_coord, G.neighbour_cell
    search_reach, listed = G.search_reach, G.listed
    Walk, walk_from, walk_cells, walk_span, walk_at = G.Walk, G.walk_from, G.walk_cells, G.walk_span, G.walk_at

    @wp.kernel(enable_backward=False, module="unique")
    def cell_keys(grid: Grid, pos: wp.array(dtype=vec), ptype: wp.array(dtype=wp.int32),
                  slot_of: wp.array(dtype=wp.int32), keys: wp.array(dtype=wp.int32),
                  values: wp.array(dtype=wp.int32)):
        """The cell of the particle whose id is k (its slot, slot_of[k]); a vacant slot (levels.py)
        sorts past the last cell, in none. Keyed in id order, the stable sort orders each cell's
        particles by id, whatever slots they stand in: every neighbour sum adds its terms in one
        order, however the particles were ordered before (a permuted start, another rank's subset)."""
        k = wp.tid()
        i = slot_of[k]
        c = cell_coord(grid, pos[i])
        keys[k] = (c[2] * grid.dims[1] + c[1]) * grid.dims[0] + c[0]
        if ptype[i] == VACANT:
            keys[k] = grid.dims[0] * grid.dims[1] * grid.dims[2]
        values[k] = i

    @wp.kernel(enable_backward=False, module="unique")
    def slots_of(ids: wp.array(dtype=wp.int32), slot_of: wp.array(dtype=wp.int32)):
        """The slot each id stands in: the inverse of the permutation ``ids``."""
        i = wp.tid()
        slot_of[ids[i]] = i

    @wp.kernel(enable_backward=False, module="unique")
    def identity(order: wp.array(dtype=wp.int32)):
        """The order of particles that already stand in cell order."""
        k = wp.tid()
        order[k] = k

    @wp.kernel(enable_backward=False, module="unique")
    def cell_ranges(n: int, keys: wp.array(dtype=wp.int32), start: wp.array(dtype=wp.int32),
                    end: wp.array(dtype=wp.int32)):
        k = wp.tid()
        c = keys[k]
        if c >= start.shape[0]:  # the vacant slots
            return
        if k == 0 or keys[k - 1] != c:
            start[c] = k
        if k == n - 1 or keys[k + 1] != c:
            end[c] = k + 1

    @wp.kernel(enable_backward=False, module="unique")
    def gather_sorted(order: wp.array(dtype=wp.int32), pos: wp.array(dtype=vec), ptype: wp.array(dtype=wp.int32),
                      hsml: wp.array(dtype=scalar), pos_sorted: wp.array(dtype=vec),
                      ptype_sorted: wp.array(dtype=wp.int32), hsml_sorted: wp.array(dtype=scalar)):
        k = wp.tid()
        i = order[k]
        pos_sorted[k] = pos[i]
        ptype_sorted[k] = ptype[i]
        hsml_sorted[k] = hsml[i]

    @wp.kernel(enable_backward=False, module="unique")
    def gather_positions(order: wp.array(dtype=wp.int32), x: wp.array(dtype=vec), x_sorted: wp.array(dtype=vec)):
        k = wp.tid()
        x_sorted[k] = x[order[k]]

    @wp.kernel(enable_backward=False, module="unique")
    def listed_then(count: wp.array(dtype=wp.int32), needs_list: wp.array(dtype=wp.int32)):
        """Which particles a build gave a list that found a neighbour: built again with these alone
        needing one, the lists are that build's (a particle with none found is empty either way)."""
        i = wp.tid()
        needs_list[i] = wp.where(count[i] > 0, 1, 0)

    @wp.kernel(enable_backward=False, module="unique")
    def check_displacement(grid: Grid, pos: wp.array(dtype=vec), vel: wp.array(dtype=vec),
                           x_build: wp.array(dtype=vec), clock: wp.array(dtype=wp.float64),
                           stale: wp.array(dtype=wp.int32)):
        """Flag the lists stale once a particle, where the next step will read it (``lookahead``
        |u| dt on), would be past half the skin from its build position: two particles closing in
        then still find each other listed."""
        i = wp.tid()
        d = separation(grid, pos[i], x_build[i])
        ahead = wp.length(d) + grid.lookahead * wp.length(vel[i]) * scalar(clock[DT])
        if ahead > grid.half_skin:
            stale[0] = 1

    @wp.kernel(enable_backward=False, module="unique")
    def mark_built(stale: wp.array(dtype=wp.int32), builds: wp.array(dtype=wp.int32)):
        builds[0] = builds[0] + 1
        stale[0] = 0

    @wp.kernel(enable_backward=False, module="unique")
    def neighbour_list(grid: Grid, pos_sorted: wp.array(dtype=vec), ptype_sorted: wp.array(dtype=wp.int32),
                       hsml_sorted: wp.array(dtype=scalar), order: wp.array(dtype=wp.int32),
                       start: wp.array(dtype=wp.int32),
                       end: wp.array(dtype=wp.int32), nbr: wp.array2d(dtype=wp.int32),
                       count: wp.array(dtype=wp.int32), needs_list: wp.array(dtype=wp.int32),
                       ghost: wp.array(dtype=vec), x_build: wp.array(dtype=vec),
                       overflow: wp.array(dtype=wp.int32), fail: wp.array(dtype=wp.int32), fail_slot: int,
                       hold: wp.array(dtype=wp.int32), chunk: int, stride: int):
        """A particle's list: every candidate within the list radius of it or, for a boundary
        particle with a ghost node (mdbc.py, at ``ghost`` from it; zero otherwise), of that node.
        A list longer than the width flags ``fail_slot`` and clears ``hold`` (the step stops) and
        keeps the longest such list in ``overflow``."""
        # walk particles in cell order, reading the candidates' positions in that order too:
        # the candidates of one cell lie next to each other in memory
        ki = wp.tid() * stride + chunk
        i = order[ki]
        x_build[i] = pos_sorted[ki]
        if needs_list[i] == 0:
            count[i] = 0
            return
        t_i = ptype_sorted[ki]
        h_i = hsml_sorted[ki]
        xi = pos_sorted[ki]
        off = ghost[i]
        ci = cell_coord(grid, xi)
        reach = search_reach(grid, h_i, t_i == PASSIVE, off)
        n = int(0)
        for dz in range(-reach[2], reach[2] + 1):
            for dy in range(-reach[1], reach[1] + 1):
                for dx in range(-reach[0], reach[0] + 1):
                    cell = neighbour_cell(grid, ci, dx, dy, dz)
                    if cell >= 0:
                        for k in range(start[cell], end[cell]):
                            if k != ki and listed(grid, t_i, ptype_sorted[k], h_i, hsml_sorted[k],
                                                  separation(grid, xi, pos_sorted[k]), off):
                                if n < grid.max_neighbours:
                                    nbr[i, n] = order[k]
                                n += 1
        if n > grid.max_neighbours:
            wp.atomic_max(overflow, 0, n)
            wp.atomic_min(fail, fail_slot, i)
            hold[0] = 0
            n = grid.max_neighbours
        count[i] = n

    @wp.kernel(enable_backward=False, module="unique")
    def record_build(pos: wp.array(dtype=vec), ptype: wp.array(dtype=wp.int32), hsml: wp.array(dtype=scalar),
                     needs_list: wp.array(dtype=wp.int32), x_build: wp.array(dtype=vec),
                     ptype_built: wp.array(dtype=wp.int32), hsml_built: wp.array(dtype=scalar),
                     needs_built: wp.array(dtype=wp.int32)):
        """Without lists: each particle as the cells were sorted, what a walk tests its pairs on, as
        a list's build tests them: where it stood, its kind, its h and whether it needs a list (a
        list holds, until the next build, the pairs of its build: a particle made since has none)."""
        i = wp.tid()
        x_build[i] = pos[i]
        ptype_built[i] = ptype[i]
        hsml_built[i] = hsml[i]
        needs_built[i] = needs_list[i]

    @wp.kernel(enable_backward=False, module="unique")
    def walk_count(grid: Grid, nb: Walk, count: wp.array(dtype=wp.int32)):
        """How many neighbours each particle's walk finds: its list's length."""
        i = wp.tid()
        n = int(0)
        cell_i, reach_i = walk_from(grid, nb, i)
        for w in range(walk_cells(reach_i)):
            span = walk_span(grid, nb, i, cell_i, reach_i, w)
            for slot in range(span[0], span[1]):
                if walk_at(grid, nb, i, slot) >= 0:
                    n += 1
        count[i] = n

    return SimpleNamespace(Grid=Grid, Walk=G.Walk, cell_keys=cell_keys, slots_of=slots_of, identity=identity,
                           cell_ranges=cell_ranges,
                           gather_sorted=gather_sorted, gather_positions=gather_positions, listed_then=listed_then,
                           record_build=record_build, walk_count=walk_count,
                           neighbour_list=neighbour_list, check_displacement=check_displacement,
                           mark_built=mark_built)


def lists_array(n: int, width: int, device, neighbour_major: bool) -> wp.array:
    """The lists, ``nbr[i, k]`` the k-th neighbour of particle i, a 2D array: each index is 32-bit
    and the byte offset 64-bit (Warp's strides), so no kernel forms i x width in 32 bits, which
    passed 2^31 at 8.7 M particles of 3D lists. Neighbour-major on a GPU (stored as width x n, read
    through a transposed view): the threads of a warp, consecutive particles, read their k-th
    neighbours from consecutive addresses. Particle-major on a CPU, where one thread walks one
    particle's list."""
    if neighbour_major:
        return wp.zeros((width, n), dtype=wp.int32, device=device).transpose()
    return wp.zeros((n, width), dtype=wp.int32, device=device)


class NeighbourList:
    """Owns the cell grid and the per-particle neighbour lists of one solver on one device."""

    def __init__(self, scalar, dim: int, support: float, lo, hi, periodic, ptype: wp.array,
                 needs_list: wp.array, ghost: wp.array, max_neighbours: int, launcher, hsml: wp.array,
                 ids: wp.array, variable: bool = False, substeps: int = 1, neighbour_major: "bool | None" = None,
                 fail: "wp.array | None" = None, fail_slot: int = 0, hold: "wp.array | None" = None,
                 cells: bool = False):
        """``ptype``, ``needs_list``, ``ghost`` (each particle's ghost-node offset, see
        neighbour_list) and ``ids`` (each slot's particle, a permutation: the sort orders a cell's
        particles by it) are the solver's own device arrays (it may reorder them); ``hsml``, each
        particle's smoothing length, which a pair's radius follows where ``variable`` (they differ:
        ``support`` is then the largest's); ``substeps``, the finest level's steps one launched
        step spans (2 with multirate), whose force passes all read these lists;
        ``neighbour_major``, the lists' layout (lists_array), by default the device's; ``fail``
        and ``fail_slot``, where a list that overflows its width is flagged (the solver's health
        flags) and ``hold`` cleared (the step loop's flag that lets a step go on past its lists);
        ``cells``: keep no lists, the passes walking the cells of the last sort (Walk)."""
        self._passes = build(scalar)
        Grid = self._passes.Grid
        n = needs_list.shape[0]
        self.n = n
        self.launcher = launcher
        self.device = device = launcher.device
        self.max_neighbours = max_neighbours
        lo = np.asarray(lo, dtype=np.float64)
        length = np.asarray(hi, dtype=np.float64) - lo
        self.skin = list_skin(substeps)
        radius = self.skin * support
        h_min = float(hsml.numpy().min()) if variable else 0.5 * support
        cell = self.skin * 2.0 * h_min  # see the module docstring
        reach = int(math.ceil(radius / cell - 1.0e-4))  # cells searched each way by the largest h
        dims = [max(1, int(math.floor(length[ax] / cell))) for ax in range(3)]
        if dim == 2:
            dims[2] = 1
        g = Grid()
        g.lo = wp.types.vector(3, scalar)(*lo)
        g.length = wp.types.vector(3, scalar)(*length)
        g.inv_cell = wp.types.vector(3, scalar)(*[dims[ax] / length[ax] for ax in range(3)])
        g.dims = wp.vec3i(*dims)
        g.periodic = wp.vec3i(*[1 if p else 0 for p in periodic])
        g.any_periodic = 1 if any(periodic) else 0
        g.reach = reach
        g.reach_z = reach if dim == 3 else 0
        g.radius2 = radius * radius
        g.variable = int(variable)
        g.inv_h2 = (2.0 / support) ** 2
        g.inv_h_min = 1.0 / h_min
        # two particles closing in each move at most half the skin (the finest level's)
        g.half_skin = 0.5 * (radius - support) * 2.0 * h_min / support
        g.lookahead = LOOKAHEAD_SAFETY * (substeps - 0.5)
        g.max_neighbours = max_neighbours
        self.grid = g
        ncells = dims[0] * dims[1] * dims[2]
        self._key_bits = ncells.bit_length()  # the vacant slots' key is ncells
        self._keys = wp.zeros(2 * n, dtype=wp.int32, device=device)
        self._order = wp.zeros(2 * n, dtype=wp.int32, device=device)
        self._ids = ids
        self._slot_of = wp.zeros(n, dtype=wp.int32, device=device)
        self._start = wp.zeros(ncells, dtype=wp.int32, device=device)
        self._end = wp.zeros(ncells, dtype=wp.int32, device=device)
        self.neighbour_major = device.is_cuda if neighbour_major is None else neighbour_major
        self.cells = cells
        # without lists: no list, no count and none of the sorted copies the lists' build reads
        self.nbr = None if cells else lists_array(n, max_neighbours, device, self.neighbour_major)
        self.count = None if cells else wp.zeros(n, dtype=wp.int32, device=device)
        self.overflow = wp.zeros(1, dtype=wp.int32, device=device)
        self._fail = fail if fail is not None else wp.zeros(1, dtype=wp.int32, device=device)
        self._fail_slot = fail_slot
        self._hold = hold if hold is not None else wp.ones(1, dtype=wp.int32, device=device)
        self._needs_list = needs_list
        self._ghost = ghost
        self._ptype = ptype
        self._hsml = hsml
        # the lists' build reads sorted copies; walks read the kinds, h and needs as of the sort
        sorted_n, built_n = (0, n) if cells else (n, 0)
        self._pos_sorted = wp.zeros(sorted_n, dtype=wp.types.vector(3, scalar), device=device)
        self._ptype_sorted = wp.zeros(sorted_n, dtype=wp.int32, device=device)
        self._hsml_sorted = wp.zeros(sorted_n, dtype=scalar, device=device)
        self._ptype_built = wp.zeros(built_n, dtype=wp.int32, device=device)
        self._hsml_built = wp.zeros(built_n, dtype=scalar, device=device)
        self._needs_built = wp.zeros(built_n, dtype=wp.int32, device=device)
        self._x_build = wp.zeros(n, dtype=wp.types.vector(3, scalar), device=device)
        self.stale = wp.ones(1, dtype=wp.int32, device=device)
        self.builds = wp.zeros(1, dtype=wp.int32, device=device)  # how many times the lists were built
        self.walk = self._passes.Walk()
        self._walk_arrays()

    def _walk_arrays(self):
        w = self.walk
        w.cells = int(self.cells)
        if not self.cells:
            w.nbr, w.count = self.nbr, self.count
        w.start, w.end, w.order, w.x_build, w.ghost = self._start, self._end, self._order, self._x_build, self._ghost
        w.ptype, w.hsml, w.needs_list = self._ptype_built, self._hsml_built, self._needs_built

    @property
    def x_build(self) -> wp.array:
        """Each particle's position when the lists were last built (a particle made since sets its own)."""
        return self._x_build

    def moved(self, pos: wp.array, vel: wp.array, clock: wp.array):
        """Note the particles' new positions and velocities (``clock``: the solver's, whose DT is
        the last step): the lists go stale if the next step would read any too far away."""
        wp.launch(self._passes.check_displacement, dim=self.n,
                  inputs=[self.grid, pos, vel, self._x_build, clock, self.stale], device=self.device)

    def sort(self, pos: wp.array) -> wp.array:
        """Sort the particles by cell; returns the particle index of each sorted position. The
        radix sort reads only the bits a cell index (and the vacant slots' key past the last cell)
        needs: 16 instead of 32 on DamBreak 1's grid."""
        wp.launch(self._passes.slots_of, dim=self.n, inputs=[self._ids, self._slot_of], device=self.device)
        wp.launch(self._passes.cell_keys, dim=self.n,
                  inputs=[self.grid, pos, self._ptype, self._slot_of, self._keys, self._order], device=self.device)
        wp.utils.radix_sort_pairs(self._keys, self._order, self.n, end_bit=self._key_bits)
        return self._order

    def _ranges(self):
        self._start.zero_()
        self._end.zero_()
        wp.launch(self._passes.cell_ranges, dim=self.n, inputs=[self.n, self._keys, self._start, self._end],
                  device=self.device)

    def _build(self, pos: wp.array, presorted: bool = False):
        """Sort (unless the particles already stand in the last sort's cell order), then build
        every list or, without lists, note where each particle stands (the walks test it there)."""
        n = self.n
        if presorted:
            wp.launch(self._passes.identity, dim=n, inputs=[self._order], device=self.device)
        else:
            self.sort(pos)
        self._ranges()
        if self.cells:
            wp.launch(self._passes.record_build, dim=n,
                      inputs=[pos, self._ptype, self._hsml, self._needs_list, self._x_build, self._ptype_built,
                              self._hsml_built, self._needs_built], device=self.device)
        else:
            self._list(pos)
        wp.launch(self._passes.mark_built, dim=1, inputs=[self.stale, self.builds], device=self.device)

    def _list(self, pos: wp.array):
        """Every particle's list, from the sort just made."""
        wp.launch(self._passes.gather_sorted, dim=self.n,
                  inputs=[self._order, pos, self._ptype, self._hsml, self._pos_sorted, self._ptype_sorted,
                          self._hsml_sorted], device=self.device)
        self._fill(self._needs_list)

    def _fill(self, needs_list: wp.array):
        self.launcher(self._passes.neighbour_list, self.n, [self.grid, self._pos_sorted, self._ptype_sorted,
                                                            self._hsml_sorted, self._order, self._start, self._end,
                                                            self.nbr, self.count, needs_list, self._ghost,
                                                            self._x_build, self.overflow, self._fail,
                                                            self._fail_slot, self._hold])

    def relist(self):
        """The lists of the last build again, from what a state keeps of it (checkpoint.put): that
        build's sort (order, cell ranges), the positions then (x_build), the kinds and h it read
        (the sorted copies) and the lists' lengths, nonzero exactly where a particle needed a list
        and found a neighbour: each list the same, entry for entry."""
        wp.launch(self._passes.gather_positions, dim=self.n, inputs=[self._order, self._x_build, self._pos_sorted],
                  device=self.device)
        needs = wp.empty(self.n, dtype=wp.int32, device=self.device)  # a restore's, not the step's
        wp.launch(self._passes.listed_then, dim=self.n, inputs=[self.count, needs], device=self.device)
        self._fill(needs)

    def rebuild(self, pos: wp.array, force: bool = False):
        """Sort and build the lists if they are stale (the device's flag: a branch of a captured
        graph, read in place on a CPU) or ``force``. Between builds the cells keep the last
        sort's ranges: a particle has moved less than half the skin since, so a walk of the cells
        one list radius around a point still finds every particle within a kernel support of it."""
        if force:
            self.stale.fill_(1)
        wp.capture_if(self.stale, on_true=self._build, pos=pos)

    def resize(self, width: int):
        """Lists ``width`` long, to be built before they are read (stale)."""
        self.max_neighbours = self.grid.max_neighbours = int(width)
        self.nbr = lists_array(self.n, self.max_neighbours, self.device, self.neighbour_major)
        self._walk_arrays()
        self.stale.fill_(1)

    def counts(self) -> np.ndarray:
        """Each particle's neighbour count as of the last build (a host read; without lists, what
        a walk finds)."""
        if not self.cells:
            return self.count.numpy()
        count = wp.zeros(self.n, dtype=wp.int32, device=self.device)
        wp.launch(self._passes.walk_count, dim=self.n, inputs=[self.grid, self.walk, count], device=self.device)
        return count.numpy()

    def longest(self) -> int:
        """The longest list of the last build, or of the build that overflowed (a host read)."""
        return max(int(self.counts().max(initial=0)), int(self.overflow.numpy()[0]))

    def rebuild_sorted(self, pos: wp.array):
        """Build the lists of particles just put in the order of the last sort (a reorder), with
        no second sort."""
        self._build(pos, presorted=True)

    @property
    def cell_start(self) -> wp.array:
        """First sorted slot of each cell, as of the last sort (``order`` maps slots to particles)."""
        return self._start

    @property
    def cell_end(self) -> wp.array:
        return self._end

    @property
    def order(self) -> wp.array:
        return self._order

    def mean_neighbours(self) -> float:
        """Mean list length over the fluid particles."""
        return float(self.counts()[self._ptype.numpy() == 0].mean())
