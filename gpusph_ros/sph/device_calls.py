"""Counting what a block of code asks of the Warp device: kernel launches, sorts, scans, copies,
fills, host reads (a read of device memory or a wait for the device), allocations, graph replays
and branch reads, by wrapping Warp's own functions while the block runs. The step-count test
(tests/test_step_counts.py) and the GPU check (bench/step_counts.py) read a step through it; a
replayed graph's launches happen inside Warp and count as one replay.

What ``Solver._sync`` reads (the clock, step counts and health flags once an output) is counted as
syncs, not as host reads, so that a read anywhere else stands out.
"""
import collections
import contextlib

import warp as wp

KINDS = ("launch", "sort", "scan", "copy", "fill", "host_read", "allocation", "replay", "sync")


@contextlib.contextmanager
def counting(solver_class=None):
    """Yields a Counter by kind (KINDS) of what the wrapped Warp functions are asked while the block
    runs; with ``solver_class`` (Solver), its _sync calls count as "sync" and what they read does not
    count."""
    counts = collections.Counter()
    undo = []
    in_sync = []

    def wrap(owner, name, kind):
        original = getattr(owner, name)

        def counted(*args, **kwargs):
            if not in_sync:
                counts[kind] += 1
            if kind != "sync":
                return original(*args, **kwargs)
            in_sync.append(True)
            try:
                return original(*args, **kwargs)
            finally:
                in_sync.pop()

        setattr(owner, name, counted)
        undo.append((owner, name, original))

    wrap(wp, "launch", "launch")
    wrap(wp.utils, "radix_sort_pairs", "sort")
    wrap(wp.utils, "array_scan", "scan")
    wrap(wp, "copy", "copy")
    wrap(wp.array, "fill_", "fill")
    wrap(wp.array, "zero_", "fill")
    wrap(wp.array, "numpy", "host_read")
    for name in ("synchronize", "synchronize_device", "synchronize_stream"):
        wrap(wp, name, "host_read")
    wrap(wp, "capture_launch", "replay")
    allocators = {type(d.get_allocator()) for d in wp.get_devices()}
    for allocator in allocators:
        wrap(allocator, "allocate", "allocation")
    if solver_class is not None:
        wrap(solver_class, "_sync", "sync")
    try:
        yield counts
    finally:
        for owner, name, original in reversed(undo):
            setattr(owner, name, original)
