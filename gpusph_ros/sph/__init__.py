"""The SPH solver: Warp kernels and their drivers. Imports nothing from ROS."""

from .config import BOUNDARIES, DENSITY_DIFFUSIONS, KERNELS, PRECISIONS, VISCOSITIES, ConfigError, Plane, SolverConfig
from .health import HealthError
from .neighbours import NeighbourOverflow
from .particles import Particles
from .solver import Solver
from .state import BOUNDARY, FLUID

__all__ = [
    "BOUNDARIES", "DENSITY_DIFFUSIONS", "KERNELS", "PRECISIONS", "VISCOSITIES", "ConfigError", "Plane",
    "SolverConfig", "NeighbourOverflow", "BOUNDARY", "FLUID", "HealthError", "Particles", "Solver",
]
