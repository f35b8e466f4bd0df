"""What a run will cost, before it runs: particles, device memory, steps and wall time.

The solver is built on the chosen device (so the memory is what it allocates, neighbour lists
included) and stepped a little from rest: the step rate is measured on the loop a run uses, after
the kernels are loaded and the loop captured,
and the number of steps to the end time follows from the mean time step of those first steps. A
flow that speeds up takes shorter steps (the CFL condition on c0 + |u|, the force condition), so
the estimate is a lower bound (measured: 551 for 562 steps of the 2D collapse to 0.1 s at 5 mm,
518 for 593 of DamBreak 1 to 0.5 s at 5 cm).

A run larger than this machine, or for a device it does not have, is priced from the scene alone
(``estimate``, ``gpusph-plan --estimate``): the particles the build would make at most, the memory
they take on the device (scenes/resources.py, within a few percent of what a solver holds) and
whether it is free there, with neighbour lists (a CPU's default) and walking the cells (a GPU's),
and the fewest steps the sound speed allows; nothing is built. ``gpusph-plan`` prices so any run of
more than LARGE particles, or on a device this machine lacks, and times the steps at a spacing
coarse enough for CALIBRATION_PARTICLES on the device it runs on (``coarse_plan``): a 10^8-particle
run is priced in seconds, where building it to time 30 steps would take longer than the answer is
worth.

With refinement zones the calibration prices the zones' particles as they stand at rest; fluid that
flows into a zone later makes fine particles there, so the estimate is a lower bound again. A
scene with zones is priced without them too; one without them, with a proposed zone at half the
spacing around each obstacle and probe (``proposed_zones``), printed as the ``refine:`` to paste.
"""
import dataclasses
import math
import re
import time

import numpy as np
import warp as wp
import yaml

from .scenes import reduce, resources
from .scenes.build import build_run, priced
from .scenes.schema import parse_scene
from .sph import ConfigError, decomposition
from .sph.config import NEIGHBOUR_SEARCHES
from .sph.device import default_device
from .sph.kernels import coarse_stride
from .sph.neighbours import list_skin

# a proposed zone reaches this many of the scene's dx past an obstacle or a probe: more than a
# coarse kernel support (2 h = 2.6 dx), so that the flow arriving there is fine before it does
ZONE_MARGIN_DX = 4.0
# a run of more particles is priced from its scene (coarse_plan), its steps timed at a spacing that
# makes about CALIBRATION_PARTICLES
LARGE = 2_000_000
CALIBRATION_PARTICLES = 100_000


def plan(scene, run_config, calibration_steps: int = 30) -> dict:
    model = build_run(scene, run_config)
    solver = model.solver()
    # timed on the loop a run steps with (Solver.advance: replayed from its capture, or eager), not
    # step by step, which reads the device twice a step; the first steps load the kernels and capture
    # the loop, untimed. Aimed with the step the conditions allow (dt_stable): an advance's last step
    # is cut short to land on its target
    solver.step()
    solver.advance(solver.time + 2.0 * solver.dt_stable)
    wp.synchronize_device(solver.device)
    t0, steps0 = solver.time, solver.steps
    start = time.perf_counter()
    solver.advance(solver.time + calibration_steps * solver.dt_stable)
    wp.synchronize_device(solver.device)
    wall = time.perf_counter() - start
    steps = solver.steps - steps0
    dt = landed_dt((solver.time - t0) / steps, run_config.output)
    rate = steps / wall
    end = run_config.output.end_time
    until = reduce.valid_until(scene) if run_config.reduction.model == "2d_until_reflection" else {}
    return {"scene": scene.name, "valid_until": until, "model": run_config.reduction.label, "dx": model.config.dx,
            "kernel": model.config.kernel,
            "precision": model.config.precision, "device": str(solver.device), "particles": solver.n,
            "fluid_particles": model.fluid_particles, "device_bytes": solver.device_bytes(),
            "calibration_steps": steps, "calibration_wall_s": wall, "dt": dt, "steps_per_s": rate,
            "mipps": solver.n * rate / 1e6, "end_time": end, "steps": int(round(end / dt)),
            "wall_s": end / dt / rate, "real_time_factor": dt * rate}


def landed_dt(dt: float, output) -> float:
    """The mean step of a run whose steps of ``dt`` land on each of its stops: the outputs and the
    wrench-rate times (``output``: scenes.settings.Output), the finer of the two grids taken; a stop
    closer than dt cuts the steps to it (runner.Run.step_output)."""
    stop = 1.0 / max(output.output_rate, output.wrench_rate)
    return stop / math.ceil(stop / dt - 1.0e-9)


def estimate(scene, run_config) -> dict:
    """What ``plan`` says of a run, from the scene alone: its particles (at most), device memory,
    whether that memory is free on the device ("fits": True, False, or None where the device is not
    on this machine; "limit": why not), and the fewest steps to the end time (dt <= cfl h / c0, the
    sound-speed condition alone) with the particle-steps they cost. Nothing is built or allocated."""
    reduced, cfg, n = priced(scene, run_config)
    if reduced.refine:
        raise ValueError("refine: an estimate prices a scene without zones (their particles are known only as "
                         "they are split); plan it without --estimate, or without its zones")
    here, free_dev = True, None
    if cfg.device != "cpu":
        try:
            free_dev = resources.device_free_bytes(cfg.device)
        except (RuntimeError, ValueError):  # Warp: no such device here; its memory sets no limit we know
            here, free_dev = False, math.inf
    need, limit = resources.shortfall(n, cfg, free_dev=free_dev)
    end = run_config.output.end_time
    dt = landed_dt(cfg.cfl * cfg.h / cfg.sound_speed, run_config.output)
    steps = int(np.ceil(end / dt))
    fits = not limit if here else None
    searches = [search for search in NEIGHBOUR_SEARCHES if search != "auto"]
    return {"scene": scene.name, "model": run_config.reduction.label, "dx": cfg.dx, "kernel": cfg.kernel,
            "precision": cfg.precision, "device": cfg.device, "particles": n, "device_bytes": need,
            "search": "cells" if cfg.cell_walks else "lists",
            "bytes_by_search": {search: resources.device_bytes(n, cfg.replace(neighbour_search=search))
                                for search in searches},
            "fits": fits, "limit": re.sub(r"^(; | and )", "", limit), "end_time": end, "dt": dt, "steps": steps,
            "particle_steps": n * steps}


def coarse_plan(scene, run_config, calibration_steps: int = 30) -> dict:
    """``estimate`` of the run, with the wall time its particle-steps take at the MIPPS that
    ``plan`` measures at a spacing coarse enough for about CALIBRATION_PARTICLES, on the run's device
    if this machine has it, else on this machine's (``calibration``: what was timed); nothing timed
    where the run does not fit its device."""
    e = estimate(scene, run_config)
    if e["fits"] is False:
        return e
    cfg = run_config.solver
    device = cfg.device if e["fits"] is not None else default_device()
    # the particles scale as dx^-dim: the ratio's root; never finer than the run itself
    dx = cfg.dx * max(1.0, e["particles"] / CALIBRATION_PARTICLES) ** (1.0 / scene.dim)
    small = dataclasses.replace(run_config, numerics={**run_config.numerics, "dx": dx, "device": device},
                                solver=cfg.replace(dx=dx, device=device))
    timed = plan(scene, small, calibration_steps)
    return {**e, "mipps": timed["mipps"], "wall_s": e["particle_steps"] / (timed["mipps"] * 1e6),
            "calibration": {key: timed[key] for key in ("dx", "particles", "device", "calibration_steps",
                                                        "calibration_wall_s")}}


def rank_plan(scene, run_config, ranks: int) -> dict:
    """The run cut for ``ranks`` ranks (sph/decomposition.py) and what each rank holds: its particles,
    its halo, its device memory (both, at resources.device_bytes a particle) and the bytes its halo
    takes to refresh a step. The cells are one reach wide: the kernel support, with the neighbour
    lists' skin where the run keeps lists (a list must find its neighbours in the halo until it is
    rebuilt); the halo is the exchange's, decomposition.HALO_CELLS deep (SPS_HALO_CELLS under SPS).
    A run of more than LARGE particles is cut as built at a spacing that makes about
    CALIBRATION_PARTICLES, its counts scaled to the run's spacing (a slab's as dx^-dim, a halo's,
    a fixed number of cells thick, as dx^(1-dim)); its cells are counted at the run's spacing. ConfigError on
    ``ranks`` where a rank would have fewer than decomposition.MIN_CELLS cells."""
    cfg = run_config.solver
    n = priced(scene, run_config)[2]
    dx = cfg.dx * max(1.0, n / CALIBRATION_PARTICLES) ** (1.0 / scene.dim) if n > LARGE else cfg.dx
    coarse = dataclasses.replace(run_config, numerics={**run_config.numerics, "dx": dx}, solver=cfg.replace(dx=dx))
    model = build_run(scene, coarse)
    mc = model.config
    refined = bool(model.scene.refine)
    reach = 2.0 * mc.h  # the scene's h: a refinement zone's particles are finer
    if not mc.cell_walks:
        reach *= list_skin(coarse_stride(mc, refined))
    lo = [0.0, 0.0, 0.0]
    hi = list(model.scene.tank) + [0.0] * (3 - len(model.scene.tank))
    pos = model.particles.pos
    fine = reach * cfg.dx / dx  # the reach at the run's spacing: the ranks' cells
    spread = dx if dx != cfg.dx else 0.0
    slabs = decomposition.split(pos, lo, hi, mc.periodic, fine, ranks, spread=spread)
    scale, thin = (dx / cfg.dx) ** scene.dim, (dx / cfg.dx) ** (scene.dim - 1)
    own = [int(round(scale * c)) for c in slabs.counts(pos, spread)]
    depth = decomposition.SPS_HALO_CELLS if mc.viscosity == "sps" else decomposition.HALO_CELLS
    halo = [int(round(thin * len(h))) for h in slabs.halos(pos, depth * slabs.cell * dx / cfg.dx)]
    scalar = 8 if cfg.precision == "float64" else 4
    return {"scene": scene.name, "dx": cfg.dx, "ranks": ranks, "slabs": slabs.describe(), "reach": fine,
            "scaled_from": None if dx == cfg.dx else dx, "particles": own, "halo": halo,
            "device_bytes": [resources.device_bytes(a + b, mc.replace(dx=cfg.dx), refined) for a, b in zip(own, halo)],
            "exchange_bytes": [decomposition.exchange_bytes(b, scalar) for b in halo]}


def rank_text(r: dict) -> str:
    scaled = f"; counted at dx = {r['scaled_from']:.3g} m and scaled" if r["scaled_from"] else ""
    lines = [f"{r['scene']} on {r['ranks']} ranks at dx = {r['dx']:g} m: {r['slabs']} "
             f"(reach {r['reach']:.3g} m{scaled})",
             "rank  particles       halo  halo share  memory      halo a step"]
    for k, (own, halo, mem, ex) in enumerate(zip(r["particles"], r["halo"], r["device_bytes"], r["exchange_bytes"])):
        lines.append(f"{k:4d}  {own:>10,}  {halo:>9,}  {halo / max(own, 1):9.1%}  {mem / 2 ** 30:7.3g} GiB  "
                     f"{ex / 2 ** 20:8.3g} MiB")
    mean = sum(r["particles"]) / r["ranks"]
    lines.append(f"imbalance: the largest rank holds {max(r['particles']) / mean - 1.0:+.1%} of the mean")
    return "\n".join(lines)


def is_large(scene, run_config) -> bool:
    """Whether ``gpusph-plan`` prices the run from its scene (coarse_plan): more than LARGE particles,
    or a device this machine does not have."""
    if run_config.solver.device != "cpu":
        try:
            resources.device_free_bytes(run_config.solver.device)
        except (RuntimeError, ValueError):
            return True
    return priced(scene, run_config)[2] > LARGE


def estimate_text(e: dict) -> str:
    if e["fits"] is None:
        verdict = f"{e['device']} is not on this machine: its free memory is not known here"
        if e["limit"]:
            verdict += f"; {e['limit']}"
    else:
        verdict = "fits" if e["fits"] else f"does not fit: {e['limit']}"
    searches = "; ".join(f"{_SEARCHED[search]}: {b / 2 ** 30:.3g} GiB ({b / e['particles']:.0f} B a particle)"
                         for search, b in e["bytes_by_search"].items())
    lines = [
        f"{e['scene']} ({e['model']}): dx = {e['dx']:g} m, {e['kernel']} kernel, {e['precision']} on {e['device']} "
        "(estimated from the scene: nothing built)",
        f"particles    at most {e['particles']:,}",
        f"memory       {e['device_bytes'] / 2 ** 30:.3g} GiB on {e['device']} "
        f"({e['device_bytes'] / e['particles']:.0f} B a particle, {_SEARCHED[e['search']]}): {verdict}",
        f"             {searches}",
        f"steps        at least {e['steps']:,} to t = {e['end_time']:g} s (dt <= cfl h / c0, landing on each output: "
        f"{e['dt']:.3g} s)",
    ]
    if "mipps" not in e:
        return "\n".join(lines + [f"cost         at least {e['particle_steps']:.3g} particle-steps: "
                                  f"{e['particle_steps'] / 1e6:.3g} s of wall time at 1 MIPPS (gpusph-plan on the "
                                  f"device measures its MIPPS)"])
    c = e["calibration"]
    return "\n".join(lines + [
        f"wall time    at least {_duration(e['wall_s'])}: {e['particle_steps']:.3g} particle-steps at "
        f"{e['mipps']:.3g} MIPPS, measured on {c['device']} over {c['calibration_steps']} steps at dx = "
        f"{c['dx']:.3g} m ({c['particles']:,} particles)",
        f"real time    {e['end_time'] / e['wall_s']:.3g} simulated s per wall s at most"])


_SEARCHED = {"lists": "with neighbour lists (a CPU's default)", "cells": "walking the cells (a GPU's default)"}


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.3g} s"
    if seconds < 7200:
        return f"{seconds / 60:.3g} min"
    return f"{seconds / 3600:.3g} h"


def plan_reductions(scene, run_config, calibration_steps: int = 30) -> tuple:
    """(plans, not_applicable): the plan of the run as configured, then of the run under each
    reduction of ``reduce.applicable`` that it does not already use, then with and without zones
    (``zone_option``); and why the others do not apply."""
    cfg = build_run(scene, run_config).config
    options = reduce.applicable(scene, run_config.output.end_time, cfg.dx)
    plans = [plan(scene, run_config, calibration_steps)]
    not_applicable = dict(options["not applicable"])
    label, other = zone_option(scene, cfg.dx)
    others = [(name, scene, dataclasses.replace(run_config, reduction=reduction), {})
              for name, reduction in options["apply"].items() if name != run_config.reduction.label]
    for name, chosen, config, extra in others + [(label, other, run_config, {"model": label, "refine": other.refine})]:
        try:
            plans.append({**plan(chosen, config, calibration_steps), **extra})
        except (ConfigError, ValueError) as err:  # a reduction that does not carry the scene's zones, a
            not_applicable[name] = str(err)       # proposal the run's numerics cannot refine
    return plans, not_applicable


def zone_option(scene, dx: float) -> tuple:
    """(label, scene): a scene with zones without them; one without, with ``proposed_zones``."""
    data = yaml.safe_load(scene.text) if scene.text else None
    if data is None:
        raise ValueError(f"scene {scene.name}: no scene text to change")
    if scene.refine:
        data["refine"] = []
        return "no zones", parse_scene(data, default_name=scene.name)
    data["refine"] = proposed_zones(scene, dx)
    return "zones (proposed)", parse_scene(data, default_name=scene.name)


def proposed_zones(scene, dx: float) -> list:
    """``refine:`` items: a zone at half the spacing ZONE_MARGIN_DX dx around each obstacle and
    each probe, from the floor (or a point probe's or sensor's height less that reach) to that reach
    above the scene's depth or the probe's point, whichever is lower, and a dx below the tank's top:
    no fine air above the water, where the slots reserved for a zone would go unused. Where the accuracy comes from
    (docs/variable_resolution.md): resolution at the body and over the bed in front of it."""
    dim, up = scene.dim, scene.dim - 1
    margin = round(ZONE_MARGIN_DX * dx, 6)
    tank = np.asarray(scene.tank[:dim])

    def box(name, lo, hi, top):
        lo, hi = np.asarray(lo[:dim], dtype=np.float64) - margin, np.asarray(hi[:dim], dtype=np.float64) + margin
        hi[up] = min(min(top, scene.depth) + margin, tank[up] - dx)  # below the top: a zone reaching a
        # tank face is open beyond it (refine.zone_bounds), and the headroom's air would be fine
        return {"name": name, "lo": [round(float(v), 6) for v in np.clip(lo, 0.0, tank)],
                "hi": [round(float(v), 6) for v in np.clip(hi, 0.0, tank)], "ratio": 0.5}

    zones = [box(f"near_{o.name}", o.lo, o.hi, o.hi[up]) for o in scene.obstacles]
    for probe in scene.probes:
        line = probe.type in ("profile", "gauge", "column")
        zones.append(box(f"near_{probe.name}", probe.position, probe.position,
                         scene.depth if line else probe.position[up]))
    return zones


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
    lines += [f"{p['model']:<18} refine: " + yaml.safe_dump(_zone_items(p["refine"]), default_flow_style=True,
                                                             sort_keys=False, width=10_000).strip()
              for p in plans if p.get("refine")]
    lines += [f"{label:<18} not applicable: {why}" for label, why in not_applicable.items()]
    return "\n".join(lines)


def _zone_items(zones) -> list:
    """Zones as the ``refine:`` items a scene file takes."""
    out = []
    for z in zones:
        item = {"name": z.name, "around": z.around, "margin": z.margin} if z.around else \
            {"name": z.name, "lo": list(z.lo), "hi": list(z.hi)}
        out.append({**item, "ratio": z.ratio})
    return out


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
        f"real time    {p['real_time_factor']:.3g} simulated s per wall s at most (the steps alone; the outputs cost "
        "more: bench/realtime.py measures a node's run)",
    ] + ([f"validity     {validity(p)}"] if p["valid_until"] else []))
