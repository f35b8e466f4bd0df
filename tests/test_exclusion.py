"""Exclude and count (sph.health): a fluid particle at fault leaves the flow, is counted by reason
with its mass, and the run goes on; the run fails only once the excluded fluid passes
max_excluded_fraction, and with 0 a fault fails it under its own name, as before.

The case: the 2D column collapse (Martin & Moyce's a = 57.15 mm column) at a/15, one or a few of its
fluid particles broken on purpose at the start.
"""
import dataclasses

import numpy as np
import pytest

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.sph import HealthError, Solver
from gpusph_ros.sph.state import EXCLUDED, FLUID

pytestmark = pytest.mark.physics

END = 0.03  # [s] ~150 steps: long enough that an excluded particle would have moved with the flow


def collapse(**numerics):
    scene = load_scene("collapse_2d")
    model = build(scene, dx=scene.fluid[0].hi[0] / 15, **numerics)
    return model.config, dataclasses.replace(model.particles, pos=model.particles.pos.copy(),
                                             vel=model.particles.vel.copy(), rho=model.particles.rho.copy())


def middle_fluid(parts, k=1):
    """k fluid particles from the middle of the column, away from walls and surface."""
    fluid = np.flatnonzero(parts.ptype == FLUID)
    centre = parts.pos[fluid].mean(axis=0)
    return fluid[np.argsort(np.linalg.norm(parts.pos[fluid] - centre, axis=1))[:k]]


def break_past_wall(cfg, parts, i):
    """Put fluid particle i 1.5 dx below the floor's face, inside the wall's particles."""
    parts.pos[i, 1] = cfg.wall_lo[1] - 1.5 * cfg.dx


def break_over_the_top(cfg, parts, i):
    """Put fluid particle i beyond the far wall's face as deep as break_past_wall, but above the
    wall's top: it went over the wall and left the tank, the wall did not let it through."""
    parts.pos[i, :2] = [cfg.wall_hi[0] + 1.5 * cfg.dx, cfg.wall_top + 2.0 * cfg.dx]


def break_density(cfg, parts, i):
    parts.rho[i] = 1.5 * cfg.rho0


def break_displacement(cfg, parts, i):
    """Move the particle into the air over the dry floor, alone (so nothing but its speed is
    wrong), with a velocity that carries it 3 h sideways in one (fixed) step, inside the tank."""
    parts.pos[i, :2] = [0.6 * cfg.wall_hi[0], cfg.wall_lo[1] + 0.12]
    parts.vel[i, 0] = 3.0 * cfg.h / cfg.dt_fixed


CASES = {"wall_penetration": (break_past_wall, {}), "outside_domain": (break_over_the_top, {}),
         "density_bounds": (break_density, {}),
         "displacement": (break_displacement, {"dt_fixed": 2.0e-4})}


@pytest.mark.parametrize("reason", sorted(CASES))
def test_a_faulty_particle_is_excluded_and_counted_and_the_run_goes_on(reason):
    breaker, numerics = CASES[reason]
    cfg, parts = collapse(**numerics)
    (i,) = middle_fluid(parts)
    breaker(cfg, parts, i)
    solver = Solver(cfg, parts)
    solver.step()
    assert solver.excluded == {**{r: 0 for r in solver.excluded}, reason: 1}
    first = solver.first_excluded_time
    assert first == pytest.approx(solver.time)
    held = solver.snapshot()
    solver.advance(END)
    assert solver.time == pytest.approx(END)
    assert solver.excluded_particles == 1 and solver.first_excluded_time == first
    fluid_mass = parts.mass[parts.ptype == FLUID].sum()
    assert solver.excluded_fraction == pytest.approx(parts.mass[i] / fluid_mass, rel=1e-6)
    snap = solver.snapshot()
    assert snap["ptype"][i] == EXCLUDED and (snap["ptype"] == EXCLUDED).sum() == 1
    # it stays where it was excluded, at rest, out of the flow; the rest of the fluid moves on
    np.testing.assert_array_equal(snap["pos"][i], held["pos"][i])
    np.testing.assert_array_equal(snap["vel"][i], 0.0)
    keep = solver.kept()
    assert not keep[i] and keep.sum() == len(parts) - 1
    moving = snap["ptype"] == FLUID
    assert np.isfinite(snap["pos"][moving]).all()
    assert np.abs(snap["pos"][moving] - held["pos"][moving]).max() > cfg.dx
    assert (np.abs(snap["rho"][moving] / cfg.rho0 - 1.0) < 0.25).all()


def test_an_excluded_particle_is_nobodys_neighbour():
    cfg, parts = collapse()
    (i,) = middle_fluid(parts)
    break_density(cfg, parts, i)
    solver = Solver(cfg, parts)
    solver.step()
    solver.neighbours.rebuild(solver.pos, force=True)
    nl = solver.neighbours
    count, nbr, ids = nl.count.numpy(), nl.nbr.numpy().reshape(solver.n, -1), solver.ids.numpy()
    slot = int(np.flatnonzero(ids == i)[0])
    assert count[slot] == 0
    listed = np.concatenate([nbr[s, :count[s]] for s in range(solver.n)])
    assert slot not in listed


@pytest.mark.parametrize("broken", [2, 3])
def test_past_the_limit_the_run_fails_with_the_state_before_that_step(broken):
    cfg, parts = collapse()
    fluid_mass = parts.mass[parts.ptype == FLUID].sum()
    bad = middle_fluid(parts, broken)
    cfg = cfg.replace(max_excluded_fraction=2.5 * parts.mass[bad[0]] / fluid_mass)  # room for two
    for i in bad:
        break_density(cfg, parts, i)
    solver = Solver(cfg, parts)
    before = solver.snapshot()
    if broken == 2:
        solver.step()
        assert solver.excluded["density_bounds"] == 2
        return
    with pytest.raises(HealthError) as err:
        solver.step()
    e = err.value
    assert e.check == "excluded_fraction" and e.step == 1 and e.particle == -1
    assert "density_bounds 3" in str(e) and "max_excluded_fraction" in str(e)
    assert solver.steps == 0 and solver.time == 0.0 and solver.excluded_particles == 0
    after = solver.snapshot()
    np.testing.assert_array_equal(after["ptype"], before["ptype"])
    np.testing.assert_array_equal(after["pos"], before["pos"])


def test_strict_mode_fails_under_the_faults_own_name():
    cfg, parts = collapse(max_excluded_fraction=0.0)
    (i,) = middle_fluid(parts)
    break_past_wall(cfg, parts, i)
    solver = Solver(cfg, parts)
    with pytest.raises(HealthError) as err:
        solver.step()
    assert err.value.check == "wall_penetration" and err.value.particle == i
    assert solver.excluded_particles == 0


def test_max_excluded_fraction_is_checked():
    cfg, _ = collapse()
    for bad in (-0.1, 1.0, "1%", True):
        with pytest.raises(ValueError, match="max_excluded_fraction"):
            cfg.replace(max_excluded_fraction=bad).validate()
