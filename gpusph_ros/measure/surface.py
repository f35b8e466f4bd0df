"""Free-surface elevation at a gauge: the highest point of a vertical line where the fluid's
kernel sum sum_b W(x - x_b) m_b / rho_b reaches 1/2, the level a free surface has halfway
through the kernel's reach (the level-crossing gauges of DualSPHysics and GPUSPH). The line is
sampled every dx/4 with the point probes' interpolation on the device."""
import numpy as np

LEVEL = 0.5
SAMPLES_PER_DX = 4


def gauge_points(position, top: float, dx: float, dim: int) -> np.ndarray:
    """Sample points of a gauge at horizontal ``position`` from the floor to ``top``."""
    heights = np.arange(0.0, top + 1e-12, dx / SAMPLES_PER_DX)
    pts = np.repeat(np.asarray(position, dtype=np.float64).reshape(1, 3), len(heights), axis=0)
    pts[:, dim - 1] = heights
    return pts


def elevation(heights: np.ndarray, weight: np.ndarray) -> float:
    """The highest height where ``weight`` crosses LEVEL from below, interpolated linearly; 0
    for a dry gauge."""
    wet = np.nonzero(weight >= LEVEL)[0]
    if len(wet) == 0:
        return 0.0
    k = wet[-1]
    if k + 1 == len(heights):
        return float(heights[k])
    w0, w1 = weight[k], weight[k + 1]
    return float(heights[k] + (heights[k + 1] - heights[k]) * (w0 - LEVEL) / (w0 - w1))
