"""Sums over the particles in an order fixed by their count alone: per-block partial sums, then a
sum of those, so that a device repeats its sums bit for bit.

A float sum's bits depend on the order of its terms. A GPU adds atomically in whatever order its
threads arrive, so an atomic float sum (a body's force, the fluid's energy) differs in its last
bits from run to run there, and a flow amplifies that: a floating body would not repeat, nor
would a recording. Here a summing pass is one kernel over ``Partials.count`` blocks of SPAN
particles. Thread k sums its block's particles one after another into its row of ``part``, one
slot per quantity (a body's force and torque, a column, a pressure block), with a plain write:
one thread owns a row, so no atomic is needed. ``Partials.total`` then adds each slot's block sums
in block order. GPUSPH and DualSPHysics reduce the same way: per-block partials, then a pass over
them.

Which particles make block k (``member``) is fixed by n and the device: on a CPU SPAN neighbouring
particles, which one thread reads in turn from contiguous memory; on a GPU particles k, k + count,
..., so that a warp's threads read neighbouring particles at once (coalesced). A CPU and a GPU
therefore sum in different orders, each repeatably, and on a CPU the result does not depend on how
many threads share the blocks (launch.py).
"""
import functools

import warp as wp

SPAN = 256  # particles a block sums in turn


@wp.func
def member(k: int, j: int, lead: int, step: int) -> int:
    """The j-th particle of block k (Partials: lead and step)."""
    return k * lead + j * step


@functools.lru_cache(maxsize=None)
def _total(dtype):
    @wp.kernel(enable_backward=False, module="unique")
    def total(part: wp.array2d(dtype=dtype), out: wp.array(dtype=dtype), offset: int, add: int):
        """out[offset + s] = (out[offset + s] if add else 0) + the block sums of slot s, in block order."""
        s = wp.tid()
        acc = part[0, s]
        for k in range(1, part.shape[0]):
            acc = acc + part[k, s]
        if add != 0:
            acc = out[offset + s] + acc
        out[offset + s] = acc

    return total


class Partials:
    """The block sums of ``slots`` quantities of type ``dtype`` over ``n`` particles on ``device``.
    A summing kernel takes ``args()`` (part, lead, step), runs ``count`` threads, and writes every
    slot of its row ``part[k]``; ``total`` finishes the sums."""

    def __init__(self, n: int, slots: int, dtype, device):
        self.count = max(1, -(-n // SPAN))
        self.slots = slots
        self.device = wp.get_device(device)
        self.lead, self.step = (SPAN, 1) if self.device.is_cpu else (1, self.count)
        self.part = wp.zeros((self.count, max(1, slots)), dtype=dtype, device=self.device)
        self._total = _total(dtype)

    def args(self) -> list:
        return [self.part, self.lead, self.step]

    def total(self, out: wp.array, offset: int = 0, add: bool = False):
        """out[offset:offset + slots] = the sums (added to what it holds with ``add``)."""
        wp.launch(self._total, dim=self.slots, inputs=[self.part, out, offset, int(add)], device=self.device)
