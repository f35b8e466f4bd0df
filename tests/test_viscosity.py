"""Laminar viscosity (thesis Eq. 2.16-2.17) and the SPS stress (Eq. 2.18-2.21) against plane
Poiseuille flow: a body force g along a periodic channel of width L between no-slip walls
settles to u(y) = g / (2 nu) y (L - y) (Morris et al. 1997).

The walls are dynamic boundary particles whose first layer lies on the wall lines y = 0 and
y = L, as Crespo et al. 2007 and DualSPHysics place them; the fluid lattice starts dx inside.
"""
import numpy as np
import pytest

from gpusph_ros.scenes.boxes import lattice
from gpusph_ros.sph import BOUNDARY, FLUID, Particles, Solver, SolverConfig

pytestmark = pytest.mark.physics

L = 0.02  # channel width [m]
DX = L / 20
NU = 1.0e-3  # a viscous fluid, so the start-up decays in a fraction of a second
U_MAX = 0.01
G = 8.0 * NU * U_MAX / L ** 2


def channel(viscosity: str):
    length = 12 * DX  # periodic along x: a whole number of particles, more than 3 list radii
    layers = 3
    # lattice() puts points at cell centres: shift by dx/2 so rows fall on y = k dx
    fluid = lattice((0.0, 0.5 * DX), (length, L - 0.5 * DX), DX, 2)
    walls = np.concatenate([lattice((0.0, -(layers - 0.5) * DX), (length, 0.5 * DX), DX, 2),
                            lattice((0.0, L - 0.5 * DX), (length, L + (layers - 0.5) * DX), DX, 2)])
    pos = np.concatenate([fluid, walls])
    n = len(pos)
    cfg = SolverConfig(dim=2, dx=DX, viscosity=viscosity, nu=NU, gravity=(G, 0.0, 0.0), c0=20 * U_MAX,
                       density_diffusion="none", boundary="dynamic", precision="float64",
                       domain_lo=(0.0, -(layers + 1) * DX, -1.0), domain_hi=(length, L + (layers + 1) * DX, 1.0),
                       periodic=(True, False, False))
    parts = Particles(pos=pos, vel=np.zeros((n, 3)), rho=np.full(n, 1000.0), mass=np.full(n, 1000.0 * DX ** 2),
                      ptype=np.concatenate([np.full(len(fluid), FLUID), np.full(len(walls), BOUNDARY)]))
    return cfg, parts


@pytest.mark.parametrize("viscosity", ["laminar", "sps"])
def test_poiseuille_profile(viscosity):
    cfg, parts = channel(viscosity)
    solver = Solver(cfg, parts)
    t_end = 1.5 * L ** 2 / NU  # the slowest start-up mode has decayed by exp(-1.5 pi^2) ~ 4e-7
    solver.advance(t_end)
    snap = solver.snapshot()
    f = snap["ptype"] == FLUID
    y, u = snap["pos"][f, 1], snap["vel"][f, 0]
    exact = G / (2 * NU) * y * (L - y)
    rms = np.sqrt(np.mean((u - exact) ** 2))
    print(f"\nPoiseuille ({viscosity}): u_max {u.max():.5f} m/s (exact {U_MAX:.5f}), "
          f"RMS error {100 * rms / U_MAX:.2f}% of u_max")
    assert rms < 0.05 * U_MAX
    assert np.abs(snap["vel"][f, 1]).max() < 0.05 * U_MAX
    if viscosity == "sps":
        # the Smagorinsky shear stress tau_xy / rho = (Cs dx)^2 |du/dy| du/dy (Eq. 2.19-2.21)
        off = snap["sps_tau_off"][f]
        dudy = G / (2 * NU) * (L - 2 * y)
        interior = (y > 3 * cfg.h) & (y < L - 3 * cfg.h)
        expected = (cfg.sps_cs * DX) ** 2 * np.abs(dudy) * dudy
        scale = np.abs(expected[interior]).max()
        assert np.abs(off[interior, 0] - expected[interior]).max() < 0.1 * scale


def test_a_live_change_to_sps_allocates_its_stress_and_the_profile_holds():
    """The SPS stress is held only under sps (six scalars a particle; issue 59): a laminar channel
    switched to sps halfway (Solver.reconfigure, as the node's live viscosity parameter does) gets
    its stress then, and ends on the same Poiseuille profile and Smagorinsky shear stress."""
    cfg, parts = channel("laminar")
    solver = Solver(cfg, parts)
    t_end = 1.5 * L ** 2 / NU
    solver.advance(0.5 * t_end)
    before = solver.device_bytes()
    solver.reconfigure(viscosity="sps")
    assert solver.device_bytes() - before == 6 * 8 * solver.n  # float64: two vectors a particle
    solver.advance(t_end)
    snap = solver.snapshot()
    f = snap["ptype"] == FLUID
    y, u = snap["pos"][f, 1], snap["vel"][f, 0]
    assert np.sqrt(np.mean((u - G / (2 * NU) * y * (L - y)) ** 2)) < 0.05 * U_MAX
    dudy = G / (2 * NU) * (L - 2 * y)
    interior = (y > 3 * cfg.h) & (y < L - 3 * cfg.h)
    expected = (cfg.sps_cs * DX) ** 2 * np.abs(dudy) * dudy
    off = snap["sps_tau_off"][f][interior, 0]
    assert np.abs(off - expected[interior]).max() < 0.1 * np.abs(expected[interior]).max()
