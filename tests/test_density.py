"""Density treatments: the Shepard filter (thesis Eq. 2.28) and the hydrostatic start (Eq. 2.12)."""
import numpy as np
import pytest

from gpusph_ros.scenes.boxes import lattice
from gpusph_ros.sph import KERNELS, Particles, Solver, SolverConfig, kernels
from gpusph_ros.sph.eos import hydrostatic_density

pytestmark = pytest.mark.unit


def periodic_block(kernel: str, dim: int, precision: str = "float64"):
    dx = 0.005
    side = 0.08
    hi = (side, side, side if dim == 3 else 1.0)
    lo = (0.0, 0.0, 0.0 if dim == 3 else -1.0)
    cfg = SolverConfig(dim=dim, dx=dx, kernel=kernel, precision=precision, domain_lo=lo, domain_hi=hi,
                       periodic=(True, True, dim == 3), gravity=(0.0, -9.81, 0.0) if dim == 2 else (0.0, 0.0, -9.81))
    pos = lattice((0.0,) * dim, (side,) * dim, dx, dim)
    n = len(pos)
    parts = Particles(pos=pos, vel=np.zeros((n, 3)), rho=np.full(n, 1000.0), mass=np.full(n, 1000.0 * dx ** dim),
                      ptype=np.zeros(n))
    return cfg, parts


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("kernel", KERNELS)
def test_shepard_filter_keeps_a_uniform_lattice_at_rho0(kernel, dim):
    """A plain kernel sum on this lattice is off by up to 5%; the normalised filter must not be."""
    cfg, parts = periodic_block(kernel, dim)
    solver = Solver(cfg, parts)
    solver.shepard_filter()
    rho = solver.snapshot()["rho"]
    np.testing.assert_allclose(rho, 1000.0, rtol=1e-9)
    # the bias the filter avoids: the same particles' plain sum m W
    dists = np.linalg.norm(parts.pos - parts.pos[len(parts) // 2], axis=1)
    w, _ = kernels.evaluate(kernel, dim, cfg.h, dists)
    plain = (parts.mass * w).sum()
    if kernel != "cubic_spline":
        assert abs(plain / 1000.0 - 1.0) > 0.005


def test_shepard_filter_smooths_noise_toward_the_local_mean():
    cfg, parts = periodic_block("cubic_spline", 2)
    rng = np.random.default_rng(1)
    parts.rho = 1000.0 + rng.normal(0.0, 5.0, len(parts))
    solver = Solver(cfg, parts)
    solver.shepard_filter()
    rho = solver.snapshot()["rho"]
    assert np.std(rho) < 0.5 * np.std(parts.rho)
    assert np.mean(rho) == pytest.approx(np.mean(parts.rho), abs=0.5)


def test_hydrostatic_density_inverts_the_tait_law():
    b = 30.0 ** 2 * 1000.0 / 7.0
    depth = np.array([0.0, 0.1, 0.4])
    rho = hydrostatic_density(depth, 1000.0, b, 7.0, 9.81)
    p = b * ((rho / 1000.0) ** 7 - 1.0)
    np.testing.assert_allclose(p, 1000.0 * 9.81 * depth, rtol=1e-10, atol=1e-9)
