"""The modified dynamic boundary condition (sph/boundaries/mdbc.py; English et al. 2021).

- Geometry: each boundary particle's ghost node is its mirror image across the nearest wall face
  (through the corner for a tank corner, across the nearest face of an obstacle, never through
  the tank floor under it).
- Still tank, 2D, dx = 1 cm, water 0.2 m deep, settled for 0.4 s and read at 1 s: the wall pressure
  (sensors.WallPressure, the boundary's own extrapolation at the face) is rho0 g d within 2% every
  2 cm from 3 cm below the surface down on both side walls, and along the floor; no gap: the first fluid layer keeps
  dx/2 from the floor and from the side walls (within 10%, more than 2h below the surface, where a
  kernel cut by the free surface lifts the top layer off the wall by up to 0.3 dx).
- Slip modes, on Stokes' first problem (a layer moving at u0 = 0.1 m/s over a wall at rest, nu =
  1e-3 m^2/s, dx = 5 mm, periodic along the wall, read at 0.05 s): no_slip gives u(y, t) = u0
  erf(y / (2 sqrt(nu t))) (Schlichting, Boundary-Layer Theory, Section 5.2) within 0.1 u0 at every
  height (measured within 0.074 u0) and the wall takes the momentum deficit int (1 - u/u0) dy =
  2 sqrt(nu t / pi) within 20% (measured +15.7% at 5 mm and +14.8% at 2.5 mm: the ghost velocity
  is a zeroth-order Shepard mean, as in DualSPHysics, which at the first layer's ghost leans on the
  faster fluid above it and so over-shears); free_slip takes less than 1% of that deficit
  (measured 0.03%), the first layer sliding 5% faster than the rest (the fluid rides over the wall
  particles' lattice), and ``none`` (wall velocity zero at the particles) takes 22% too little.
"""
import math

import numpy as np
import pytest

from gpusph_ros.measure.sensors import WallPressure
from gpusph_ros.scenes.boxes import box_tank
from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import parse_scene
from gpusph_ros.sph import Solver, SolverConfig
from gpusph_ros.sph.boundaries import mdbc

DX = 0.01
U0, NU, T_STOKES, STOKES_LENGTH = 0.1, 1.0e-3, 0.05, 0.1  # Stokes' first problem: m/s, m^2/s, s, m


def ghosts(model):
    """Each boundary particle's position and ghost offset (host copies)."""
    solver = Solver(model.config, model.particles)
    b = solver.ptype.numpy() == 1
    return solver.pos.numpy()[b].astype(np.float64), solver.ghost.numpy()[b].astype(np.float64), \
        solver.body.numpy()[b]


@pytest.mark.unit
def test_a_boundary_particles_ghost_node_is_its_mirror_across_the_nearest_face():
    scene = parse_scene({"name": "g", "dim": 2, "tank": [0.3, 0.2], "depth": 0.1,
                         "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.1, 0.1]}],
                         "obstacles": [{"name": "block", "lo": [0.2, 0.0], "hi": [0.25, 0.05]}]})
    model = build(scene, dx=DX, boundary="mdbc")
    pos, off, body = ghosts(model)
    tank = body < 0
    xg = pos + off
    # tank walls: the ghost is the mirror through the nearest point of the tank's inside
    inside = np.clip(pos[tank, :2], [0.0, 0.0], [0.3, np.inf])
    assert np.allclose(xg[tank, :2], 2 * inside - pos[tank, :2], atol=1e-6)
    corner = tank & (np.abs(pos[:, 0] + 0.5 * DX) < 1e-6) & (np.abs(pos[:, 1] + 0.5 * DX) < 1e-6)
    assert np.allclose(xg[corner, :2], [[0.5 * DX, 0.5 * DX]], atol=1e-6)
    # the block: across its nearest face, never down through the floor it stands on
    blk = ~tank
    assert np.all(xg[blk, 1] >= pos[blk, 1] - 1e-9)
    left_face = blk & (np.abs(pos[:, 0] - (0.2 + 0.5 * DX)) < 1e-6) & (np.abs(pos[:, 1] - 0.025) < 0.006)
    assert left_face.any() and np.allclose(xg[left_face, 0], 0.2 - 0.5 * DX, atol=1e-6)
    top_corner = blk & (np.abs(pos[:, 0] - (0.25 - 0.5 * DX)) < 1e-6) & (np.abs(pos[:, 1] - (0.05 - 0.5 * DX)) < 1e-6)
    assert np.allclose(xg[top_corner, :2], [[0.25 + 0.5 * DX, 0.05 + 0.5 * DX]], atol=1e-6)


@pytest.fixture(scope="module")
def still_tank():
    depth, size = 0.2, (0.3, 0.24)
    cfg = SolverConfig(dim=2, dx=DX, gravity=(0.0, -9.81, 0.0), depth=depth, boundary="mdbc",
                       settle_tau=0.02, settle_until=0.4)
    cfg, parts = box_tank(cfg, size, [((0.0, 0.0), (size[0], depth))])
    solver = Solver(cfg, parts)
    solver.advance(1.0)
    return solver, depth, size


@pytest.mark.physics
def test_mdbc_wall_pressure_in_a_still_tank_is_hydrostatic_at_every_depth(still_tank):
    solver, depth, size = still_tank
    depths = np.arange(0.03, depth, 0.02)  # from 3 dx down: nearer, the surface's own dx/2 dominates
    points, normals = [], []
    for x, n in ((0.0, 1.0), (size[0], -1.0)):
        points += [(x, depth - d, 0.0) for d in depths]
        normals += [(n, 0.0, 0.0)] * len(depths)
    floor = np.arange(0.02, size[0] - 0.01, 0.02)
    points += [(x, 0.0, 0.0) for x in floor]
    normals += [(0.0, 1.0, 0.0)] * len(floor)
    p = WallPressure(solver, points, normals).sample()
    expected = 1000.0 * 9.81 * np.concatenate([depths, depths, np.full(len(floor), depth)])
    err = p / expected - 1.0
    print("\nmDBC wall pressure / (rho0 g d) - 1: left", np.round(err[:len(depths)], 4),
          "right", np.round(err[len(depths):2 * len(depths)], 4), "floor", np.round(err[2 * len(depths):], 4))
    assert np.all(np.abs(err) < 0.02), err


@pytest.mark.physics
def test_mdbc_keeps_the_first_fluid_layer_at_half_a_spacing_from_the_walls(still_tank):
    solver, depth, size = still_tank
    snap = solver.snapshot()
    x = snap["pos"][snap["ptype"] == 0]
    below = x[:, 1] < depth - 2.0 * solver.config.h
    for name, ax, face, sel in (("floor", 1, 0.0, np.ones(len(x), dtype=bool)), ("left", 0, 0.0, below),
                                ("right", 0, size[0], below)):
        d = np.abs(x[sel, ax] - face)
        first = d[d < DX]
        print(f"{name}: first layer at {first.min() / DX:.3f}-{first.max() / DX:.3f} dx")
        assert len(first) >= 10 and np.all(np.abs(first / DX - 0.5) < 0.05), (name, first / DX)


def stokes_layer(slip: str, u0=U0, nu=NU, dx=0.005, t_end=T_STOKES):
    """Heights, x velocities and volumes of a 2D layer 4 cm deep, periodic along a 0.1 m wall, that
    started sliding at u0 over the wall at rest, at t_end."""
    depth = 0.04
    cfg = SolverConfig(dim=2, dx=dx, gravity=(0.0, -9.81, 0.0), depth=depth, boundary="mdbc", mdbc_slip=slip,
                       viscosity="laminar", nu=nu, periodic=(True, False, False), precision="float64")
    cfg, parts = box_tank(cfg, (STOKES_LENGTH, 0.06), [((0.0, 0.0), (STOKES_LENGTH, depth))])
    parts.vel[parts.ptype == 0, 0] = u0
    solver = Solver(cfg, parts)
    solver.advance(t_end)
    snap = solver.snapshot()
    f = snap["ptype"] == 0
    return snap["pos"][f, 1], snap["vel"][f, 0], snap["mass"][f] / snap["rho"][f]


def deficit(u, volume):
    """The momentum the wall has taken, as a thickness: int (1 - u / u0) dy."""
    return float(((1.0 - u / U0) * volume).sum()) / STOKES_LENGTH


@pytest.mark.physics
def test_mdbc_no_slip_follows_stokes_first_problem():
    y, u, volume = stokes_layer("no_slip")
    dx = 0.005
    for k in range(6):  # the boundary layer, 2 sqrt(nu t) = 1.4 cm, and above it
        row = (y >= k * dx) & (y < (k + 1) * dx)
        got, want = u[row].mean(), U0 * math.erf(y[row].mean() / (2.0 * math.sqrt(NU * T_STOKES)))
        print(f"y = {y[row].mean() * 1000:.1f} mm: u = {got:.4f} m/s, erf profile {want:.4f}")
        assert abs(got - want) < 0.1 * U0
    exact = 2.0 * math.sqrt(NU * T_STOKES / math.pi)
    print(f"momentum deficit {deficit(u, volume) * 1000:.2f} mm, exact {exact * 1000:.2f} mm")
    assert deficit(u, volume) == pytest.approx(exact, rel=0.2)


@pytest.mark.physics
def test_mdbc_free_slip_takes_no_momentum_from_the_layer():
    y, u, volume = stokes_layer("free_slip")
    assert abs(deficit(u, volume)) < 0.01 * 2.0 * math.sqrt(NU * T_STOKES / math.pi)
    assert np.all(np.abs(u / U0 - 1.0) < 0.06), (u.min(), u.max())


@pytest.mark.unit
def test_mdbc_slip_modes_are_named():
    assert set(mdbc.SLIP_ID) == {"none", "no_slip", "free_slip"}
    with pytest.raises(ValueError, match="mdbc_slip"):
        SolverConfig(mdbc_slip="partial").validate()
