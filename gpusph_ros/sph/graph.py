"""The step loop captured once and replayed: what lets a GPU run the step at full speed.

A step is about a dozen launches (passes.py), and at 10^5 particles on a GPU the host's time to
issue them is as long as the kernels themselves. Every decision in the loop is taken on the device
(solver.py: the clock's TARGET, the loop's flags), so the whole loop to an output, ``wp.capture_while``
on its RUNNING flag with each step's branches (``wp.capture_if``: reorder, list build, census,
Shepard filter), is captured once (``wp.ScopedCapture``) and replayed with one ``wp.capture_launch``
per output: a CUDA graph with conditional nodes on a GPU, Warp's API capture on a CPU. A replay
takes the same steps as the eager loop, bit for bit (tests/test_graph.py).

What a capture holds is fixed when it is made: the kernels' struct arguments (Params, the grid, the
fields) by value and every array by address. A reconfigure (new Params) or a new step hook drops it;
arrays are never reallocated during a run, and a restored checkpoint is copied into them. On a CPU
a captured loop runs every pass on one core (the heavy passes' chunks, launch.py, are recorded one
after the other), so ``step_graph: auto`` replays on a GPU and on a CPU that runs on one thread
anyway. Measured (2-core CPU, float32, one run after the other, docs/results/speed.md): DamBreak 1
lab at 3 cm, 122 steps, eager on 2 threads 2.12 s, replayed 3.51 s; on one thread 3.50 s and
3.46 s; a 2D column of 900 particles to 0.08 s, 0.31 s eager and 0.09 s replayed.
"""
import warp as wp

from .state import RUNNING

STEP_GRAPHS = ("auto", "on", "off")


def wanted(setting: str, device, threads: int) -> bool:
    """Whether a loop is replayed from a capture under ``step_graph`` = setting on ``device``, whose
    heavy passes run on ``threads`` threads. A GPU whose driver has no conditional graph nodes (CUDA
    before 12.4) steps eagerly under ``auto``; ``on`` there raises Warp's error naming the driver."""
    if setting == "auto":
        return (device.is_cuda and wp.is_conditional_graph_supported()) or (device.is_cpu and threads == 1)
    return setting == "on"


class LoopGraph:
    """The captured step loops of one solver, one per block size (steps before the device stops for
    the host), made on first use."""

    def __init__(self, solver):
        self._solver = solver
        self._graphs = {}

    def drop(self):
        """Forget every capture (what they hold has changed)."""
        self._graphs.clear()

    def run(self, block: int):
        """Replay the loop of ``block`` steps at most (solver.advance has aimed it)."""
        graph = self._graphs.get(block)
        if graph is None:
            graph = self._graphs[block] = self._capture(block)
        wp.capture_launch(graph)

    def _capture(self, block: int):
        s = self._solver
        # a CUDA driver may refuse to load a module mid-capture: load every kernel first (a branch
        # not yet taken, the Shepard filter, has not loaded its own); Warp's API capture on a CPU
        # loads as it records
        with s.launch.serial(), wp.ScopedCapture(s.device, force_module_load=s.device.is_cuda) as capture:
            wp.capture_while(s.flag(RUNNING), s.loop_body, block=block)
        return capture.graph
