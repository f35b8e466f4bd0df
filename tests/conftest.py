"""Shared test set-up: quiet Warp, the shared reference data, small tank builders."""
from pathlib import Path

import numpy as np
import pytest
import warp as wp

wp.config.quiet = True

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    if not SHARED.is_dir():
        pytest.fail(f"the shared reference material is missing: expected it at {SHARED}")
    return SHARED


def hydrostatic_errors(snap: dict, dim: int, h: float, depth: float, rho0: float, g: float,
                       fluid_lo, fluid_hi, bins=(0.2, 0.4, 0.6)) -> np.ndarray:
    """p / (rho0 g d) - 1 in depth bins [b, b + 0.2] H, over fluid particles at least 3h from the
    walls. The depth d is measured from the surface that the fluid's own volume (sum m / rho over
    the footprint it occupies) sets, so that a sinking or spreading column is not counted as a
    pressure error."""
    up = dim - 1
    f = snap["ptype"] == 0
    x, p = snap["pos"][f], snap["pressure"][f]
    footprint = float(np.prod([fluid_hi[a] - fluid_lo[a] for a in range(dim - 1)]))
    surface = (snap["mass"][f] / snap["rho"][f]).sum() / footprint
    d = surface - x[:, up]
    away = x[:, up] > 3 * h
    for a in range(dim - 1):
        if fluid_lo[a] is not None:
            away &= (x[:, a] > fluid_lo[a] + 3 * h) & (x[:, a] < fluid_hi[a] - 3 * h)
    errors = []
    for b in bins:
        sel = away & (d > b * depth) & (d <= (b + 0.2) * depth)
        assert sel.sum() >= 5, f"too few particles in the depth bin {b:.1f}-{b + 0.2:.1f} H"
        errors.append(p[sel].mean() / (rho0 * g * d[sel].mean()) - 1.0)
    return np.array(errors)
