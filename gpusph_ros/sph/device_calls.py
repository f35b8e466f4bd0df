"""Counting what a block of code asks of the Warp device: kernel launches, sorts, scans, copies,
fills, host reads (a read of device memory or a wait for the device), allocations, graph replays
and branch reads, by wrapping Warp's own functions while the block runs. The step-count test
(tests/test_step_counts.py) and the GPU check (bench/step_counts.py) read a step through it; a
replayed graph's launches happen inside Warp and count as one replay.

What ``Solver._sync`` reads (the clock, step counts and health flags once an output) is counted as
syncs, not as host reads, so that a read anywhere else stands out. A branch read is a flag that
``wp.capture_if`` or ``wp.capture_while`` (each pass of its loop, and the test that ends it) takes
to the host outside a capture: free on a CPU, a copy and a wait for the stream on a GPU.

``strict`` makes a CPU run fail where a GPU would refuse or reorder: Warp's CPU device runs a
kernel's threads one after another and a CPU capture only records calls, which hides both.
"""
import collections
import contextlib

import warp as wp

from .launch import Launcher

# Warp utilities that allocate device scratch memory at every call on CUDA (warp/native/scan.cu,
# reduce.cu, runlength_encode.cu: wp_alloc_device), which CUDA refuses inside a captured
# conditional body. radix_sort_pairs is not among them: sort.cu keeps its scratch across captures
# (a side allocation, cached).
ALLOCATING = ("array_scan", "array_sum", "array_inner", "runlength_encode")


class GpuRefusal(AssertionError):
    """What a GPU would refuse, met on the CPU under ``strict``."""

KINDS = ("launch", "sort", "scan", "copy", "fill", "host_read", "allocation", "replay", "sync", "branch")


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
    capturing = []
    enter, leave = wp.ScopedCapture.__enter__, wp.ScopedCapture.__exit__

    def entered(self):
        capturing.append(True)
        return enter(self)

    def left(self, *exc):
        capturing.pop()
        return leave(self, *exc)

    def branch(name, reads):
        original = getattr(wp, name)

        def read(*args, **kwargs):
            if capturing or in_sync:  # recorded, not read; a sync's own reads are the sync's
                return original(*args, **kwargs)
            counts["branch"] += 1
            return original(*reads(*args), **kwargs)

        setattr(wp, name, read)
        undo.append((wp, name, original))

    def each_pass(condition, body, *rest):  # capture_while reads its flag again after each pass of its body
        def counted_body(*a, **kw):
            counts["branch"] += 1
            return body(*a, **kw)

        return (condition, counted_body, *rest)

    for owner, name, replacement in ((wp.ScopedCapture, "__enter__", entered), (wp.ScopedCapture, "__exit__", left)):
        undo.append((owner, name, getattr(owner, name)))
        setattr(owner, name, replacement)
    branch("capture_if", lambda *args: args)
    branch("capture_while", each_pass)
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


@contextlib.contextmanager
def strict():
    """The strict CPU mode: while the block runs,

    - inside a captured region (a ``wp.ScopedCapture``, or the body of a ``wp.capture_if`` or
      ``wp.capture_while``, which a GPU with conditional graph nodes replays from a capture even where
      this run steps eagerly) an allocation, a Warp utility that allocates on CUDA (ALLOCATING) or a
      host read raises GpuRefusal naming it;
    - a heavy pass's chunks (launch.py) run one after the other, last first, so that a pass whose
      result depends on the order its threads run in gives other bits on 1, 2 and 3 threads.
    """
    depth = [0]
    undo = []

    def patch(owner, name, replacement):
        undo.append((owner, name, getattr(owner, name)))
        setattr(owner, name, replacement)

    def region(owner, name):
        original = getattr(owner, name)

        def inside(*args, **kwargs):
            depth[0] += 1
            try:
                return original(*args, **kwargs)
            finally:
                depth[0] -= 1

        patch(owner, name, inside)

    def refused(owner, name, what):
        original = getattr(owner, name)

        def guarded(*args, **kwargs):
            if depth[0]:
                raise GpuRefusal(f"{what} ({getattr(owner, '__name__', type(owner).__name__)}.{name}) inside a "
                                 f"captured region: CUDA refuses it there")
            return original(*args, **kwargs)

        patch(owner, name, guarded)

    region(wp, "capture_if")
    region(wp, "capture_while")
    enter, leave = wp.ScopedCapture.__enter__, wp.ScopedCapture.__exit__

    def entered(self):
        depth[0] += 1
        return enter(self)

    def left(self, *exc):
        depth[0] -= 1
        return leave(self, *exc)

    patch(wp.ScopedCapture, "__enter__", entered)
    patch(wp.ScopedCapture, "__exit__", left)
    for name in ALLOCATING:
        refused(wp.utils, name, "a Warp utility that allocates device memory at every call")
    for allocator in {type(d.get_allocator()) for d in wp.get_devices()}:
        refused(allocator, "allocate", "an allocation")
    refused(wp.array, "numpy", "a host read")
    undo.append((Launcher, "reverse_chunks", Launcher.reverse_chunks))
    Launcher.reverse_chunks = True
    try:
        yield
    finally:
        for owner, name, original in reversed(undo):
            setattr(owner, name, original)
