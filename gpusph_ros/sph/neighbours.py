"""Neighbour search: a uniform grid of cells at least one kernel support wide, built by a
counting sort of cell keys (Warp's radix sort), then one fixed-width neighbour list per particle
(as GPUSPH keeps). Every later pass of the step loops over that list only.

Periodic axes wrap both the cell search and the separation vector (minimum image).
"""

import functools
import math

import numpy as np
import warp as wp

from .config import LIST_SKIN


class NeighbourOverflow(RuntimeError):
    """More neighbours than the list holds (particles clumped or the list is too narrow)."""


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.struct
    class Grid:
        lo: vec
        length: vec  # domain extent, the period on periodic axes
        inv_cell: vec
        dims: wp.vec3i
        periodic: wp.vec3i
        search_z: int  # 0 in 2D: one layer of cells
        radius2: scalar  # squared list radius (support plus skin)
        max_neighbours: int

    @wp.func
    def separation(grid: Grid, xa: vec, xb: vec) -> vec:
        """x_a - x_b, by the minimum image on periodic axes."""
        r = xa - xb
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

    @wp.kernel(enable_backward=False, module="unique")
    def cell_keys(grid: Grid, pos: wp.array(dtype=vec), keys: wp.array(dtype=wp.int32),
                  values: wp.array(dtype=wp.int32)):
        i = wp.tid()
        c = cell_coord(grid, pos[i])
        keys[i] = (c[2] * grid.dims[1] + c[1]) * grid.dims[0] + c[0]
        values[i] = i

    @wp.kernel(enable_backward=False, module="unique")
    def cell_ranges(n: int, keys: wp.array(dtype=wp.int32), start: wp.array(dtype=wp.int32),
                    end: wp.array(dtype=wp.int32)):
        k = wp.tid()
        c = keys[k]
        if k == 0 or keys[k - 1] != c:
            start[c] = k
        if k == n - 1 or keys[k + 1] != c:
            end[c] = k + 1

    @wp.kernel(enable_backward=False, module="unique")
    def neighbour_list(grid: Grid, pos: wp.array(dtype=vec), order: wp.array(dtype=wp.int32),
                       start: wp.array(dtype=wp.int32), end: wp.array(dtype=wp.int32),
                       nbr: wp.array(dtype=wp.int32), count: wp.array(dtype=wp.int32),
                       needs_list: wp.array(dtype=wp.int32), overflow: wp.array(dtype=wp.int32), chunk: int, stride: int):
        # walk particles in cell order so consecutive threads read neighbouring memory
        i = order[wp.tid() * stride + chunk]
        if needs_list[i] == 0:
            count[i] = 0
            return
        xi = pos[i]
        ci = cell_coord(grid, xi)
        n = int(0)
        base = i * grid.max_neighbours
        for dz in range(-grid.search_z, grid.search_z + 1):
            for dy in range(-1, 2):
                for dx in range(-1, 2):
                    c = ci + wp.vec3i(dx, dy, dz)
                    inside = int(1)
                    for ax in range(3):
                        if c[ax] < 0 or c[ax] >= grid.dims[ax]:
                            if grid.periodic[ax] != 0:
                                c[ax] = (c[ax] + grid.dims[ax]) % grid.dims[ax]
                            else:
                                inside = 0
                    if inside == 1:
                        cell = (c[2] * grid.dims[1] + c[1]) * grid.dims[0] + c[0]
                        for k in range(start[cell], end[cell]):
                            j = order[k]
                            if j != i:
                                r = separation(grid, xi, pos[j])
                                if wp.dot(r, r) < grid.radius2:
                                    if n < grid.max_neighbours:
                                        nbr[base + n] = j
                                    n += 1
        if n > grid.max_neighbours:
            wp.atomic_max(overflow, 0, n)
            n = grid.max_neighbours
        count[i] = n

    return Grid, separation, cell_keys, cell_ranges, neighbour_list


class NeighbourList:
    """Owns the cell grid and the per-particle neighbour lists of one solver on one device."""

    SKIN = LIST_SKIN

    def __init__(self, scalar, dim: int, support: float, lo, hi, periodic, needs_list: np.ndarray,
                 max_neighbours: int, launcher):
        Grid, self._separation, self._cell_keys, self._cell_ranges, self._neighbour_list = build(scalar)
        n = len(needs_list)
        self.n = n
        self.launcher = launcher
        self.device = device = launcher.device
        self.max_neighbours = max_neighbours
        lo = np.asarray(lo, dtype=np.float64)
        length = np.asarray(hi, dtype=np.float64) - lo
        radius = self.SKIN * support
        dims = [max(1, int(math.floor(length[ax] / radius))) for ax in range(3)]
        if dim == 2:
            dims[2] = 1
        g = Grid()
        g.lo = wp.types.vector(3, scalar)(*lo)
        g.length = wp.types.vector(3, scalar)(*length)
        g.inv_cell = wp.types.vector(3, scalar)(*[dims[ax] / length[ax] for ax in range(3)])
        g.dims = wp.vec3i(*dims)
        g.periodic = wp.vec3i(*[1 if p else 0 for p in periodic])
        g.search_z = 1 if dim == 3 else 0
        g.radius2 = radius * radius
        g.max_neighbours = max_neighbours
        self.grid = g
        ncells = dims[0] * dims[1] * dims[2]
        self._keys = wp.zeros(2 * n, dtype=wp.int32, device=device)
        self._order = wp.zeros(2 * n, dtype=wp.int32, device=device)
        self._start = wp.zeros(ncells, dtype=wp.int32, device=device)
        self._end = wp.zeros(ncells, dtype=wp.int32, device=device)
        self.nbr = wp.zeros(n * max_neighbours, dtype=wp.int32, device=device)
        self.count = wp.zeros(n, dtype=wp.int32, device=device)
        self.overflow = wp.zeros(1, dtype=wp.int32, device=device)
        self._needs_list = wp.array(np.asarray(needs_list, dtype=np.int32), dtype=wp.int32, device=device)

    def rebuild(self, pos: wp.array):
        n = self.n
        wp.launch(self._cell_keys, dim=n, inputs=[self.grid, pos, self._keys, self._order], device=self.device)
        wp.utils.radix_sort_pairs(self._keys, self._order, n)
        self._start.zero_()
        self._end.zero_()
        wp.launch(self._cell_ranges, dim=n, inputs=[n, self._keys, self._start, self._end], device=self.device)
        self.launcher(self._neighbour_list, n, [self.grid, pos, self._order, self._start, self._end, self.nbr,
                                                self.count, self._needs_list, self.overflow])

    def mean_neighbours(self) -> float:
        """Mean list length over the particles that keep a list."""
        needs = self._needs_list.numpy() > 0
        return float(self.count.numpy()[needs].mean())
