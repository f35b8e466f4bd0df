"""Measurements against analytic fields: probes (Shepard-normalised kernel interpolation, thesis
Section 3.2) and the net force of a hydrostatic tank on its floor and walls."""
import numpy as np
import pytest

from gpusph_ros.measure.forces import BodyWrench
from gpusph_ros.measure.probes import PointProbes
from gpusph_ros.scenes.boxes import box_tank, lattice
from gpusph_ros.sph import BOUNDARY, Particles, Solver, SolverConfig, kernels

pytestmark = pytest.mark.physics

DX = 0.01


def fluid_block(kernel="quadratic", velocity=None, precision="float64"):
    """A 3D block of fluid on a lattice, at rest or with a prescribed velocity field (no stepping)."""
    side = 0.12
    pos = lattice((0.0, 0.0, 0.0), (side, side, side), DX, 3)
    n = len(pos)
    vel = np.zeros((n, 3)) if velocity is None else velocity(pos)
    cfg = SolverConfig(dim=3, dx=DX, kernel=kernel, precision=precision, domain_lo=(-0.05,) * 3,
                       domain_hi=(side + 0.05,) * 3)
    parts = Particles(pos=pos, vel=vel, rho=np.full(n, 1000.0), mass=np.full(n, 1000.0 * DX ** 3), ptype=np.zeros(n))
    return cfg, parts


def interior_points(rng, count):
    return 0.04 + rng.random((count, 3)) * 0.04  # at least 3h inside the block


@pytest.mark.parametrize("kernel", ["quadratic", "cubic_spline", "wendland"])
def test_uniform_field_comes_back_exactly_and_without_the_lattice_bias(kernel):
    u = np.array([0.3, -0.2, 0.1])
    cfg, parts = fluid_block(kernel, velocity=lambda p: np.tile(u, (len(p), 1)))
    solver = Solver(cfg, parts)
    # a lattice node first: there the plain kernel sum is 1.02 (quadratic) or 1.01 (Wendland)
    points = np.vstack([[0.065, 0.065, 0.065], interior_points(np.random.default_rng(3), 19)])
    out = PointProbes(solver, points).sample()
    np.testing.assert_allclose(out["vel"], np.tile(u, (20, 1)), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(out["rho"], 1000.0, rtol=1e-9)
    # what the normalisation removes: the plain kernel sum at that node
    # (the cubic spline happens to sum to 0.997 at h = 1.3 dx in 3D)
    w, _ = kernels.evaluate(kernel, 3, cfg.h, np.linalg.norm(parts.pos - points[0], axis=1))
    plain = (parts.mass * w).sum() / 1000.0
    if kernel != "cubic_spline":
        assert plain > 1.005


def test_linear_field_is_exact_at_lattice_symmetric_points_and_close_elsewhere():
    grad = np.array([[0.0, 2.0, 0.0], [0.0, 0.0, -1.0], [0.5, 0.0, 0.0]])  # du_i / dx_j

    def field(p):
        return p @ grad.T

    cfg, parts = fluid_block("cubic_spline", velocity=field)
    solver = Solver(cfg, parts)
    nodes = np.array([[0.06, 0.06, 0.06], [0.055, 0.065, 0.06], [0.05, 0.05, 0.07]])  # lattice nodes and centres
    out = PointProbes(solver, nodes).sample()
    np.testing.assert_allclose(out["vel"], field(nodes), atol=1e-10)
    anywhere = interior_points(np.random.default_rng(5), 30)
    err = np.abs(PointProbes(solver, anywhere).sample()["vel"] - field(anywhere)).max()
    assert err < 0.02 * np.abs(grad).max() * DX  # a fiftieth of the change over one spacing


def test_dry_probe_reports_zero_weight():
    cfg, parts = fluid_block()
    out = PointProbes(Solver(cfg, parts), [(0.3, 0.3, 0.3)]).sample()
    assert out["weight"][0] == 0.0 and np.all(out["vel"][0] == 0.0)


def test_hydrostatic_tank_loads_its_floor_and_walls():
    """2D, per unit depth: the floor carries the water's weight M g, each side wall rho0 g H^2 / 2."""
    depth, width = 0.2, 0.3
    cfg = SolverConfig(dim=2, dx=DX, gravity=(0.0, -9.81, 0.0), depth=depth, settle_tau=0.02, settle_until=0.3)
    cfg, parts = box_tank(cfg, (width, 0.24), [((0.0, 0.0), (width, depth))])
    wall = parts.ptype == BOUNDARY
    parts.body[wall & (parts.pos[:, 1] < 0.0)] = 0  # floor
    parts.body[wall & (parts.pos[:, 1] >= 0.0) & (parts.pos[:, 0] < 0.0)] = 1  # left wall
    parts.body[wall & (parts.pos[:, 1] >= 0.0) & (parts.pos[:, 0] > width)] = 2  # right wall
    solver = Solver(cfg, parts)
    floor, left, right = (BodyWrench(solver, b) for b in range(3))
    forces = []
    for t in np.linspace(0.5, 0.7, 5):
        solver.advance(float(t))
        forces.append([floor.sample()[0], left.sample()[0], right.sample()[0]])
    f_floor, f_left, f_right = np.mean(forces, axis=0)
    weight = parts.mass[parts.ptype == 0].sum() * 9.81
    side = 1000.0 * 9.81 * depth ** 2 / 2
    print(f"\nfloor {f_floor[1]:.1f} N/m (weight {-weight:.1f}), walls {f_left[0]:.1f} / {f_right[0]:.1f} "
          f"N/m (rho0 g H^2 / 2 = {side:.1f})")
    assert f_floor[1] == pytest.approx(-weight, rel=0.03)
    assert f_left[0] == pytest.approx(-side, rel=0.05)
    assert f_right[0] == pytest.approx(side, rel=0.05)
    assert abs(f_floor[0]) < 0.01 * weight
