"""Free-surface elevation at a gauge: going up a vertical line from the floor, the first height
where the fluid's kernel sum sum_b W(x - x_b) m_b / rho_b falls below 1/2 after the line was
wet, the level a free surface has halfway through the kernel's reach. This is DualSPHysics'
GaugeSwl (JGaugeSwl::CalculeCpuT: from point0 up to the first fluid-to-empty change, mass limit
half a particle's mass): spray and an overturning jet above an air pocket are not the water at
the gauge. The line is sampled every dx/4 with the point probes' interpolation on the device.

GaugeSwl reads the first wet stretch wherever it starts, so over a dry floor a clump of spray is
the surface: behind a box hit by a surge a gauge read 0.4 m of water at 0.62 s where the measured
level stayed dry until 0.9 s. Here the water must stand on the floor under the gauge (the tank's,
or the top of a fixed obstacle it stands over, ``floor_under``): a line whose first wet point is
more than a kernel support (2h) above that floor reads 0, as a dry gauge does.

``reading: top`` (``TopLevels``) reads, as gauges often did before GaugeSwl, the top of the
highest fluid particle within a spacing of the line: its height plus half a spacing.
"""
import functools

import numpy as np
import warp as wp

from ..sph.state import FLUID
from .probes import PointProbes
from .ranks import Alone

LEVEL = 0.5
SAMPLES_PER_DX = 4


def gauge_points(position, top: float, dx: float, dim: int) -> np.ndarray:
    """Sample points of a gauge at horizontal ``position`` from the floor to ``top``."""
    heights = np.arange(0.0, top + 1e-12, dx / SAMPLES_PER_DX)
    pts = np.repeat(np.asarray(position, dtype=np.float64).reshape(1, 3), len(heights), axis=0)
    pts[:, dim - 1] = heights
    return pts


def floor_under(position, obstacles, dim: int) -> float:
    """The height of what the water under a gauge at horizontal ``position`` stands on: the top of
    the highest fixed obstacle standing on the floor whose footprint holds the position, else 0."""
    up = dim - 1
    tops = [o.hi[up] for o in obstacles if o.motion is None and o.lo[up] <= 1e-9
            and all(o.lo[ax] <= position[ax] <= o.hi[ax] for ax in range(up))]
    return max(tops, default=0.0)


def elevation(heights: np.ndarray, weight: np.ndarray, floor: float = None, reach: float = 0.0) -> float:
    """The first height above a wet point where ``weight`` falls below LEVEL, interpolated
    linearly; the top of the line when it never falls; 0 for a dry gauge. With a ``floor``, water
    whose first wet point is more than ``reach`` above it is not standing on it: 0 (spray)."""
    wet = weight >= LEVEL
    if not wet.any():
        return 0.0
    first = int(np.argmax(wet))
    if floor is not None and heights[first] > floor + reach:
        return 0.0
    dry = np.nonzero(~wet[first:])[0]
    if len(dry) == 0:
        return float(heights[-1])
    k = first + int(dry[0]) - 1  # the last wet point below the first fall
    w0, w1 = weight[k], weight[k + 1]
    return float(heights[k] + (heights[k + 1] - heights[k]) * (w0 - LEVEL) / (w0 - w1))


class Gauges:
    """Gauges at many horizontal ``positions`` (k x 3, the vertical coordinate ignored), each a line
    from ``bottom``, which must be under the water, to ``top``: the mean of their elevations is the
    level over a region. Neither the top particle of each dx-wide column plus dx/2 (in 3D at 2 cm a
    dx-square column often lacks the top layer's particle, and that level read up to a spacing low
    about a floating box) nor the fluid's volume over the area (the fluid stands off the walls and
    the floor: 1.6 mm low in 2D at 1 cm) reads it without a bias (docs/results/bodies.md)."""

    def __init__(self, solver, positions, bottom: float, top: float, dx: float):
        up = solver.config.dim - 1
        self.heights = np.arange(bottom, top + 1e-12, dx / SAMPLES_PER_DX)
        pts = np.repeat(np.asarray(positions, dtype=np.float64).reshape(-1, 1, 3), len(self.heights), axis=1)
        pts[:, :, up] = self.heights
        self.count = pts.shape[0]
        self._probes = PointProbes(solver, pts.reshape(-1, 3))

    def elevations(self) -> np.ndarray:
        """Each gauge's elevation now."""
        weight = self._probes.sample()["weight"].reshape(self.count, -1)
        return np.array([elevation(self.heights, w) for w in weight])


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.kernel(enable_backward=False, module="unique")
    def top_heights(up: int, centres: wp.array(dtype=vec), radius2: wp.array(dtype=scalar),
                    pos: wp.array(dtype=vec), ptype: wp.array(dtype=wp.int32), top: wp.array(dtype=scalar)):
        """The highest fluid particle within each line's radius (an atomic max: the same in any
        order of the threads)."""
        i = wp.tid()
        if ptype[i] != FLUID:
            return
        for c in range(centres.shape[0]):
            d = pos[i] - centres[c]
            d[up] = scalar(0.0)
            if wp.dot(d, d) <= radius2[c]:
                wp.atomic_max(top, c, pos[i][up])

    return top_heights


DRY = -1.0e30  # no fluid particle near the line


class TopLevels:
    """Gauges (schema Probes of ``reading: top``) that read the top of the highest fluid particle
    within one ``spacing`` (one per gauge) of their vertical line: its height plus half a spacing;
    0 where no fluid is near. ``across``: how the ranks of a run find the highest (ranks.py)."""

    def __init__(self, solver, probes, spacings, across=None):
        self.solver = solver
        self.across = across or Alone(solver)
        self.names = [p.name for p in probes]
        self.half = 0.5 * np.asarray(spacings, dtype=np.float64)
        dev = solver.device
        self._kernel = build(solver.scalar)
        self._centres = wp.array(np.asarray([p.position for p in probes], dtype=np.float64), dtype=solver.vec,
                                 device=dev)
        self._radius2 = wp.array(np.asarray(spacings, dtype=np.float64) ** 2, dtype=solver.scalar, device=dev)
        self._top = wp.zeros(len(probes), dtype=solver.scalar, device=dev)

    def sample(self) -> dict:
        s = self.solver
        self._top.fill_(DRY)
        wp.launch(self._kernel, dim=s.n, inputs=[s.config.dim - 1, self._centres, self._radius2, s.pos, s.ptype,
                                                 self._top], device=s.device)
        top = self.across.most(self._top.numpy()).astype(np.float64)
        return {name: float(t + self.half[k]) if t > 0.5 * DRY else 0.0
                for k, (name, t) in enumerate(zip(self.names, top))}
