"""What a pressure transducer reports between two outputs: its face's mean pressure (sensors.py)
read at every step, as gauge pressure, through its own response, and averaged over the steps since
the last output.

One step's reading scatters: on a 3D dam break at 3 cm a face sensor sampled at the step an output
falls on jumped by +-5 kPa around a 4 kPa mean from one 10 ms output to the next, where the
transducer behind the measurement reads a smooth trace. So, as the wrench (forces.py), a sensor
by default publishes the mean over the steps since the last output, each step weighted by its
length (``sampling: mean``); ``sampling: step`` publishes the output step's reading alone.

A gauge-pressure transducer in a splash reads 0, not the fluid's tension, and the measurements
we compare with (Lobovsky et al. 2014; De Courcy et al. 2024) clip their series at 0. So each step's
reading is clipped at 0 before it is averaged (``clip: true``, the default); ``clip: false``
keeps the sign. ``response`` [s] is a first-order transducer's time constant tau: each step of
length dt moves the reading y toward the face's pressure x by y += (1 - exp(-dt / tau)) (x - y),
the exact step of tau dy/dt = x - y for x held over it; 0, the default, is an ideal transducer.

Every step adds on the device; a failed step adds nothing (its state is not kept), as in forces.py.
The step's reading is of the state it ends on (solver.fields), through the cells of the lists'
build, which hold every particle within a kernel support of a point until the lists go stale
(neighbours.py) and so for the step that makes them stale too; daughters spawned in a refinement
zone in that step join the cells at the next build.
"""
import functools

import numpy as np
import warp as wp

from ..sph import health
from ..sph.state import DT
from .probes import PointProbes
from .ranks import Alone
from .sensors import SMOOTHED_WIDEN, WallPressure

SAMPLINGS = ("mean", "step")


@functools.lru_cache(maxsize=None)
def build(scalar):
    healthy = health.build(scalar).healthy

    @wp.kernel(enable_backward=False, module="unique")
    def transduce(pressure: wp.array(dtype=scalar), weight: wp.array(dtype=scalar), drop: wp.array(dtype=scalar),
                  clip_points: int, first: wp.array(dtype=wp.int32), last: wp.array(dtype=wp.int32),
                  clip: wp.array(dtype=wp.int32), tau: wp.array(dtype=wp.float64), timed: int, stride: int,
                  fail: wp.array(dtype=wp.int32), clock: wp.array(dtype=wp.float64), now: wp.array(dtype=wp.float64),
                  filtered: wp.array(dtype=wp.float64), primed: wp.array(dtype=wp.int32),
                  impulse: wp.array(dtype=wp.float64), span: wp.array(dtype=wp.float64)):
        """Sensor s's face mean now (its points first[s]..last[s]; a dry point reads 0, a point's
        reading clipped at 0 where ``clip_points``), clipped at 0 where clip[s]; ``timed``: also the
        step's part of the response and of the mean (a failed step adds nothing). One thread a
        sensor: the same sums in any order of the threads."""
        s = wp.tid()
        total = wp.float64(0.0)
        for k in range(first[s], last[s]):
            v = scalar(0.0)
            if weight[k] > scalar(0.0):
                v = pressure[k] - drop[k]
            if clip_points != 0:
                v = wp.max(v, scalar(0.0))
            total = total + wp.float64(v)
        x = total / wp.float64(last[s] - first[s])
        if clip[s] != 0:
            x = wp.max(x, wp.float64(0.0))
        now[s] = x
        if timed == 0:
            return
        if not healthy(fail) or clock[DT] <= wp.float64(0.0):
            return
        dt = wp.float64(stride) * clock[DT]
        y = x
        if tau[s] > wp.float64(0.0) and primed[s] != 0:
            y = filtered[s] + (wp.float64(1.0) - wp.exp(-dt / tau[s])) * (x - filtered[s])
        filtered[s] = y
        primed[s] = 1
        impulse[s] = impulse[s] + dt * y
        span[s] = span[s] + dt

    return transduce


class Transducers:
    """Pressure sensors of one reading (sensors.py): ``sensors`` is a list of (name, points, normals,
    sampling, clip, response); ``smoothed``: each read as the converged reference reads its own (the
    fluid at the face, a kernel SMOOTHED_WIDEN times as wide, each point clipped at 0), else by the
    wall model's reading (WallPressure). ``sample()``: {name: pressure [Pa]}."""

    def __init__(self, solver, sensors, smoothed: bool, across=None):
        self.solver = solver
        self.across = across or Alone(solver)
        self.names = [name for name, *_ in sensors]
        self._points = points = np.concatenate([np.asarray(pts, dtype=np.float64).reshape(-1, 3)
                                                for _, pts, *_ in sensors])
        normals = np.concatenate([np.asarray(nrm, dtype=np.float64).reshape(-1, 3) for _, _, nrm, *_ in sensors])
        counts = np.array([len(np.asarray(pts).reshape(-1, 3)) for _, pts, *_ in sensors])
        if smoothed:
            self._source, drop = PointProbes(solver, points, SMOOTHED_WIDEN, across), np.zeros(len(points))
        else:
            self._source = WallPressure(solver, points, normals, across)
            drop = self._source.drop
        self._clip_points = int(smoothed)
        self.sampling = [sampling for *_, sampling, _, _ in sensors]
        dev, k = solver.device, len(sensors)
        i32 = lambda values: wp.array(np.asarray(values, dtype=np.int32), dtype=wp.int32, device=dev)  # noqa: E731
        self._drop = wp.array(drop, dtype=solver.scalar, device=dev)
        self._first, self._last = i32(np.cumsum(counts) - counts), i32(np.cumsum(counts))
        self._clip = i32([bool(clip) for *_, clip, _ in sensors])
        tau = np.asarray([float(r) for *_, r in sensors])
        self._lagged = tau > 0.0  # the sensors with a response
        self._tau = wp.array(tau, dtype=wp.float64, device=dev)
        self._now, self._filtered, self._impulse, self._span = (wp.zeros(k, dtype=wp.float64, device=dev)
                                                                for _ in range(4))
        self._primed = wp.zeros(k, dtype=wp.int32, device=dev)
        self._kernel = build(solver.scalar)
        self.across.each_step(self._add)

    def _read(self, view, timed: bool):
        s = self.solver
        pressure, weight = self._source.launch(view)
        if self.across.ranked:  # each point as its owner reads it, on every rank (ranks.py)
            for a in (pressure, weight):
                a.assign(self.across.pick(a.numpy(), self._points))
        wp.launch(self._kernel, dim=len(self.names),
                  inputs=[pressure, weight, self._drop, self._clip_points, self._first, self._last, self._clip,
                          self._tau, int(timed), s.params.coarse_stride, s.failures, s.clock, self._now,
                          self._filtered, self._primed, self._impulse, self._span], device=s.device)

    def _add(self):
        s = self.solver
        self._read((s.params, s.fields, s.neighbours), True)

    def restart(self):
        """Forget the steps so far and the response's memory (a restored state)."""
        for a in (self._impulse, self._span, self._filtered, self._primed):
            a.zero_()

    def sample(self) -> dict:
        """Each sensor's reading now: the mean over the steps since the last sample (its reading
        now where no step was taken since), or the reading at this step (``sampling: step``); through
        its response where it has one and a step was taken."""
        self._read(self.across.view(), False)
        # copies: on the CPU numpy() is a view of the device's memory, which zero_() clears
        now, span, impulse = (a.numpy().copy() for a in (self._now, self._span, self._impulse))
        held = np.where(self._lagged & (self._primed.numpy() != 0), self._filtered.numpy(), now)
        self._impulse.zero_()
        self._span.zero_()
        out = {}
        for k, name in enumerate(self.names):
            mean = impulse[k] / span[k] if span[k] > 0.0 else held[k]
            out[name] = float(mean if self.sampling[k] == "mean" else held[k])
        return out
