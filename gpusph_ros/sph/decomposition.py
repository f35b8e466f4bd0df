"""One run's particles cut into slabs of whole cells along one axis, a slab a rank (issue 69).

As GPUSPH v5 cuts a run across devices (Rustico et al., IEEE TPDS 2014): the axis is the domain's
longest; it is cut into cells at least one kernel support (2 h of the largest h) wide, so that a
particle's neighbours lie in its own cell or the next one on either side, and each rank takes a run
of whole cells, at least ``MIN_CELLS`` of them (GPUSPH's bound: a rank's halo then never reaches past
its neighbour's slab). The cuts are chosen where the particle counts balance: every particle
counts, the walls' too, since a wall particle costs a rank memory and, near fluid, a neighbour walk.

A rank's halo is the particles of other ranks within ``HALO_CELLS`` cells below its first and above
its last (across the period where the axis is periodic; ``SPS_HALO_CELLS`` under SPS): one cell holds
all of its particles' neighbours that it does not own, and three let it step them too, so that one
exchange a step is enough (tests/test_halo_depth.py, sph/exchange.py). ``exchange_bytes`` prices
that exchange: after each step, the state a force evaluation reads (position, velocity, density: 7
scalars) of every halo particle, and what a particle that enters a halo carries besides (mass and
h: 2 scalars; kind and body: 8 bytes; its identity: 8 bytes), priced for every halo particle every
step (an upper bound: particles change hands only where the lists are built again, and most stay
in the halo).
"""
from dataclasses import dataclass

import numpy as np

from .config import ConfigError

MIN_CELLS = 3  # the fewest cells a rank's slab may be across (GPUSPH v5)
STATE_SCALARS = 7  # position, velocity, density: what a force evaluation reads of a neighbour
IDENTITY_SCALARS, IDENTITY_BYTES = 2, 16  # mass, h; kind, body and the particle's id
HALO_CELLS, SPS_HALO_CELLS = 3, 4  # a halo's depth for one exchange a step, measured: tests/test_halo_depth.py


@dataclass(frozen=True)
class Slabs:
    """The cut of one run: ``axis`` (0, 1, 2: x, y, z), ``lo`` the first cell's low face [m],
    ``cell`` the cells' width [m] (at least the support), ``n_cells`` of them, ``cuts`` the first
    cell of each rank after the first, and whether the axis is ``periodic``."""

    axis: int
    lo: float
    cell: float
    n_cells: int
    cuts: tuple
    periodic: bool

    @property
    def ranks(self) -> int:
        return len(self.cuts) + 1

    def bounds(self) -> list:
        """Each rank's cells, [first, last + 1)."""
        edges = [0, *self.cuts, self.n_cells]
        return list(zip(edges[:-1], edges[1:]))

    def cell_of(self, pos: np.ndarray) -> np.ndarray:
        """The cell along the axis of each position (n x dim or n x 3)."""
        c = np.floor((np.asarray(pos)[:, self.axis] - self.lo) / self.cell).astype(np.int64)
        return np.mod(c, self.n_cells) if self.periodic else np.clip(c, 0, self.n_cells - 1)

    def rank_of(self, pos: np.ndarray) -> np.ndarray:
        """The rank that owns each position."""
        return np.searchsorted(np.asarray(self.cuts, dtype=np.int64), self.cell_of(pos), side="right")

    def halos(self, pos: np.ndarray, width: "float | None" = None) -> list:
        """For each rank, the indices of the particles it does not own within ``width`` (one cell by
        default: the cell next to each end of its slab) of its slab along the axis, across the
        period where the axis is periodic: its halo, in index order."""
        width = self.cell if width is None else width
        x, owner = np.asarray(pos)[:, self.axis], self.rank_of(pos)
        span = self.n_cells * self.cell
        out = []
        for rank, (first, end) in enumerate(self.bounds()):
            below = self.lo + first * self.cell - x  # how far below the slab's low face
            above = x - (self.lo + end * self.cell)  # how far above its high face
            if self.periodic:
                below, above = np.mod(below, span), np.mod(above, span)
            near = ((below > 0.0) & (below <= width)) | ((above >= 0.0) & (above < width))
            out.append(np.flatnonzero(near & (owner != rank)))
        return out

    def counts(self, pos: np.ndarray, spread: float = 0.0) -> np.ndarray:
        """The particles each rank owns (``split``'s ``spread``: each spread over that length)."""
        return self.per_rank(_below(self, pos, spread))

    def per_rank(self, below: np.ndarray) -> np.ndarray:
        """The particles each rank's cells hold, from ``below``, the particles below each cell face."""
        return np.array([below[end] - below[first] for first, end in self.bounds()])

    def recut(self, pos: np.ndarray, ranks: "int | None" = None, spread: float = 0.0) -> "Slabs":
        """The same cells cut for ``ranks`` ranks (as many as now by default) where the particles at
        ``pos`` balance (``split``): each cut on the face nearest its share, every slab at least
        MIN_CELLS across. A rebalance moves the cuts by whole cells and keeps the cells."""
        return self.cut_at(_below(self, pos, spread), self.ranks if ranks is None else ranks)

    def cut_at(self, below: np.ndarray, ranks: int) -> "Slabs":
        """The same cells cut for ``ranks`` ranks from ``below``, the particles below each cell face
        (n_cells + 1 of them; ranks count their own and add them up): ``recut``."""
        cuts, first = [], 0
        for r in range(1, ranks):
            faces = np.arange(first + MIN_CELLS, self.n_cells - (ranks - r) * MIN_CELLS + 1)
            first = int(faces[np.argmin(np.abs(below[faces] - below[-1] * r / ranks))])
            cuts.append(first)
        return Slabs(axis=self.axis, lo=self.lo, cell=self.cell, n_cells=self.n_cells, cuts=tuple(cuts),
                     periodic=self.periodic)

    def imbalance(self, pos: np.ndarray) -> float:
        """How far the fullest rank's particles exceed the mean, as a fraction of it."""
        counts = np.bincount(self.rank_of(pos), minlength=self.ranks)
        return float(counts.max() / max(counts.mean(), 1.0e-300) - 1.0) if len(pos) else 0.0

    def rebalanced(self, pos: np.ndarray, threshold: float) -> "Slabs":
        """These slabs cut again (``recut``) where the fullest rank holds more than ``threshold`` (a
        fraction) over the mean; else these."""
        return self.recut(pos) if self.imbalance(pos) > threshold else self

    def describe(self) -> str:
        """The cuts, as a run's first line says them: the axis and each cut's position [m]."""
        if not self.cuts:
            return f"one slab, {self.n_cells} cells of {self.cell:.4g} m along {'xyz'[self.axis]}"
        where = ", ".join(f"{self.lo + c * self.cell:.4g}" for c in self.cuts)
        return f"slabs along {'xyz'[self.axis]}, {self.n_cells} cells of {self.cell:.4g} m, cut at {where} m"


def split(pos: np.ndarray, lo, hi, periodic, support: float, ranks: int, axis: "int | None" = None,
          spread: float = 0.0) -> Slabs:
    """Slabs for ``ranks`` ranks of the particles at ``pos`` (n x 3) in the domain [lo, hi] (the
    particles' own bounds where they reach past it: the walls' layers), cells at least ``support``
    [m] wide, along ``axis`` or the domain's longest: each cut on the cell face where the particles
    below it come nearest to its share of them, every slab at least MIN_CELLS across. ``spread``:
    each particle counted as spread evenly over that length about it (a coarser lattice standing
    for a finer one: its planes would otherwise fall into some cells and miss others). ConfigError
    on ``ranks`` where the axis has too few cells."""
    pos = np.asarray(pos, dtype=float)
    dim = pos.shape[1]
    if not isinstance(ranks, (int, np.integer)) or ranks < 1:
        raise ConfigError("ranks", ranks, "a whole number of at least 1")
    if axis is None:
        axis = int(np.argmax([float(hi[ax]) - float(lo[ax]) for ax in range(dim)]))
    wrap = bool(periodic[axis])
    low, high = float(lo[axis]), float(hi[axis])
    if not wrap and len(pos):  # the walls' layers lie outside the tank
        low, high = min(low, float(pos[:, axis].min())), max(high, float(np.nextafter(pos[:, axis].max(), np.inf)))
    # a span of whole supports is that many cells, not one fewer from rounding (2.0 // 0.1 is 19)
    n_cells = max(1, int(np.floor((high - low) / support * (1.0 + 1.0e-12))))
    most = n_cells // MIN_CELLS
    if ranks > max(1, most):
        raise ConfigError("ranks", ranks, f"at most {max(1, most)}: {'xyz'[axis]} spans {n_cells} cells of "
                          f"{(high - low) / n_cells:.4g} m (each at least a neighbour's reach), and a rank "
                          f"needs at least {MIN_CELLS}")
    cells = Slabs(axis=axis, lo=low, cell=(high - low) / n_cells, n_cells=n_cells, cuts=(), periodic=wrap)
    return cells.recut(pos, ranks, spread)


def _below(slabs: Slabs, pos: np.ndarray, spread: float) -> np.ndarray:
    """The particles below each cell face (n_cells + 1 of them; ``split``'s ``spread``): with a
    spread s, sum_i clip((f - x_i) / s + 1/2, 0, 1) at face f, the difference over s of the
    integral G(t) = sum_i max(0, t - x_i), which sorted prefix sums give at every face at once."""
    if spread <= 0.0:
        counts = np.bincount(slabs.cell_of(pos), minlength=slabs.n_cells)
        return np.concatenate([[0], np.cumsum(counts)])
    x = pos[:, slabs.axis]
    if slabs.periodic:  # into the period: a particle spread over its end counts at that end
        x = slabs.lo + np.mod(x - slabs.lo, slabs.n_cells * slabs.cell)
    x = np.sort(x)
    prefix = np.concatenate([[0.0], np.cumsum(x)])
    faces = slabs.lo + np.arange(slabs.n_cells + 1) * slabs.cell

    def integral(t):
        k = np.searchsorted(x, t)
        return k * t - prefix[k]

    below = (integral(faces + 0.5 * spread) - integral(faces - 0.5 * spread)) / spread
    below[0], below[-1] = 0.0, len(x)
    return below


def exchange_bytes(halo: int, scalar_bytes: int) -> int:
    """The bytes one rank receives a step to refresh a halo of ``halo`` particles (the module's
    docstring): its state before each force evaluation and, once, what a particle carries with it."""
    return halo * (STATE_SCALARS * scalar_bytes + IDENTITY_SCALARS * scalar_bytes + IDENTITY_BYTES)
