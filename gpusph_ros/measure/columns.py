"""Depth-averaged velocity: the mean velocity of the fluid particles inside a vertical cylinder
of radius R around a horizontal point (thesis Section 3.3, R = 3 dx; in 2D a vertical strip of
half-width R). Summed on the solver's device; only the sums come to the host."""
import functools

import numpy as np
import warp as wp

from ..sph import sums
from ..sph.state import FLUID
from .ranks import Alone


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.kernel(enable_backward=False, module="unique")
    def column_sums(up: int, centres: wp.array(dtype=vec), radius2: wp.array(dtype=scalar),
                    pos: wp.array(dtype=vec), vel: wp.array(dtype=vec), ptype: wp.array(dtype=wp.int32),
                    ranked: int, owned: wp.array(dtype=wp.int32), counts: wp.array(dtype=wp.int32),
                    part: wp.array2d(dtype=vec), lead: int, step: int, members: int):
        """Block k's velocity sum of each column into part[k] (sums.py: a fixed order of the terms)
        and the fluid particles in each into counts (integers: the same in any order); ``ranked``:
        only the particles this rank owns (measure/ranks.py)."""
        k = wp.tid()
        n = ptype.shape[0]
        for c in range(centres.shape[0]):
            part[k, c] = vec(scalar(0.0))
        for j in range(members):
            i = sums.member(k, j, lead, step)
            if i < n:
                if ptype[i] == FLUID and (ranked == 0 or owned[i] != 0):
                    for c in range(centres.shape[0]):
                        d = pos[i] - centres[c]
                        d[up] = scalar(0.0)
                        if wp.dot(d, d) <= radius2[c]:
                            part[k, c] = part[k, c] + vel[i]
                            wp.atomic_add(counts, c, 1)

    return column_sums


class ColumnMeans:
    """Mean fluid velocity in vertical columns at horizontal ``positions`` (3-vectors; the vertical
    component is ignored) with radii ``radii`` [m]; ``across``: how the ranks of a run add them
    up (ranks.py)."""

    def __init__(self, solver, positions, radii, across=None):
        self.solver = solver
        self.across = across or Alone(solver)
        dev = solver.device
        self._sums_kernel = build(solver.scalar)
        self.centres = wp.array(np.asarray(positions, dtype=np.float64).reshape(-1, 3), dtype=solver.vec, device=dev)
        self.radius2 = wp.array(np.asarray(radii, dtype=np.float64) ** 2, dtype=solver.scalar, device=dev)
        k = self.centres.shape[0]
        self._sums = wp.zeros(k, dtype=solver.vec, device=dev)
        self._part = sums.Partials(solver.n, k, solver.vec, dev)
        self._counts = wp.zeros(k, dtype=wp.int32, device=dev)

    def sample(self) -> dict:
        """vel (k x 3, zero where a column holds no fluid) and count (fluid particles in each)."""
        s, a = self.solver, self.across
        self._counts.zero_()
        # one launch: CPU atomics are not atomic across the threads of a split launch
        wp.launch(self._sums_kernel, dim=self._part.count,
                  inputs=[s.config.dim - 1, self.centres, self.radius2, s.pos, s.vel, s.ptype, a.ranked, a.owned,
                          self._counts, *self._part.args()], device=s.device)
        self._part.total(self._sums)
        sums = a.total(self._sums.numpy().astype(np.float64))
        counts = a.total(self._counts.numpy())
        vel = np.where(counts[:, None] > 0, sums / np.maximum(counts, 1)[:, None], 0.0)
        return {"vel": vel, "count": counts}
