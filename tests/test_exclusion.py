"""Exclude and count (sph.health): a fluid particle at fault leaves the flow, is counted by reason
with its mass, and the run goes on; the run fails only once the excluded fluid passes
max_excluded_fraction, and with 0 a fault fails it under its own name, as before. Water that goes
over an open tank's walls is counted apart (left_tank), against max_left_fraction (no limit by
default).

The case: the 2D column collapse (Martin & Moyce's a = 57.15 mm column) at a/15, one or a few of its
fluid particles broken on purpose at the start.
"""
import dataclasses

import numpy as np
import pytest
import yaml

from gpusph_ros.scenes import resources
from gpusph_ros.scenes.build import build, fluid_boxes
from gpusph_ros.scenes.schema import load_scene, parse_scene
from gpusph_ros.sph import ConfigError, HealthError, Solver
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


def break_out_of_domain(cfg, parts, i):
    """Put fluid particle i past the domain's far end below the walls' top: through the wall."""
    parts.pos[i, :2] = [cfg.domain_hi[0] + cfg.dx, 0.5 * cfg.wall_top]


def break_density(cfg, parts, i):
    parts.rho[i] = 1.5 * cfg.rho0


def break_displacement(cfg, parts, i):
    """Move the particle into the air over the dry floor, alone (so nothing but its speed is
    wrong), with a velocity that carries it 3 h sideways in one (fixed) step, inside the tank."""
    parts.pos[i, :2] = [0.6 * cfg.wall_hi[0], cfg.wall_lo[1] + 0.12]
    parts.vel[i, 0] = 3.0 * cfg.h / cfg.dt_fixed


CASES = {"wall_penetration": (break_past_wall, {}), "outside_domain": (break_out_of_domain, {}),
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
    solver = Solver(cfg.replace(neighbour_search="lists"), parts)
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


def test_water_over_the_walls_is_counted_apart_and_fails_only_past_its_own_limit():
    """A particle over the far wall's top left the tank: excluded and counted as left_tank with its
    mass, not as a fault (excluded_fraction stays 0, however strict max_excluded_fraction is); with
    max_left_fraction 0 the run fails on left_fraction, the state before that step kept."""
    cfg, parts = collapse(max_excluded_fraction=0.0)
    (i,) = middle_fluid(parts)
    break_over_the_top(cfg, parts, i)
    solver = Solver(cfg, parts)
    solver.advance(END)
    assert solver.left_tank_particles == 1 and solver.excluded == {r: 0 for r in solver.excluded}
    fluid_mass = parts.mass[parts.ptype == FLUID].sum()
    assert solver.left_tank_fraction == pytest.approx(parts.mass[i] / fluid_mass, rel=1e-6)
    assert solver.excluded_fraction == 0.0 and solver.first_excluded_time is None
    assert solver.snapshot()["ptype"][i] == EXCLUDED and not solver.kept()[i]
    strict = Solver(cfg.replace(max_left_fraction=0.0), parts)
    with pytest.raises(HealthError) as err:
        strict.step()
    assert err.value.check == "left_fraction" and "left the tank over its walls (1 particles)" in str(err.value)
    assert strict.steps == 0 and strict.left_tank_particles == 0


def test_a_run_up_that_climbs_over_a_low_tank_runs_on():
    """The 2D collapse in a tank as tall as its column, under the strictest exclusion (0: a fault
    fails the run): the frictionless run-up on the far wall climbs to 1.75 H and throws fluid over its
    top by t = 0.5 s. That is no fault: the run goes on (it failed on outside_domain, as a 1.67 H
    tank did at 1.14 s, issue 58); the fluid that left is counted as left_tank, and the tank's fluid
    and what left add up to the fluid at the start."""
    scene = load_scene("collapse_2d")
    low = dataclasses.replace(scene, tank=(scene.tank[0], scene.depth, scene.tank[2]))
    model = build(low, dx=scene.fluid[0].hi[0] / 8, max_excluded_fraction=0.0)
    solver = Solver(model.config, model.particles)
    solver.advance(0.5)
    assert solver.time == pytest.approx(0.5) and solver.excluded_particles == 0
    assert solver.left_tank_particles > 0
    snap = solver.snapshot()
    fluid = model.particles.mass[model.particles.ptype == FLUID].sum()
    inside = snap["mass"][snap["ptype"] == FLUID].sum()
    assert inside + solver.left_tank_fraction * fluid == pytest.approx(fluid, rel=1e-6)  # float32 masses


def _lidded(walls="particles"):
    """The low tank of the run-up test, with ``lid: true``."""
    data = yaml.safe_load(load_scene("collapse_2d").text)
    data.update(tank=[data["tank"][0], data["depth"]], lid=True, walls=walls)
    return parse_scene(data)


def test_a_lid_keeps_the_run_up_in_the_tank():
    """The same run-up under a lid of wall particles: nothing leaves or is excluded, the fluid stays
    below the lid, and the build makes exactly the particles the plan prices (the walls' lattice
    continued across the top)."""
    scene = _lidded()
    assert scene.walls["lid"] == "particles"
    model = build(scene, dx=scene.fluid[0].hi[0] / 8, max_excluded_fraction=0.0)
    assert len(model.particles) == resources.particle_bound(scene, model.config, fluid_boxes(scene))
    solver = Solver(model.config, model.particles)
    solver.advance(0.5)
    assert solver.left_tank_particles == 0 and solver.excluded_particles == 0
    snap = solver.snapshot()
    assert snap["pos"][snap["ptype"] == FLUID, 1].max() < scene.tank[1]


def test_a_lid_is_a_wall_of_its_own_kind_and_asked_for_by_name():
    """``walls: {lid: planes}`` puts a plane across the top (normal down) beside particle walls;
    ``lid`` must be true or false, and a lid face without ``lid: true`` is no face of the tank."""
    scene = _lidded({"lid": "planes"})
    model = build(scene, dx=scene.fluid[0].hi[0] / 8)
    assert [(p.point[1], p.normal[1]) for p in model.config.planes] == [(scene.tank[1], -1.0)]
    assert model.config.wall_top > 1.0e29  # no water leaves a closed tank
    assert model.config.domain_hi[1] < scene.tank[1] + 5 * model.config.dx  # and there is no headroom
    data = yaml.safe_load(load_scene("collapse_2d").text)
    with pytest.raises(ConfigError, match="lid: 1 is not allowed; expected true or false"):
        parse_scene({**data, "lid": 1})
    with pytest.raises(ConfigError, match="walls"):
        parse_scene({**data, "walls": {"lid": "planes"}})
