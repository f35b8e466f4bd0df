"""Loads on a wall against cases known exactly (scenes/exact.py): the net force on a wall's particles
and the pressure the sensors read on it (measure/sensors.py, measure/forces.py).

A 2D jet impinging normally on a wall of boundary particles, b = 0.1 m, U = 1 m/s, ten particles
across, averaged over the steady window (0.4-1.4 s, after the first contact's water hammer, before
the tail arrives; bench/jet_impingement.py prints the rest). Under dynamic walls what the sensors
read is not yet right (docs/results/wall_pressure.md): the stagnation pressure 49% low and the
wall-pressure load 63% low at ten across, while the wall particles carry about nine times the
stagnation pressure; that is the subject of the open wall-pressure work, and no test here claims
otherwise.
"""
import numpy as np
import pytest

from gpusph_ros.measure.forces import BodyWrench
from gpusph_ros.measure.sensors import WallPressure
from gpusph_ros.scenes.exact import impinging_jet, jet_force, jet_stagnation_pressure
from gpusph_ros.sph import Solver

pytestmark = pytest.mark.physics


@pytest.mark.parametrize("boundary", ["dynamic", "mdbc", "adami"])
def test_the_force_on_a_wall_a_jet_hits_is_its_momentum_flux(boundary):
    """The force on the wall's particles over the window (each sample the mean over the steps since
    the last: measure/forces.py) within 3% of rho U^2 b under the particle walls with volume
    (measured +0.9% dynamic, +1.5% mdbc, -0.2% adami; mDBC's first formulation, which extrapolated
    the density gradient into the wall, -11.8%). The extrapolated-pressure wall has no fluid-wall
    friction and its force scatters from step to step by about its mean: a sample of one step's
    force every 0.02 s would not do. Under mDBC and the extrapolated-pressure wall the sensor at the
    stagnation point, sampled every 0.02 s, reads rho U^2 / 2 within 20% (measured -15% mdbc, -6%
    at twenty across with the bench's samples before the wet share; -9% adami); under dynamic walls
    it does not (-42%)."""
    cfg, particles, face, dx = impinging_jet(10, boundary)
    solver = Solver(cfg, particles)
    wrench = BodyWrench(solver, 0)
    stagnation = WallPressure(solver, [(face, 0.0, 0.0)], [(-1.0, 0.0, 0.0)])
    solver.advance(0.4)
    wrench.sample()  # the mean before the window
    forces, pressures = [], []
    for t in np.arange(0.42, 1.4 + 1e-9, 0.02):
        solver.advance(float(t))
        forces.append(wrench.sample()[0])
        pressures.append(stagnation.sample()[0])
    mean, p = np.mean(forces, axis=0), float(np.mean(pressures))
    print(f"\n{boundary}: force on the wall's particles {mean[0]:.2f} N/m against rho U^2 b = {jet_force():.1f} N/m; "
          f"across the jet {mean[1]:+.2f} N/m; stagnation pressure {p:.0f} Pa against {jet_stagnation_pressure():.0f}; "
          f"{solver.excluded_particles} particles excluded")
    assert mean[0] == pytest.approx(jet_force(), rel=0.03)
    assert abs(mean[1]) < 0.03 * jet_force()  # the jet is symmetric: no force along the wall
    assert solver.excluded_fraction < 0.01
    if boundary != "dynamic":
        assert p == pytest.approx(jet_stagnation_pressure(), rel=0.2)
