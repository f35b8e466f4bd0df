"""gpusph-plan (gpusph_ros.plan): the particle count is the scene's, the memory is what the solver
holds, and the step estimate from a calibration at rest is a lower bound close to the real count.
An estimate from the scene alone prices 2 x 10^7 particles with their memory."""
import re

import numpy as np
import pytest
import warp as wp

from gpusph_ros.plan import estimate, estimate_text, landed_dt, plan, plan_reductions, table, text, zone_option
from gpusph_ros.runner import Run
from gpusph_ros.scenes import resources
from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.scenes.settings import Output, resolve
from gpusph_ros.sph import ConfigError, Solver

from conftest import planned_bytes

pytestmark = pytest.mark.unit


@pytest.fixture(scope="module")
def collapse():
    scene = load_scene("collapse_2d")
    config = resolve(scene, dx=0.005, end_time=0.1)
    return scene, config, plan(scene, config, calibration_steps=20)


def test_particles_and_memory(collapse):
    scene, config, p = collapse
    model = build(scene, **config.numerics)
    assert p["particles"] == len(model.particles) == 777 and p["fluid_particles"] == 276
    # at least the state the solver cannot do without: position, velocity (3 x 4 B), density, mass,
    # pressure (4 B), type, body, id (4 B) in the three states of a predictor-corrector step
    assert p["device_bytes"] >= 777 * 3 * (12 + 12 + 4 + 4 + 4)
    # and the neighbour list dominates it: max_neighbours x 4 B a particle at most, plus the rest
    solver = Solver(model.config, model.particles)
    assert p["device_bytes"] == solver.device_bytes()
    assert p["device_bytes"] < 777 * (solver.neighbours.max_neighbours * 4 + 400)


def test_the_step_estimate_is_a_close_lower_bound(collapse):
    scene, config, p = collapse
    model = build(scene, **config.numerics)
    solver = Solver(model.config, model.particles)
    solver.advance(config.output.end_time)
    assert p["steps"] <= solver.steps <= 1.3 * p["steps"], (p["steps"], solver.steps)
    assert np.isfinite(p["wall_s"]) and p["wall_s"] > 0
    assert "about" in text(p) and "777" in text(p)
    # the real-time factor it prints is the simulated time its estimate steps in its wall time
    assert p["real_time_factor"] == pytest.approx(p["end_time"] / p["wall_s"])
    assert "simulated s per wall s" in text(p)


def test_the_steps_land_on_the_finer_of_the_output_and_wrench_rate_grids():
    """A stop closer than a step cuts the steps to it: at 200 Hz, 2.53 ms steps become two of 2.5 ms
    a stop, and a run with such stops takes the steps the plan counts (runner.Run.step_output)."""
    assert landed_dt(2.53e-3, Output(output_rate=20.0, wrench_rate=200.0)) == pytest.approx(2.5e-3, rel=1e-12)
    assert landed_dt(2.4e-3, Output(output_rate=20.0)) == pytest.approx(0.05 / 21, rel=1e-12)
    assert landed_dt(1.0e-3, Output(output_rate=100.0, wrench_rate=50.0)) == pytest.approx(1.0e-3, rel=1e-12)
    scene = load_scene("paddle_2d")
    config = resolve(scene, dx=0.1, end_time=0.1, wrench_rate=200.0, particle_rate=0.0)
    p = plan(scene, config, calibration_steps=30)
    run = Run(scene, config)
    while not run.done:
        run.step_output()
    assert run.solver.steps == p["steps"] == 40  # two steps a 5 ms stop, at rest


def test_a_scene_is_priced_with_and_without_zones():
    """Without zones, a zone at half the spacing is proposed 4 dx around each obstacle and probe,
    below the tank's top; with zones, the scene is priced without them."""
    lab = load_scene("dambreak1_lab")
    label, zoned = zone_option(lab, 0.03)
    assert label == "zones (proposed)" and [z.name for z in zoned.refine] == ["near_obstruction", "near_velocity",
                                                                               "near_D"]
    near = zoned.refine[0]  # the obstruction 0.90-1.02 x 0.24-0.36, 0.4 m tall, in water 0.3 m deep
    assert near.lo == pytest.approx((0.78, 0.12, 0.0)) and near.hi == pytest.approx((1.14, 0.48, 0.37))
    label, plain = zone_option(load_scene("dambreak1_lab_zoned"), 0.03)
    assert label == "no zones" and plain.refine == [] and plain.obstacles == lab.obstacles
    stoker = load_scene("stoker_2d")
    config = resolve(stoker, dx=0.02, end_time=0.1)
    plans, _ = plan_reductions(stoker, config, calibration_steps=2)
    proposed = [p for p in plans if p["model"] == "zones (proposed)"]
    assert len(proposed) == 1 and proposed[0]["particles"] > plans[0]["particles"]
    assert "zones (proposed)   refine: [{name: near_" in table(plans, {})


def test_the_cli_refuses_a_run_the_machine_cannot_hold_with_its_numbers():
    """A spacing whose run no machine here holds (10^10 particles) is a refusal with the numbers,
    before any calibration, never a traceback."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "gpusph_ros.cli", "plan", "dambreak1_lab", "--set", "dx=0.0005"],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 1 and "Traceback" not in out.stderr, out.stderr
    assert re.search(r"gpusph-plan: dx = 0.0005 m needs up to 7.87e\+08 particles, \d+ GiB on cpu: max_particles is",
                     out.stderr), out.stderr
    assert "MIPPS, measured on" not in out.stdout and "walking the cells" in out.stdout


def test_an_estimate_prices_a_run_from_the_scene_alone():
    """At a spacing this machine builds, the estimate's particles are the build's exactly and its
    memory within 2% of what the solver holds with its lists that wide; the steps are a lower bound."""
    scene = load_scene("dambreak1_lab")
    config = resolve(scene, dx=0.03, end_time=0.05)
    e = estimate(scene, config)
    model = build(scene, **config.numerics)
    solver = Solver(model.config, model.particles)
    assert e["particles"] == len(model.particles) and e["fits"] is True and e["limit"] == ""
    assert e["device_bytes"] == pytest.approx(planned_bytes(solver), rel=0.02)
    solver.advance(0.05)
    assert e["steps"] <= solver.steps


def test_20_million_particles_are_priced_with_their_memory_and_refused_for_it(monkeypatch):
    """A 3D run of 2 x 10^7 particles: priced (particles, memory, steps) without building it; where
    it does not fit, the refusal names memory, not an index; only past Warp's 32-bit array shapes
    does one name the index."""
    scene = load_scene("dambreak1_lab")
    config = resolve(scene, dx=0.00177, end_time=0.5)
    monkeypatch.setattr(resources, "host_free_bytes", lambda: 16 * 2 ** 30)
    e = estimate(scene, config)
    assert 1.9e7 < e["particles"] < 2.1e7 and e["device_bytes"] > 20 * 2 ** 30 and e["fits"] is False
    assert "host memory" in e["limit"] and "32-bit" not in e["limit"]
    words = estimate_text(e)
    assert "GiB on cpu" in words and "does not fit" in words and "particle-steps" in words
    gpu = estimate(scene, resolve(scene, dx=0.00177, end_time=0.5, device="cuda:0"))
    # a GPU this machine lacks: its free memory unknown, the same particles, walking the cells (no lists)
    assert gpu["particles"] == e["particles"] and gpu["search"] == "cells" and e["search"] == "lists"
    assert gpu["device_bytes"] == e["bytes_by_search"]["cells"] < e["device_bytes"] / 4
    assert (gpu["fits"] is None) == (wp.get_cuda_device_count() == 0)
    with pytest.raises(ConfigError, match="host memory") as err:
        build(scene, **config.numerics)
    assert "32-bit" not in str(err.value)
    monkeypatch.setattr(resources, "host_free_bytes", lambda: 1 << 62)
    cfg = model_config(dx=0.03, max_particles=10 ** 12)
    with pytest.raises(ConfigError, match="32-bit array shape"):
        resources.check_count(resources.MAX_INDEXED + 1, cfg, "dx", 1e-4, "dx needs", "a coarser spacing")
    assert resources.check_count(resources.MAX_INDEXED, cfg, "dx", 1e-4, "dx needs", "a coarser spacing")


def model_config(**numerics):
    from gpusph_ros.sph import SolverConfig

    return SolverConfig(dim=3, **numerics).validate()


def test_a_zoned_scene_lists_the_reductions_that_cannot_carry_its_zones(tmp_path):
    """wall_planes does not carry refinement zones yet: the plan of a zoned scene says so beside the
    others, where it ended on that reduction's ConfigError (issue 58). The zone stands in the air
    at rest: it holds no fluid until the surge climbs there."""
    path = tmp_path / "dry_zone.yaml"
    path.write_text("base: collapse_2d\nrefine:\n  - {name: dry, lo: [0.2, 0.15], hi: [0.3, 0.2], ratio: 0.5}\n")
    scene = load_scene(path)
    plans, not_applicable = plan_reductions(scene, resolve(scene, dx=0.01, end_time=0.05), calibration_steps=3)
    assert [p["model"] for p in plans] == ["full", "no zones"]
    assert "refinement zones (refine:) are not carried" in not_applicable["wall_planes"]
    assert plans[0]["particles"] > plans[1]["particles"] and "not applicable" in table(plans, not_applicable)


def test_10_to_the_8_particles_are_priced_from_the_scene_with_the_step_rate_of_this_device(capsys):
    """DamBreak 1's laboratory tank at 1 mm, about 10^8 particles: gpusph-plan builds nothing of it.
    On a GPU (the cells walked, no lists) it needs under 45 GiB; with lists, over four times that, which
    this machine does not hold: a refusal naming memory. The wall time follows from the MIPPS timed
    here at a spacing coarse enough for about 10^5 particles."""
    from gpusph_ros.cli import plan_main

    assert plan_main(["dambreak1_lab", "--set", "dx=0.001", "--set", "device=cuda:0",
                      "--calibration-steps", "3"]) == 0 or wp.get_cuda_device_count() > 0
    gpu = capsys.readouterr().out
    particles = int(re.search(r"particles +at most ([\d,]+)", gpu).group(1).replace(",", ""))
    memory = float(re.search(r"memory +([\d.]+) GiB on cuda:0 \(\d+ B a particle, walking the cells", gpu).group(1))
    assert 0.95e8 < particles < 1.1e8 and memory < 45
    timed = re.search(r"wall time +at least .*: ([\d.e+]+) particle-steps at ([\d.]+) MIPPS, measured on cpu over \d+ "
                      r"steps at dx = [\d.]+ m \(([\d,]+) particles\)", gpu)
    assert timed and 5e4 < int(timed.group(3).replace(",", "")) < 5e5
    assert plan_main(["dambreak1_lab", "--set", "dx=0.001", "--calibration-steps", "3"]) == 1
    cpu = capsys.readouterr()
    assert re.search(r"GiB on cpu \(\d+ B a particle, with neighbour lists.*\): does not fit: .*host memory", cpu.out)
    assert "gpusph-plan: dx = 0.001 m needs up to 1.03e+08 particles" in cpu.err and "host memory" in cpu.err
