"""collapse_2d: the water column of Martin & Moyce 1952 (Phil. Trans. R. Soc. A 244, 312-324),
2D, column width a = 2.25 in = 0.05715 m and height 2a (n^2 = 2), released at t = 0 in a tank
6a long. Their surge front Z = x_front / a is tabulated against T = t sqrt(2 g / a).
"""
from ..sph.config import SolverConfig
from .boxes import box_tank

WIDTH = 0.05715  # a [m]


def collapse_2d(per_width: int = 30, **overrides):
    """(config, particles) with ``per_width`` particles across the column; overrides go to the config."""
    a = WIDTH
    cfg = SolverConfig(dim=2, dx=a / per_width, gravity=(0.0, -9.81, 0.0), depth=2 * a, **overrides)
    return box_tank(cfg, (6 * a, 2.5 * a), [((0.0, 0.0), (a, 2 * a))])
