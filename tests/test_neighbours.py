"""Neighbour lists against brute force, with a periodic axis (minimum image)."""
import numpy as np
import pytest

from gpusph_ros.sph import Particles, Solver, SolverConfig
from gpusph_ros.sph.neighbours import NeighbourList

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("precision", ["float32", "float64"])
def test_lists_match_brute_force(precision):
    rng = np.random.default_rng(7)
    dx = 0.01
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([0.1, 0.1, 0.1])
    pos = lo + rng.random((800, 3)) * (hi - lo)
    n = len(pos)
    cfg = SolverConfig(dim=3, dx=dx, precision=precision, domain_lo=tuple(lo), domain_hi=tuple(hi),
                       periodic=(True, False, False))
    solver = Solver(cfg, Particles(pos=pos, vel=np.zeros((n, 3)), rho=np.full(n, 1000.0),
                                   mass=np.full(n, 1.0), ptype=np.zeros(n)))
    solver.mean_neighbours()
    nl = solver.neighbours
    count = nl.count.numpy()
    nbr = nl.nbr.numpy().reshape(n, nl.max_neighbours)
    radius = NeighbourList.SKIN * 2.0 * cfg.h
    sep = pos[:, None, :] - pos[None, :, :]
    sep[..., 0] -= 0.1 * np.round(sep[..., 0] / 0.1)
    dist = np.linalg.norm(sep, axis=2)
    for i in range(0, n, 7):
        expected = set(np.flatnonzero((dist[i] < radius * (1 - 1e-5)) & (np.arange(n) != i)))
        got = set(nbr[i, :count[i]].tolist())
        assert expected <= got, f"particle {i}: missing {sorted(expected - got)[:5]}"
        assert all(dist[i, j] < radius * (1 + 1e-5) for j in got)
    # a periodic pair across the seam is found
    assert any(abs(pos[i, 0] - pos[j, 0]) > 0.05 for i in range(n) for j in nbr[i, :count[i]])
