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
particles, which one thread reads in turn from contiguous memory; on a GPU GPU_SPAN particles k,
k + count, ..., so that a warp's threads read neighbouring particles at once (coalesced). A CPU
and a GPU therefore sum in different orders, each repeatably, and on a CPU the result does not
depend on how many threads share the blocks (launch.py).

A GPU needs tens of thousands of threads in flight to hide its memory's latency: with SPAN
particles a block it would run n / 256, 3,900 at 10^6 particles. So on a GPU a block is GPU_SPAN
particles (n / 8 threads, 125,000 at 10^6), and its many block sums are added as a tree of fixed
shape: each level adds FAN consecutive rows per thread, until at most FAN rows are left for
``total``'s one thread a slot. The shape depends on n alone, so a GPU repeats its sums bit for bit.
A CPU keeps one level (its threads are few, and the order is today's, bit for bit).
"""
import functools

import warp as wp

SPAN = 256  # particles a block sums in turn on a CPU
GPU_SPAN = 8  # ... on a GPU: n / 8 threads
FAN = 256  # rows of block sums one thread adds at each level of a GPU's tree


def layout(n: int, cuda: bool) -> dict:
    """How a sum over ``n`` particles is cut: the blocks (count, lead, step, span: ``member``) and,
    on a GPU, the rows at each level of the tree over their sums (the last at most FAN, which
    ``total`` adds); ``threads``, each launch's, in order."""
    span = GPU_SPAN if cuda else SPAN
    count = max(1, -(-n // span))
    rows = [count]
    while cuda and rows[-1] > FAN:
        rows.append(-(-rows[-1] // FAN))
    lead, step = (1, count) if cuda else (span, 1)
    return {"count": count, "lead": lead, "step": step, "span": span, "rows": rows,
            "threads": [count, *rows[1:]]}


@wp.func
def member(k: int, j: int, lead: int, step: int) -> int:
    """The j-th particle of block k (Partials: lead and step)."""
    return k * lead + j * step


@functools.lru_cache(maxsize=None)
def _fold(dtype):
    @wp.kernel(enable_backward=False, module="unique")
    def fold(src: wp.array2d(dtype=dtype), dst: wp.array2d(dtype=dtype)):
        """dst[r, s] = src[r FAN, s] + ... + src[r FAN + FAN - 1, s], in that order (a level of the tree)."""
        r, s = wp.tid()
        first = r * FAN
        acc = src[first, s]
        for j in range(1, FAN):
            if first + j < src.shape[0]:
                acc = acc + src[first + j, s]
        dst[r, s] = acc

    return fold


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
    A summing kernel takes ``args()`` (part, lead, step, members: the span), runs ``count`` threads, and writes
    every slot of its row ``part[k]``; ``total`` finishes the sums. ``cuda`` picks the layout (the
    device's kind by default; a CPU may sum as a GPU does, to check the GPU's layout here)."""

    def __init__(self, n: int, slots: int, dtype, device, cuda: bool = None):
        self.device = wp.get_device(device)
        cut = layout(n, self.device.is_cuda if cuda is None else cuda)
        self.count, self.lead, self.step, self.span = cut["count"], cut["lead"], cut["step"], cut["span"]
        self.slots = slots
        width = max(1, slots)
        self.part = wp.zeros((self.count, width), dtype=dtype, device=self.device)
        self._levels = [wp.zeros((rows, width), dtype=dtype, device=self.device) for rows in cut["rows"][1:]]
        self._fold = _fold(dtype)
        self._total = _total(dtype)

    def args(self) -> list:
        return [self.part, self.lead, self.step, self.span]

    def total(self, out: wp.array, offset: int = 0, add: bool = False):
        """out[offset:offset + slots] = the sums (added to what it holds with ``add``)."""
        last = self.part
        for level in self._levels:
            wp.launch(self._fold, dim=(level.shape[0], self.slots), inputs=[last, level], device=self.device)
            last = level
        wp.launch(self._total, dim=self.slots, inputs=[last, out, offset, int(add)], device=self.device)
