"""How a measurement adds up across the ranks of one run (issue 69 item 4; docs/ranks.md).

A rank holds its slab's particles and a halo (sph/exchange.py). After each step the halo holds its
owners' state, and a measurement reads it there (``each_step``, ``view``). So:
- **A reading at a point** (a probe, a gauge's line, a sensor's face, the wall pressure on a face)
  is whole on the rank that owns the point's cell: a reading reaches at most two cells from its
  point, and the halo is three deep. That rank's value is taken and every other rank gives 0
  (``pick``). It is one rank's value bit for bit: the same particles are summed in the same order.
- **A sum over particles** (a body's wrench, a pressure block, a column) counts each rank's own
  particles (``owned``), and the ranks' sums are added (``total``, in float64). It is one rank's
  sum to round-off, its terms added in another order.
- **A largest value** (a gauge's top particle) is the largest of the ranks' (``most``): exact.

One rank (``Alone``) adds nothing, and its step loop stays on the device.
"""
import numpy as np


class Alone:
    """A run on one solver: every reading is whole where it is taken."""

    ranked = 0

    def __init__(self, solver):
        self.solver = solver

    @property
    def owned(self):
        """The solver's owned-particle marks (state.Fields.owned), read where ``ranked``."""
        return self.solver.fields.owned

    def each_step(self, hook):
        self.solver.each_step(hook)

    def view(self):
        return self.solver.measurement_view()

    def pick(self, values, points):
        return values

    def total(self, values):
        return values

    def most(self, values):
        return values


class Across(Alone):
    """The measurements of ``ranks`` (sph.exchange.RankedRun), this rank's part of one run."""

    ranked = 1

    def __init__(self, ranks):
        from mpi4py import MPI

        super().__init__(ranks.solver)
        self.ranks, self.comm = ranks, ranks.comm
        self._ops = {"sum": MPI.SUM, "max": MPI.MAX}

    def each_step(self, hook):
        """``hook()`` after every step, once the halo is the owners' state again."""
        self.ranks.each_step(hook)

    def view(self):
        return self.ranks.view()

    def _reduce(self, values, op: str) -> np.ndarray:
        local = np.ascontiguousarray(values)
        out = np.empty_like(local)
        self.comm.Allreduce(local, out, op=self._ops[op])
        return out

    def pick(self, values, points):
        """``values`` (one row a point of ``points``, k x 3) as the rank that owns each point reads it."""
        values = np.asarray(values)
        mine = self.ranks.slabs.rank_of(np.asarray(points, dtype=np.float64).reshape(-1, 3)) == self.comm.rank
        return self._reduce(np.where(mine.reshape(-1, *[1] * (values.ndim - 1)), values, 0).astype(values.dtype),
                            "sum")

    def total(self, values):
        values = np.asarray(values)
        return self._reduce(values.astype(np.float64) if values.dtype.kind == "f" else values, "sum")

    def most(self, values):
        return self._reduce(np.asarray(values), "max")
