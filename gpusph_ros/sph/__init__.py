"""The SPH solver: Warp kernels and their drivers. Imports nothing from ROS."""

from .config import BOUNDARIES, DENSITY_DIFFUSIONS, KERNELS, PRECISIONS, VISCOSITIES, ConfigError, Plane, SolverConfig
from .neighbours import NeighbourOverflow
from .solver import BOUNDARY, FLUID, HealthError, Particles, Solver

__all__ = [
    "BOUNDARIES", "DENSITY_DIFFUSIONS", "KERNELS", "PRECISIONS", "VISCOSITIES", "ConfigError", "Plane",
    "SolverConfig", "NeighbourOverflow", "BOUNDARY", "FLUID", "HealthError", "Particles", "Solver",
]
