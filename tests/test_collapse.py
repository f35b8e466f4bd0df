"""2D collapse of a water column against Martin & Moyce 1952, Table 2 (column height = 2 x width).

The surge front Z = x_front / a is compared at the measured T = t sqrt(2 g / a) from 1 to 2.5.
The computed front leads: the laboratory's column took time to be released, so the measured clock
ran from before the water moved. The comparison takes that lag as one constant, the one (a
multiple of 0.01 in T up to 0.5) that brings the computed fronts nearest the measured ones, and
holds every point within 5% of the measured front at the lagged time, the lag no more than 0.3
(16 ms at a = 2.25 in). Measured: the defaults (extrapolated-pressure walls, no wall friction)
lag 0.21 and are then within 1.5%, where with no lag they led by 8-16%; the thesis's scenario 3
(Lennard-Jones walls) lags 0.16, within 2.2%.
"""
import numpy as np
import pytest

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.scenes.settings import read_run_file
from gpusph_ros.sph import Solver

pytestmark = pytest.mark.physics

SCENE = load_scene("collapse_2d")
A = SCENE.fluid[0].hi[0]  # column width a
# the defaults in both precisions, and the thesis's scenario 3 as GPUSPH ran it (cubic spline,
# laminar + SPS, XSPH, Shepard filter every 40 steps, Lennard-Jones walls, no density diffusion)
THESIS_SCENARIO_3 = read_run_file("thesis_scenario3")
CASES = [("float32", {}), ("float64", {}), ("float32", THESIS_SCENARIO_3)]
LAGS = np.arange(0.0, 0.505, 0.01)  # [T]


@pytest.mark.parametrize("precision, numerics", CASES,
                         ids=["defaults-float32", "defaults-float64", "thesis-scenario-3"])
def test_surge_front_matches_martin_moyce(reference_data, precision, numerics):
    table = np.loadtxt(reference_data / "martin_moyce_1952_collapse/ocellaris/martin_moyce_1952_table2_surge_front.txt")
    points = table[(table[:, 0] >= 1.0) & (table[:, 0] <= 2.55)]
    model = build(SCENE, dx=A / 30, precision=precision, **numerics)
    cfg, parts = model.config, model.particles
    solver = Solver(cfg, parts)
    rate = np.sqrt(2 * 9.81 / A)
    rows = []
    for T, Z in points:
        solver.advance(T / rate)
        snap = solver.snapshot()
        front = snap["pos"][snap["ptype"] == 0, 0].max() / A
        rows.append((T, Z, front, front / Z - 1.0))
    print(f"\nMartin & Moyce collapse, dx = a/30, {precision} {numerics or 'defaults'}: T, Z_exp, Z_sph, error")
    for row in rows:
        print("  T=%.2f  Z_exp=%.2f  Z_sph=%.3f  error=%+.1f%%" % (row[0], row[1], row[2], 100 * row[3]))
    def lagged(lag):  # the computed fronts against the measured ones lag later
        return np.array([front / np.interp(T + lag, table[:, 0], table[:, 1]) - 1.0 for T, _, front, _ in rows])

    lag = min(LAGS, key=lambda s: np.abs(lagged(s)).max())
    errors = lagged(lag)
    print(f"  lag {lag:.2f}: errors " + " ".join(f"{100 * e:+.1f}%" for e in errors))
    assert lag <= 0.3 and np.all(np.abs(errors) < 0.05), (lag, errors)
    # none may be lost through the walls: no fluid particle behind the first layer of wall
    # particles (dx/2 outside the wall's nominal surface)
    fluid = snap["pos"][snap["ptype"] == 0]
    assert len(fluid) == int((parts.ptype == 0).sum())
    assert fluid[:, 0].min() > -0.5 * cfg.dx and fluid[:, 1].min() > -0.5 * cfg.dx
