"""Exclusive prefix sums of int32 arrays with their scratch allocated once: a scan that a captured
step loop may hold.

Warp 1.19's ``wp.utils.array_scan`` allocates its scratch at every call on a CUDA device
(warp/native/scan.cu, wp_alloc_device), and CUDA refuses an allocation inside a captured
conditional body: the refinement levels' scans (solver._relevel) run in the step's LISTS_HOLD
branch. This one is a blocked scan (Blelloch 1990, "Prefix sums and their applications", the
reduce-then-scan of blocks): each thread scans SPAN entries in turn and leaves their total; the
totals are scanned the same way, level above level, until one block holds them all; each level's
block offsets are then added back down. Integers add exactly, so any order of the threads gives
the same sums. log_span(n) levels, two launches each: on a CPU a thread scans SPAN entries (three
levels up to 16.7 million entries, few threads: a CPU has few); on a GPU GPU_SPAN, so that the
first level runs n / 8 threads (125,000 at 10^6 entries, where 256 gave 3,900: too few to hide a
GPU's memory latency), in 7 levels at 10^6.
"""
import functools
from types import SimpleNamespace

import warp as wp

SPAN = 256  # entries one thread scans in turn on a CPU
GPU_SPAN = 8  # ... on a GPU


def sizes(n: int, cuda: bool) -> list:
    """Entries at each level of a scan of ``n`` on a GPU (``cuda``) or a CPU: n, its blocks' totals,
    theirs ... down to one block's; each level after the first is a launch's threads."""
    span = GPU_SPAN if cuda else SPAN
    out = [n, -(-n // span)]
    while out[-1] > 1:
        out.append(-(-out[-1] // span))
    return out


@functools.lru_cache(maxsize=None)
def _passes():
    @wp.kernel(enable_backward=False, module="unique")
    def scan_blocks(src: wp.array(dtype=wp.int32), dst: wp.array(dtype=wp.int32),
                    totals: wp.array(dtype=wp.int32), span: int):
        """dst = the exclusive prefix sums of src within each block of ``span``; totals[b] = block b's sum."""
        b = wp.tid()
        n = src.shape[0]
        running = int(0)
        for k in range(span):
            i = b * span + k
            if i < n:
                v = src[i]
                dst[i] = running
                running = running + v
        totals[b] = running

    @wp.kernel(enable_backward=False, module="unique")
    def add_offsets(dst: wp.array(dtype=wp.int32), offsets: wp.array(dtype=wp.int32), span: int):
        i = wp.tid()
        dst[i] = dst[i] + offsets[i // span]

    return SimpleNamespace(scan_blocks=scan_blocks, add_offsets=add_offsets)


class Scan:
    """Exclusive prefix sums of int32 arrays of ``n`` entries on ``device``; the scratch of every
    level is allocated here, once. ``cuda`` picks the layout (the device's kind by default)."""

    def __init__(self, n: int, device, cuda: bool = None):
        self.n, self.device = n, device
        cuda = wp.get_device(device).is_cuda if cuda is None else cuda
        self._span = GPU_SPAN if cuda else SPAN
        self._sizes = sizes(n, cuda)
        levels = len(self._sizes) - 1
        # each level's block totals, and above the first the scanned totals of the level below
        self._totals = [wp.empty(m, dtype=wp.int32, device=device) for m in self._sizes[1:]]
        self._scanned = [wp.empty(m, dtype=wp.int32, device=device) for m in self._sizes[1:levels]]

    def __call__(self, src: wp.array, dst: wp.array):
        """dst[i] = src[0] + ... + src[i - 1] (dst[0] = 0)."""
        if src.shape[0] != self.n or dst.shape[0] != self.n:
            raise ValueError(f"scan: arrays of {self.n} entries, got {src.shape[0]} and {dst.shape[0]}")
        k = _passes()
        inputs, outputs = [src, *self._totals[:-1]], [dst, *self._scanned]
        for level, (a, b) in enumerate(zip(inputs, outputs)):
            wp.launch(k.scan_blocks, dim=self._sizes[level + 1], inputs=[a, b, self._totals[level], self._span],
                      device=self.device)
        # the top level is one block, scanned whole; each level below takes its blocks' offsets
        for level in reversed(range(len(outputs) - 1)):
            wp.launch(k.add_offsets, dim=self._sizes[level], inputs=[outputs[level], outputs[level + 1], self._span],
                      device=self.device)
