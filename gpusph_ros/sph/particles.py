"""The host-side particle set a solver starts from, as a scene builds it."""
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Particles:
    """Host-side particle set a solver starts from (one row per particle, SI units)."""

    pos: np.ndarray
    vel: np.ndarray
    rho: np.ndarray
    mass: np.ndarray
    ptype: np.ndarray
    body: np.ndarray = field(default=None)
    # each particle's spacing [m]; None: the scene's dx for all (a refinement zone's are finer)
    spacing: np.ndarray = field(default=None)

    def __post_init__(self):
        n = len(self.pos)
        self.pos = np.asarray(self.pos, dtype=np.float64).reshape(n, 3)
        self.vel = np.asarray(self.vel, dtype=np.float64).reshape(n, 3)
        self.rho = np.asarray(self.rho, dtype=np.float64).reshape(n)
        self.mass = np.asarray(self.mass, dtype=np.float64).reshape(n)
        self.ptype = np.asarray(self.ptype, dtype=np.int32).reshape(n)
        self.body = (np.full(n, -1, dtype=np.int32) if self.body is None
                     else np.asarray(self.body, dtype=np.int32).reshape(n))
        if self.spacing is not None:
            self.spacing = np.asarray(self.spacing, dtype=np.float64).reshape(n)

    def __len__(self):
        return len(self.pos)
