"""One run of a scene with only the solver (no ROS), every probe and body force sampled at the
scene's output rate into flat named series; what bench/economy.py and bench/precision.py measure.

Series names: ``points/<probe>/u`` (x velocity), ``points/<probe>/p``, ``columns/<probe>/u``,
``profiles/<probe>/h<k>`` (x velocity at the k-th height), ``gauges/<probe>``, ``sensors/<probe>`` (a
pressure sensor's face mean), ``wrenches/<body>/fx``.
"""
import argparse
import time
from pathlib import Path

import numpy as np
import warp as wp


def flatten(sample: dict) -> dict:
    out = {}
    for name, v in sample["points"].items():
        out[f"points/{name}/u"] = float(v["vel"][0])
        out[f"points/{name}/p"] = float(v["pressure"])
    for name, v in sample["columns"].items():
        out[f"columns/{name}/u"] = float(v["vel"][0])
    for name, v in sample["profiles"].items():
        for k, vel in enumerate(v["vel"]):
            out[f"profiles/{name}/h{k}"] = float(vel[0])
    for name, v in sample["gauges"].items():
        out[f"gauges/{name}"] = float(v)
    for name, v in sample["sensors"].items():
        out[f"sensors/{name}"] = float(v)
    for name, (force, _) in sample["wrenches"].items():
        out[f"wrenches/{name}/fx"] = float(force[0])
    return out


def model_of_about(scene_name: str, target: float, **settings):
    """The scene built at the spacing whose particle count is within 5% of ``target`` (DamBreak 1
    has 16,898 particles at 3 cm; the walls make the count scale between dx^-2 and dx^-3)."""
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import load_scene

    scene, dx = load_scene(scene_name), 0.03 * (16898 / target) ** (1 / 3)
    while True:
        model = build(scene, dx=dx, **settings)
        n = len(model.particles)
        if abs(n / target - 1.0) < 0.05:
            return model
        dx *= (n / target) ** (1 / 2.5)


def run_series(scene_name, **settings) -> dict:
    """Run ``scene_name`` (a built-in scene's name, a file's path, or a parsed Scene) under run
    ``settings`` (``scenes.settings.resolve`` keys); the record: counts, steps, wall time (kernel
    loading excluded), MIPPS, the fluid particles excluded, how it ended, and ``series`` {name: list}
    with ``t``."""
    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.measure.suite import Measurements
    from gpusph_ros.scenes.build import build_run
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve
    from gpusph_ros.sph import HealthError, NeighbourOverflow

    scene = load_scene(scene_name) if isinstance(scene_name, (str, Path)) else scene_name
    config = resolve(scene, **settings)
    built = build_run(scene, config)
    solver = built.solver()
    measurements = Measurements(solver, built)
    rate, end = config.output.output_rate, config.output.end_time
    series = {"t": []}
    status = "completed"
    solver.step()  # loads the kernels, untimed
    wp.synchronize_device(solver.device)
    steps0, start = solver.steps, time.perf_counter()
    try:
        for k in range(1, int(np.floor(end * rate + 1e-9)) + 1):
            solver.advance(k / rate)
            series["t"].append(solver.time)
            for name, value in flatten(measurements.sample()).items():
                series.setdefault(name, []).append(value)
    except (HealthError, NeighbourOverflow) as err:
        status = f"failed: {err}"
    wp.synchronize_device(solver.device)
    wall = time.perf_counter() - start
    steps = solver.steps - steps0
    cfg = built.config
    return {"scene": scene.name, "model": config.reduction.label, "dx": cfg.dx, "kernel": cfg.kernel,
            "precision": cfg.precision, "device": str(solver.device), "particles": solver.n,
            "fluid_particles": built.fluid_particles, "steps": steps, "wall_s": wall,
            "mipps": solver.n * steps / wall / 1e6 if wall > 0 else 0.0, "simulated_s": solver.time,
            "excluded": solver.excluded_particles, "status": status, "series": series}


def parser(doc: str, out: str):
    """(parser, run, report) sub-parsers of a ``run`` / ``report`` bench script: run takes --device,
    --end-time and --out, report the folders to read."""
    main = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    sub = main.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run")
    run.add_argument("--device", default="cpu")
    run.add_argument("--end-time", type=float, default=None)
    run.add_argument("--out", default=out)
    run.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE", help="more run settings")
    report = sub.add_parser("report")
    report.add_argument("folders", nargs="+")
    return main, run, report


def settings(args) -> dict:
    """The run settings of ``--set`` and ``--end-time``."""
    from gpusph_ros.scenes.settings import parse_set

    out = dict(map(parse_set, args.set))
    if args.end_time:
        out["end_time"] = args.end_time
    return out
