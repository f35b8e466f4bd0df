"""Neighbour lists against brute force, with a periodic axis (minimum image)."""
import numpy as np
import pytest

from gpusph_ros.sph import Particles, Solver, SolverConfig
from gpusph_ros.sph.state import FLUID, PASSIVE

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
    radius = nl.skin * 2.0 * cfg.h
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


def test_two_levels_lists_match_brute_force():
    """Cells one fine list radius wide: a coarse particle searches two each way and still finds its
    whole list. An active particle lists its own level only; a passive one its donors too, the other
    level's active fluid and the finer level's passive fluid (and its own level's, for when it turns
    active before the next build). Each pair is
    within the list radius of h_ab = (h_a + h_b) / 2."""
    rng = np.random.default_rng(11)
    dx = 0.01
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([0.12, 0.12, 0.12])
    n = 1200
    pos = lo + rng.random((n, 3)) * (hi - lo)
    spacing = np.where(rng.random(n) < 0.5, dx, 0.5 * dx)
    ptype = np.where(rng.random(n) < 0.3, PASSIVE, FLUID)
    cfg = SolverConfig(dim=3, dx=dx, precision="float64", domain_lo=tuple(lo), domain_hi=tuple(hi),
                       periodic=(True, False, False))
    solver = Solver(cfg, Particles(pos=pos, vel=np.zeros((n, 3)), rho=np.full(n, 1000.0), mass=np.full(n, 1.0),
                                   ptype=ptype, spacing=spacing))
    nl = solver.neighbours
    assert nl.grid.reach == 2  # the coarse level's radius is two cells
    nl.rebuild(solver.pos, force=True)
    count = nl.count.numpy()
    nbr = nl.nbr.numpy().reshape(n, nl.max_neighbours)
    h = cfg.hdx * spacing
    sep = pos[:, None, :] - pos[None, :, :]
    sep[..., 0] -= 0.12 * np.round(sep[..., 0] / 0.12)
    dist = np.linalg.norm(sep, axis=2)
    radius = nl.skin * (h[:, None] + h[None, :])
    same = h[:, None] == h[None, :]
    donor = (ptype[None, :] == FLUID) | ((ptype[None, :] == PASSIVE) & (h[None, :] < h[:, None]))
    allowed = same | ((ptype[:, None] == PASSIVE) & donor)
    np.fill_diagonal(allowed, False)
    for i in range(n):
        expected = set(np.flatnonzero(allowed[i] & (dist[i] < radius[i] * (1 - 1e-9))))
        got = set(nbr[i, :count[i]].tolist())
        assert got == expected, f"particle {i}: missing {sorted(expected - got)[:5]}, extra {sorted(got - expected)}"
    assert any(count[i] > 0 and ptype[i] == PASSIVE and h[i] == h.max() for i in range(n))
