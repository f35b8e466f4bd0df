"""Health checks: a step far above the stable time step is caught before a NaN reaches the state,
and the state from before the failing step is kept, whether a particle's fault fails the run
(max_excluded_fraction 0) or the faults exclude more fluid than the limit allows, under dynamic
walls and under extrapolated-pressure walls (whose densities are read from the kept fluid)."""
import numpy as np
import pytest

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.sph import HealthError, Solver
from gpusph_ros.sph.health import CHECKS
from gpusph_ros.sph.state import BOUNDARY

pytestmark = pytest.mark.physics


def column(**overrides):
    scene = load_scene("collapse_2d")
    model = build(scene, dx=scene.fluid[0].hi[0] / 15, **overrides)
    return model.config, model.particles


def test_reconfigure_refuses_what_needs_new_particles():
    cfg, parts = column()
    solver = Solver(cfg, parts)
    with pytest.raises(ValueError, match="dx"):
        solver.reconfigure(dx=0.001)
    solver.reconfigure(cfl=0.2)
    assert solver.config.cfl == 0.2


def test_stable_dt_runs_clean():
    cfg, parts = column()
    solver = Solver(cfg, parts)
    solver.advance(0.05)
    snap = solver.snapshot()
    assert np.isfinite(snap["pos"]).all() and np.isfinite(snap["rho"]).all()


@pytest.mark.parametrize("factor, max_excluded, boundary", [(20.0, 0.0, "dynamic"), (200.0, 0.0, "dynamic"),
                                                             (20.0, 0.01, "dynamic"), (20.0, 0.0, "adami"),
                                                             (20.0, 0.01, "adami")])
def test_unstable_dt_raises_and_keeps_the_last_healthy_state(factor, max_excluded, boundary):
    # the factors are multiples of the step at CFL 0.3: at 20x it the first faults are fluid
    # particles' (excluded, then excluded_fraction), where 27x (20x at CFL 0.4) reaches a wall
    # particle's density first, a fault that cannot be excluded (density_bounds)
    cfg, parts = column(cfl=0.3, boundary=boundary)
    stable = Solver(cfg, parts)
    stable.step()
    cfg_bad = cfg.replace(dt_fixed=factor * stable.dt, max_excluded_fraction=max_excluded)
    solver = Solver(cfg_bad, parts)
    before = solver.snapshot()
    with pytest.raises(HealthError) as err:
        for _ in range(200):
            before = solver.snapshot()
            steps_before, t_before = solver.steps, solver.time
            solver.step()
    e = err.value
    assert e.check in CHECKS
    assert e.step == steps_before + 1
    assert e.time == pytest.approx(t_before + cfg_bad.dt_fixed)
    if max_excluded:
        assert e.check == "excluded_fraction" and e.particle == -1
        assert "of the fluid mass would be excluded" in str(e)
    else:
        assert 0 <= e.particle < solver.n
    assert str(e.step) in str(e) and e.check in str(e)
    after = solver.snapshot()
    # walls set from the fluid before every evaluation (adami) carry no state of their own: the failed
    # step's first evaluation read them from the kept fluid, and the next step reads them again
    state = np.ones(solver.n, dtype=bool) if not solver.boundary.each_evaluation else after["ptype"] != BOUNDARY
    for key in ("pos", "vel", "rho"):
        assert np.isfinite(after[key]).all()
        np.testing.assert_array_equal(after[key][state], before[key][state])
    assert solver.time == pytest.approx(t_before) and solver.steps == steps_before
    # the failure stays reported until cleared; a caller can then go on with a sane step
    with pytest.raises(HealthError):
        solver.step()
    solver.reconfigure(dt_fixed=0.0)
    solver.clear_failure()
    solver.step()
    assert solver.steps == steps_before + 1
