"""Shared test set-up: quiet Warp, the package's reference data, small tank builders, a core for
each test worker."""
import os
from pathlib import Path

import numpy as np
import pytest
import warp as wp

from gpusph_ros.analysis.reference import data_dir

wp.config.log_level = wp.LOG_WARNING

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(autouse=True)
def one_core_per_worker(request):
    """Under pytest-xdist with a worker per core (make test), a unit or physics test runs on its
    worker's core alone: its solver then steps on one thread (sph.launch.usable_cores), replayed
    from a capture, where on every core it would share them with the other worker's and spend
    what it saves on handing passes between threads (a piston wavemaker's flume of 4,017 particles,
    beside the 3D zoned tanks: 66 s pinned, 78 s not). A node, recording or study test keeps every
    core for the processes it starts."""
    worker, workers = os.environ.get("PYTEST_XDIST_WORKER"), int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
    if worker is None or not hasattr(os, "sched_setaffinity") or any(
            request.node.get_closest_marker(kind) for kind in ("ros", "study")):
        yield
        return
    cores = sorted(os.sched_getaffinity(0))
    if workers < len(cores):
        yield
        return
    os.sched_setaffinity(0, {cores[int(worker.removeprefix("gw")) % len(cores)]})
    try:
        yield
    finally:
        os.sched_setaffinity(0, cores)


@pytest.fixture(scope="session")
def reference_data() -> Path:
    """The package's own data/ folder (no ../shared needed)."""
    found = data_dir()
    if found is None:
        pytest.fail("the package's reference data (data/thesis_2011) is missing from this checkout or install")
    return found


def hydrostatic_errors(snap: dict, dim: int, h: float, depth: float, rho0: float, g: float, periodic,
                       bins=(0.2, 0.4, 0.6)) -> np.ndarray:
    """p / (rho0 g d) - 1 in depth bins [b, b + 0.2] H, over fluid particles at least 3h from the
    walls and the floor. The depth d is measured from the free surface, half a particle spacing
    above the mean height of the top layer of particles away from the walls (so that a column
    that sinks or spreads a little is not counted as a pressure error)."""
    up = dim - 1
    f = snap["ptype"] == 0
    x, p = snap["pos"][f], snap["pressure"][f]
    dx = float((snap["mass"][f][0] / rho0) ** (1.0 / dim))
    away = np.ones(len(x), dtype=bool)
    for a in range(dim - 1):
        if not periodic[a]:
            away &= (x[:, a] > x[:, a].min() + 3 * h) & (x[:, a] < x[:, a].max() - 3 * h)
    top = x[away, up].max()
    surface = x[away & (x[:, up] > top - 0.5 * dx), up].mean() + 0.5 * dx
    d = surface - x[:, up]
    away &= x[:, up] > 3 * h
    errors = []
    for b in bins:
        sel = away & (d > b * depth) & (d <= (b + 0.2) * depth)
        assert sel.sum() >= 5, f"too few particles in the depth bin {b:.1f}-{b + 0.2:.1f} H"
        errors.append(p[sel].mean() / (rho0 * g * d[sel].mean()) - 1.0)
    return np.array(errors)


KINDS = ("unit", "physics", "ros", "study")


def planned_bytes(solver) -> int:
    """The solver's device memory with its lists as wide as the plan prices them (the lattice's
    estimate, resources.device_bytes); it measures its own lists, narrower (sph/neighbours.py). A
    solver that walks the cells holds no lists."""
    from gpusph_ros.sph.neighbours import default_max_neighbours

    cfg = solver.config
    if solver.neighbours.cells:
        return solver.device_bytes()
    width = default_max_neighbours(cfg.dim, cfg.hdx, solver.finest, solver.params.coarse_stride)
    return solver.device_bytes() + 4 * solver.n * (width - solver.neighbours.max_neighbours)


def pytest_collection_modifyitems(config, items):
    """Each test is of exactly one kind (pytest.ini), so the kinds together are the whole suite."""
    wrong = [f"{item.nodeid}: {kinds or 'none'}" for item in items
             if len(kinds := [m.name for m in item.iter_markers() if m.name in KINDS]) != 1]
    if wrong:
        raise pytest.UsageError("each test needs exactly one of the markers " + ", ".join(KINDS) + ":\n  "
                                + "\n  ".join(wrong))
