"""Launching the heavy passes on every core of a CPU.

Warp runs a CPU kernel on one thread, and its ctypes call releases the GIL, so a pass whose
threads are independent can be cut into chunks launched from a thread pool, one per core. Each
such kernel takes ``chunk, stride`` as its last two arguments. On a GPU the whole range goes in
one launch.

Chunks are strided, not contiguous: particle = wp.tid() * stride + chunk. Fluid and boundary
particles cost very different amounts and lie in separate index ranges, so contiguous halves
would leave one core idle. A kernel that reduces (maxima) keeps one slot per chunk, because CPU
atomics are not atomic across these threads.

Under the strict CPU mode (device_calls.strict) the chunks run one after the other in reverse
order, as a GPU may run its blocks: a pass whose result depends on the order its threads run in
then gives other bits on 1, 2 and 3 threads (tests/test_determinism.py).
"""
import contextlib
import os
from concurrent.futures import ThreadPoolExecutor

import warp as wp


def usable_cores() -> int:
    """The cores this process may run on: its CPU affinity where the system has one (taskset, a
    container's cpuset, a test worker pinned to a core), not every core of the machine."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return os.cpu_count() or 1


class Launcher:
    # set by device_calls.strict: chunks one after the other, last first
    reverse_chunks = False

    def __init__(self, device, threads: int = 0):
        self.device = device
        if not device.is_cpu:
            threads = 1
        self.threads = max(1, threads or usable_cores())
        self._pool = ThreadPoolExecutor(self.threads) if self.threads > 1 else None
        self._loaded = set()
        self._serial = False

    @contextlib.contextmanager
    def serial(self):
        """Every launch from the calling thread, in one piece: a graph capture records only the
        launches of the thread that captures (graph.py)."""
        self._serial = True
        try:
            yield
        finally:
            self._serial = False

    def __call__(self, kernel, n: int, inputs: list):
        if self._pool is None or self._serial or n < 2 * self.threads or kernel not in self._loaded:
            # one thread; a kernel's first launch also loads its module, which must not race
            wp.launch(kernel, dim=n, inputs=[*inputs, 0, 1], device=self.device)
            self._loaded.add(kernel)
            return
        k = self.threads
        if Launcher.reverse_chunks:
            for chunk in reversed(range(k)):
                wp.launch(kernel, dim=(n - chunk + k - 1) // k, inputs=[*inputs, chunk, k], device=self.device)
            return
        futures = [self._pool.submit(wp.launch, kernel, dim=(n - chunk + k - 1) // k, inputs=[*inputs, chunk, k],
                                     device=self.device)
                   for chunk in range(k)]
        for f in futures:
            f.result()
