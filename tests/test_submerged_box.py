"""Still water over a box on a tank's floor, and the same box under a current, in 3D
(scenes.exact.submerged_box; issue 68, item 3; bench/submerged_box.py, docs/results/submerged_box.md).

- Still water, 0.2 m deep, the box's top 0.1 m under the surface, at 2.5 cm (the box's height and
  the depth whole spacings), settled for 0.5 s and read at 0.55 and 0.6 s: the sensors on the box's
  top (at its centre and one diameter from its edge) read rho g d within 2% and the floor's rho g d
  within 2% (+1.4%, +1.4%, +1.3% measured), and no fluid particle is below -50 Pa (the lowest +144 Pa).
- A current of 0.3 m/s along x (the tank periodic that way, the water started at that speed; Froude
  number 0.21): no fluid particle below -50 Pa (the lowest +116 Pa measured); the top's sensors
  within rho U^2 (90 Pa, 9% of the still rho g d) of it, the Bernoulli drop of a speed up to sqrt(2)
  U over the top (-0.3% and -1.1% measured).
"""
import numpy as np
import pytest

from gpusph_ros.measure.suite import Measurements
from gpusph_ros.scenes.build import build_run
from gpusph_ros.scenes.exact import BOX_DEPTH, BOX_HI, submerged_box
from gpusph_ros.scenes.settings import resolve
from gpusph_ros.sph.state import FLUID

pytestmark = pytest.mark.physics

DX, RATE = 0.025, 20.0
TOPS = ("top_centre", "top_edge")


def _run(current: float, start: float, end: float):
    """The sensors' readings at each output after ``start`` to ``end`` and the fluid's lowest
    pressure over them."""
    scene = submerged_box(DX, current=current > 0.0)
    built = build_run(scene, resolve(scene, dx=DX, end_time=end))
    built.particles.vel[built.particles.ptype == FLUID, 0] = current
    solver = built.solver()
    measurements = Measurements(solver, built)
    readings, lowest = [], np.inf
    for k in range(1, int(round(end * RATE)) + 1):
        solver.advance(k / RATE)
        if solver.time > start + 1e-9:
            snap = solver.snapshot()
            lowest = min(lowest, float(snap["pressure"][snap["ptype"] == FLUID].min()))
            readings.append(measurements.sample()["sensors"])
    return readings, lowest, built.config.rho0 * built.config.g_norm


def test_still_water_over_a_box_reads_rho_g_d_on_its_top_and_holds_no_tension():
    readings, lowest, rho_g = _run(0.0, 0.5, 0.6)
    assert len(readings) == 2
    for name, depth in [*((top, BOX_DEPTH - BOX_HI[2]) for top in TOPS), ("floor", BOX_DEPTH)]:
        mean = np.mean([r[name] for r in readings])
        assert abs(mean / (rho_g * depth) - 1.0) <= 0.02, (name, mean)
    assert lowest >= -50.0


def test_a_box_under_a_gentle_current_holds_no_tension():
    u = 0.3
    readings, lowest, rho_g = _run(u, 0.3, 0.4)
    assert lowest >= -50.0
    still = rho_g * (BOX_DEPTH - BOX_HI[2])
    for name in TOPS:
        mean = np.mean([r[name] for r in readings])
        assert abs(mean - still) <= 1000.0 * u ** 2, (name, mean)
