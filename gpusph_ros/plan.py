"""What a run will cost, before it runs: particles, device memory, steps and wall time.

The solver is built on the chosen device (so the memory is what it allocates, neighbour lists
included) and stepped a little from rest: the step rate is measured after the kernels are loaded,
and the number of steps to the end time follows from the mean time step of those first steps. A
flow that speeds up takes shorter steps (the CFL condition on c0 + |u|, the force condition), so
the estimate is a lower bound (measured: 551 for 562 steps of the 2D collapse to 0.1 s at 5 mm,
518 for 593 of DamBreak 1 to 0.5 s at 5 cm).
"""
import dataclasses
import time

import warp as wp

from .scenes import reduce
from .scenes.build import build_run


def plan(scene, run_config, calibration_steps: int = 30) -> dict:
    model = build_run(scene, run_config)
    solver = model.solver()
    solver.step()  # loads the kernels: not timed
    wp.synchronize_device(solver.device)
    t0, steps0 = solver.time, solver.steps
    start = time.perf_counter()
    for _ in range(calibration_steps):
        solver.step()
    wp.synchronize_device(solver.device)
    wall = time.perf_counter() - start
    steps = solver.steps - steps0
    dt = (solver.time - t0) / steps
    rate = steps / wall
    end = run_config.output.end_time
    until = reduce.valid_until(scene) if run_config.reduction.model == "2d_until_reflection" else {}
    return {"scene": scene.name, "valid_until": until, "model": run_config.reduction.label, "dx": model.config.dx,
            "kernel": model.config.kernel,
            "precision": model.config.precision, "device": str(solver.device), "particles": solver.n,
            "fluid_particles": model.fluid_particles, "device_bytes": solver.device_bytes(),
            "calibration_steps": steps, "calibration_wall_s": wall, "dt": dt, "steps_per_s": rate,
            "mipps": solver.n * rate / 1e6, "end_time": end, "steps": int(round(end / dt)),
            "wall_s": end / dt / rate}


def plan_reductions(scene, run_config, calibration_steps: int = 30) -> tuple:
    """(plans, not_applicable): the plan of the run as configured, then of the run under each
    reduction of ``reduce.applicable`` that it does not already use; and why the others do not apply."""
    cfg = build_run(scene, run_config).config
    options = reduce.applicable(scene, run_config.output.end_time, cfg.dx)
    plans = [plan(scene, run_config, calibration_steps)]
    for label, reduction in options["apply"].items():
        if label != run_config.reduction.label:
            plans.append(plan(scene, dataclasses.replace(run_config, reduction=reduction), calibration_steps))
    return plans, options["not applicable"]


def table(plans: list, not_applicable: dict) -> str:
    """One line a model: particles, memory, estimated steps and wall time, and the share of the first."""
    first = plans[0]
    lines = [f"{'model':<18} {'particles':>11} {'fluid':>11} {'memory MB':>10} {'steps/s':>9} {'steps':>9} "
             f"{'wall min':>9} {'cost':>6}"]
    for p in plans:
        share = p["wall_s"] / first["wall_s"]
        lines.append(f"{p['model']:<18} {p['particles']:>11,} {p['fluid_particles']:>11,} "
                     f"{p['device_bytes'] / 1e6:>10.1f} {p['steps_per_s']:>9.1f} {p['steps']:>9,} "
                     f"{p['wall_s'] / 60:>9.2f} {share:>6.1%}")
    lines += [f"{p['model']:<18} {validity(p)}" for p in plans if p["valid_until"]]
    lines += [f"{label:<18} not applicable: {why}" for label, why in not_applicable.items()]
    return "\n".join(lines)


def validity(p: dict) -> str:
    """Until when a model that holds only for a while (2d_until_reflection) holds at its probes."""
    return "holds until " + ", ".join(f"t = {t:.3g} s at {name}" for name, t in p["valid_until"].items()) + \
        " (then the obstacle's reflection arrives)"


def text(p: dict) -> str:
    return "\n".join([
        f"{p['scene']} ({p['model']}): dx = {p['dx']:g} m, {p['kernel']} kernel, {p['precision']} on {p['device']}",
        f"particles    {p['particles']:,} ({p['fluid_particles']:,} fluid)",
        f"memory       {p['device_bytes'] / 1e6:.1f} MB on {p['device']} "
        f"({p['device_bytes'] / p['particles']:.0f} B a particle)",
        f"calibration  {p['calibration_steps']} steps from rest in {p['calibration_wall_s']:.2f} s: "
        f"dt {p['dt']:.3g} s, "
        f"{p['steps_per_s']:.1f} steps/s, {p['mipps']:.3f} MIPPS",
        f"estimate     to t = {p['end_time']:g} s: about {p['steps']:,} steps (at least: faster flow, shorter steps), "
        f"about {p['wall_s'] / 60:.1f} min of wall time",
    ] + ([f"validity     {validity(p)}"] if p["valid_until"] else []))
