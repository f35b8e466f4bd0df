"""Force on an obstruction along the flow (x) from pressure blocks, as the thesis measured it
(Section 3.2): blocks 3 dx x 3 dx across the face (y-z) and 4 dx along the flow, on the fluid
side of the upstream and downstream faces, tiling each face (the last row and column clipped to
the face); each block's mean fluid pressure times its face area, summed over the upstream face
less the downstream one. The thesis used blocks at the faces and 0.06 m away from them (Tables
12-15). In 2D the blocks tile the face's height and the force is per unit depth.

Particles are binned on the solver's device; only per-block sums come to the host.
"""
import functools

import numpy as np
import warp as wp

from ..sph import sums
from ..sph.state import FLUID
from .ranks import Alone

ACROSS = 3.0  # block size across the face, in dx
ALONG = 4.0  # block depth along the flow, in dx


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.kernel(enable_backward=False, module="unique")
    def bin_pressure(lo: wp.array(dtype=vec), hi: wp.array(dtype=vec), bound_lo: vec, bound_hi: vec,
                     pos: wp.array(dtype=vec), pressure: wp.array(dtype=scalar), ptype: wp.array(dtype=wp.int32),
                     ranked: int, owned: wp.array(dtype=wp.int32), counts: wp.array(dtype=wp.int32),
                     part: wp.array2d(dtype=scalar), lead: int, step: int, members: int):
        """Block k's pressure sum of each pressure block into part[k] (sums.py: a fixed order of the
        terms) and the fluid particles in each into counts (integers: the same in any order);
        ``ranked``: only the particles this rank owns (measure/ranks.py)."""
        k = wp.tid()
        n = ptype.shape[0]
        for b in range(lo.shape[0]):
            part[k, b] = scalar(0.0)
        for j in range(members):
            i = sums.member(k, j, lead, step)
            if i < n:
                x = pos[i]
                near = ptype[i] == FLUID and (ranked == 0 or owned[i] != 0)
                # most particles are nowhere near a block
                for ax in range(3):
                    if x[ax] < bound_lo[ax] or x[ax] >= bound_hi[ax]:
                        near = False
                if near:
                    for b in range(lo.shape[0]):
                        a = lo[b]
                        c = hi[b]
                        if (x[0] >= a[0] and x[0] < c[0] and x[1] >= a[1] and x[1] < c[1] and x[2] >= a[2]
                                and x[2] < c[2]):
                            part[k, b] = part[k, b] + pressure[i]
                            wp.atomic_add(counts, b, 1)

    return bin_pressure


def face_blocks(box_lo, box_hi, dx: float, dim: int, offset: float):
    """The blocks of one obstacle at ``offset`` [m] from its faces: (lo, hi, sign, area) arrays,
    sign +1 upstream (x < box_lo) and -1 downstream."""
    across = list(range(1, dim))  # y (3D only) and the vertical
    edges = []
    for ax in across:
        start, stop = box_lo[ax], box_hi[ax]
        cuts = list(np.arange(start, stop, ACROSS * dx)) + [stop]
        if stop - cuts[-2] < 1e-9 * dx:
            cuts.pop(-2)
        edges.append(list(zip(cuts[:-1], cuts[1:])))
    tiles = [[t] for t in edges[0]] if len(edges) == 1 else [[a, b] for a in edges[0] for b in edges[1]]
    los, his, signs, areas = [], [], [], []
    for sign, x0, x1 in ((1.0, box_lo[0] - offset - ALONG * dx, box_lo[0] - offset),
                         (-1.0, box_hi[0] + offset, box_hi[0] + offset + ALONG * dx)):
        for tile in tiles:
            lo = [x0, -1.0e9, -1.0e9]
            hi = [x1, 1.0e9, 1.0e9]
            area = 1.0
            for ax, (a, b) in zip(across, tile):
                lo[ax], hi[ax] = a, b
                area *= b - a
            los.append(lo)
            his.append(hi)
            signs.append(sign)
            areas.append(area)
    return np.array(los), np.array(his), np.array(signs), np.array(areas)


class PressureBlockForce:
    """The x-force on the box [box_lo, box_hi] from pressure blocks at each of ``offsets`` [m]."""

    def __init__(self, solver, box_lo, box_hi, offsets=(0.0, 0.06), across=None):
        self.solver = solver
        self.across = across or Alone(solver)
        cfg = solver.config
        self.offsets = tuple(float(o) for o in offsets)
        parts = [face_blocks(box_lo, box_hi, cfg.dx, cfg.dim, o) for o in self.offsets]
        self._slices = np.cumsum([0] + [len(p[2]) for p in parts])
        lo = np.concatenate([p[0] for p in parts])
        hi = np.concatenate([p[1] for p in parts])
        self._sign = np.concatenate([p[2] for p in parts])
        self.area = np.concatenate([p[3] for p in parts])
        dev = solver.device
        self._bin = build(solver.scalar)
        self._lo = wp.array(lo, dtype=solver.vec, device=dev)
        self._hi = wp.array(hi, dtype=solver.vec, device=dev)
        self._bound_lo = solver.vec(*lo.min(axis=0))
        self._bound_hi = solver.vec(*hi.max(axis=0))
        self._sums = wp.zeros(len(lo), dtype=solver.scalar, device=dev)
        self._part = sums.Partials(solver.n, len(lo), solver.scalar, dev)
        self._counts = wp.zeros(len(lo), dtype=wp.int32, device=dev)

    def sample(self) -> dict:
        """{offset: (force_x, upstream, downstream)} [N, or N/m in 2D]; an empty block adds nothing."""
        params, fields, _ = self.across.view()
        s, a = self.solver, self.across
        self._counts.zero_()
        wp.launch(self._bin, dim=self._part.count, inputs=[self._lo, self._hi, self._bound_lo, self._bound_hi, s.pos,
                                                           fields.pressure, s.ptype, a.ranked, a.owned, self._counts,
                                                           *self._part.args()], device=s.device)
        self._part.total(self._sums)
        counts = a.total(self._counts.numpy())
        mean = np.where(counts > 0, a.total(self._sums.numpy().astype(np.float64)) / np.maximum(counts, 1), 0.0)
        load = mean * self.area
        out = {}
        for k, offset in enumerate(self.offsets):
            part = slice(self._slices[k], self._slices[k + 1])
            upstream = float(load[part][self._sign[part] > 0].sum())
            downstream = float(load[part][self._sign[part] < 0].sum())
            out[offset] = (upstream - downstream, upstream, downstream)
        return out
