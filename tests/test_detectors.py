"""Failure detectors for what does not show as NaN (sph.health, CHECKS): each fires on a run broken
on purpose and stays quiet on the same run done right; the run's health peak (Solver.health_peaks)
passes the detector's limit on the broken run and stays under it on the healthy one.

- wall_penetration: a column thrown at 3 m/s onto a Lennard-Jones floor (Monaghan 1994; thesis
  Eq. 2.24) whose strength D = 5 g H is taken with H = 0.1 mm instead of the column's 0.11 m;
- clumping: a periodic block of fluid 10% below rho0, under uniform tension, the textbook tensile
  instability (Swegle et al. 1995), against the same block at rho0;
- energy_growth: the 2D column collapse stepped at 3x the stable time step (the predictor-corrector
  then gains energy, Monaghan 1992) against 1x, in a closed tank, where energy may only fall.
"""
import dataclasses

import numpy as np
import pytest

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.sph import HealthError, Particles, Solver
from gpusph_ros.sph.config import SolverConfig

pytestmark = pytest.mark.physics

WIDE = dict(rho_min_ratio=0.2, rho_max_ratio=5.0)  # so the density check does not speak first


def collapse(**numerics):
    scene = load_scene("collapse_2d")
    return build(scene, dx=scene.fluid[0].hi[0] / 15, **numerics)


def outcome(cfg, particles, end, peak=None):
    """The check that stopped the run, or None when it reached ``end``. With ``peak`` (a key of
    Solver.health_peaks and its limit), the run's peak must pass the limit exactly when it failed."""
    solver = Solver(cfg, particles)
    try:
        solver.advance(end)
    except HealthError as err:
        if peak:
            assert solver.health_peaks[peak[0]] > peak[1], (err, solver.health_peaks)
        return err
    assert solver.time == pytest.approx(end)
    if peak:
        assert solver.health_peaks[peak[0]] <= peak[1], solver.health_peaks
    return None


@pytest.mark.parametrize("depth, fires", [(0.1143, False), (1.0e-4, True)])
def test_wall_penetration(depth, fires):
    model = collapse(boundary="lennard_jones")
    falling = dataclasses.replace(model.particles, vel=model.particles.vel.copy())
    falling.vel[model.particles.ptype == 0, 1] = -3.0
    # strict: the detector under its own name (by default the faulty particles are excluded)
    cfg = model.config.replace(depth=depth, c0=10.0 * np.sqrt(9.81 * 0.1143), energy_growth_ratio=0.0,
                               max_excluded_fraction=0.0, **WIDE)
    err = outcome(cfg, falling, 0.05)
    if not fires:
        assert err is None, err
        return
    assert err is not None and err.check == "wall_penetration", err
    assert 0 <= err.particle < len(falling) and falling.ptype[err.particle] == 0


@pytest.mark.parametrize("rho_ratio, fires", [(1.0, False), (0.9, True)])
def test_clumping(rho_ratio, fires):
    dx, n = 0.01, 30
    axis = (np.arange(n) + 0.5) * dx
    x, y = np.meshgrid(axis, axis, indexing="ij")
    pos = np.zeros((n * n, 3))
    pos[:, 0], pos[:, 1] = x.ravel(), y.ravel()
    pos[:, :2] += np.random.default_rng(1).normal(0.0, 0.02 * dx, (n * n, 2))  # a seed for the instability
    cfg = SolverConfig(dim=2, dx=dx, gravity=(0.0, -1.0e-3, 0.0), depth=0.1, c0=5.0, density_diffusion="none",
                       domain_lo=(0.0, 0.0, -1.0), domain_hi=(n * dx, n * dx, 1.0), periodic=(True, True, False),
                       **WIDE)
    particles = Particles(pos=pos, vel=np.zeros((n * n, 3)), rho=np.full(n * n, 1000.0 * rho_ratio),
                          mass=np.full(n * n, 1000.0 * dx * dx), ptype=np.zeros(n * n))
    err = outcome(cfg, particles, 0.5, peak=("peak_clumped_fraction", cfg.clump_fraction))
    if not fires:
        assert err is None, err
        return
    assert err is not None and err.check == "clumping", err
    assert "of the fluid particles have a neighbour closer than 0.25 dx" in str(err)


@pytest.mark.parametrize("factor, fires", [(1.0, False), (3.0, True)])
def test_energy_growth(factor, fires):
    model = collapse()
    probe = Solver(model.config, model.particles)
    probe.step()
    cfg = model.config.replace(dt_fixed=factor * probe.dt_stable, **WIDE)
    err = outcome(cfg, model.particles, 0.3, peak=("peak_energy_growth", cfg.energy_growth_ratio))
    if not fires:
        assert err is None, err
        return
    assert err is not None and err.check == "energy_growth", err
    assert err.particle == -1 and "above its start" in str(err)


def test_a_coarse_collapse_whose_thin_surge_pairs_at_the_floor_is_not_failed():
    """The 2D collapse at 1 cm, six particles across its column: after the surge meets the far wall
    (t = 0.34 s) 28% of its fluid pairs in the second layer of a sheet two particles thin, 1.5-1.7 dx
    above the floor, with the density within 7% of rho0 and the energy not growing: a healthy run,
    which the clumping check stopped while it exempted only the first 1.5 dx (CLUMP_WALL_DX)."""
    model = build(load_scene("collapse_2d"), dx=0.01)
    solver = Solver(model.config, model.particles)
    solver.advance(0.5)
    peaks = solver.health_peaks
    assert solver.time == pytest.approx(0.5) and solver.excluded_particles == 0
    assert peaks["peak_clumped_fraction"] <= model.config.clump_fraction
    assert 0.9 < peaks["min_density_ratio"] and peaks["max_density_ratio"] < 1.1 and peaks["peak_energy_growth"] < 0.01
