"""Particle shifting (sph.shifting; Lind et al. 2012 with DualSPHysics' free-surface treatment):
one step of a 2D lattice block moving at 1 m/s, run with and without shifting from the same state.
The difference is the shift: a particle pushed 0.3 dx off its lattice site is moved back towards
it (and by no more than the 0.1 dx cap), an undisturbed interior particle is not moved, a particle
of the free surface (div r below the threshold) is not moved at all; and shifting, which only
moves particles, changes no velocity in that first step."""
import numpy as np
import pytest

from gpusph_ros.sph import Particles, Solver
from gpusph_ros.sph.config import SolverConfig

pytestmark = pytest.mark.physics

DX, N = 0.01, 24


def block():
    axis = (np.arange(N) + 0.5) * DX
    x, y = np.meshgrid(axis, axis, indexing="ij")
    pos = np.zeros((N * N, 3))
    pos[:, 0], pos[:, 1] = x.ravel(), y.ravel()
    vel = np.zeros_like(pos)
    vel[:, 0] = 1.0
    return pos, vel


def one_step(shifting, pos, vel):
    # periodic along x only: the top row is a free surface, the bottom row sits on nothing (no gravity)
    cfg = SolverConfig(dim=2, dx=DX, gravity=(0.0, -1.0e-6, 0.0), depth=0.1, c0=10.0, dt_fixed=2.0e-4,
                       domain_lo=(0.0, -0.5, -1.0), domain_hi=(N * DX, 0.5 + N * DX, 1.0),
                       periodic=(True, False, False), shifting=shifting, energy_growth_ratio=0.0)
    n = len(pos)
    solver = Solver(cfg, Particles(pos=pos, vel=vel, rho=np.full(n, 1000.0), mass=np.full(n, 1000.0 * DX * DX),
                                   ptype=np.zeros(n)))
    solver.step()
    return solver.snapshot()


def test_shifting_moves_a_displaced_particle_back_and_leaves_the_rest():
    pos, vel = block()
    centre = (N // 2) * N + N // 2  # column N/2, row N/2
    pos[centre, 0] += 0.3 * DX
    plain, shifted = one_step(False, pos, vel), one_step(True, pos, vel)
    shift = shifted["pos"] - plain["pos"]
    assert -0.1 * DX - 1e-9 <= shift[centre, 0] < -1e-3 * DX  # back towards its site, within the cap
    assert abs(shift[centre, 1]) < 1e-6 * DX  # the lattice is symmetric about the displaced row
    interior = (N // 2) * N + 3  # column N/2, row 3: 9 dx from the disturbance, 3 from the bottom
    top = (N // 2) * N + N - 1  # column N/2, the top row
    assert np.abs(shift[interior]).max() < 1e-4 * DX
    assert np.abs(shift[top]).max() == 0.0
    np.testing.assert_allclose(shifted["vel"], plain["vel"], atol=1e-6)
