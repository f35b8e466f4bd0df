"""Free-surface elevation at a gauge: going up a vertical line from the floor, the first height
where the fluid's kernel sum sum_b W(x - x_b) m_b / rho_b falls below 1/2 after the line was
wet, the level a free surface has halfway through the kernel's reach. This is DualSPHysics'
GaugeSwl (JGaugeSwl::CalculeCpuT: from point0 up to the first fluid-to-empty change, mass limit
half a particle's mass): spray and an overturning jet above an air pocket are not the water at
the gauge. The line is sampled every dx/4 with the point probes' interpolation on the device."""
import numpy as np

from .probes import PointProbes

LEVEL = 0.5
SAMPLES_PER_DX = 4


def gauge_points(position, top: float, dx: float, dim: int) -> np.ndarray:
    """Sample points of a gauge at horizontal ``position`` from the floor to ``top``."""
    heights = np.arange(0.0, top + 1e-12, dx / SAMPLES_PER_DX)
    pts = np.repeat(np.asarray(position, dtype=np.float64).reshape(1, 3), len(heights), axis=0)
    pts[:, dim - 1] = heights
    return pts


def elevation(heights: np.ndarray, weight: np.ndarray) -> float:
    """The first height above a wet point where ``weight`` falls below LEVEL, interpolated
    linearly; the top of the line when it never falls; 0 for a dry gauge."""
    wet = weight >= LEVEL
    if not wet.any():
        return 0.0
    first = int(np.argmax(wet))
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
