"""One case of a study: the headless run, recorded, then analysed; its row of the results table.

Runs in a Dask worker (or anywhere): ``run_case`` writes ``<out>/cases/<case>/bag`` (the MCAP
recording) and ``<out>/cases/<case>/metrics.json`` (the analysis and the row), and returns the
row. A run that fails a health check, or a case that cannot be built, is a row with that status,
not an exception: the study goes on.
"""
import json
import shutil
import time
from pathlib import Path

from ..analysis.report import HEALTH_PEAKS, analyse
from ..runner import Run
from ..scenes.schema import load_scene
from ..scenes.settings import resolve

RUN_FIELDS = ("kernel", "viscosity", "boundary", "density_diffusion", "precision", "device")


def case_dir(out, name) -> Path:
    return Path(out) / "cases" / name


def finished_row(out, name):
    """The row of a case that has already finished (completed, or failed by a health check), or
    None: a case that never ran, or one that raised (``error: ...``, the code rather than the
    physics, perhaps fixed since), runs again."""
    path = case_dir(out, name) / "metrics.json"
    if not path.is_file():
        return None
    try:
        row = json.loads(path.read_text())["row"]
    except (ValueError, KeyError):
        return None  # cut short while writing: run it again
    return None if str(row.get("status", "")).startswith("error") else row


def row_of(case: dict, report: dict, result: dict, metrics: list) -> dict:
    """The flat results row: the case, the run, and per metric its value, the experiment's, the
    percent error against the experiment, GPUSPH's value at this dx and scenario and our value's
    percent difference from it."""
    row = {"case": case["name"], "scene": case["scene"], "scenario": case["scenario"], **case["grid"],
           "status": result.get("status", "?"), "particles": report.get("particles"),
           "fluid_particles": report.get("fluid_particles"), "steps": result.get("steps"),
           "simulated_time_s": result.get("simulated_time_s"), "wall_time_s": result.get("wall_time_s"),
           "mipps": result.get("mipps"), "excluded_particles": result.get("excluded_particles"),
           "excluded_fraction": result.get("excluded_fraction"), **{k: result.get(k) for k in HEALTH_PEAKS},
           "dx": report.get("dx"),
           **{k: report.get(k) for k in RUN_FIELDS}, "gpusph_scenario": report.get("gpusph_scenario"),
           "gpusph_scenario_exact": report.get("gpusph_scenario_exact")}
    for key, value in case["grid"].items():  # a case that never ran still says where it sat
        if row.get(key) is None:
            row[key] = value
    row["particle_steps"] = (row["particles"] or 0) * (row["steps"] or 0)
    by_key = {m["key"]: m for m in report.get("metrics", [])}
    for key in metrics:
        m = by_key.get(key, {})
        value, exp, gp = m.get("value"), m.get("experiment"), m.get("gpusph")
        row[key] = value
        row[f"{key}_experiment"] = exp
        row[f"{key}_error_pct"] = m.get("error_pct")
        row[f"{key}_gpusph"] = gp
        row[f"{key}_gpusph_error_pct"] = m.get("gpusph_error_pct")
        row[f"{key}_vs_gpusph_pct"] = (value - gp) / abs(gp) * 100.0 if value is not None and gp else None
    return row


def run_case(case: dict, out: str, metrics: list, cpu_threads: int = 0, device: str = None) -> dict:
    """Run, record and analyse ``case`` (``schema.Case`` as a dict); its row."""
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING  # a worker process starts with Warp's per-module lines on
    folder = case_dir(out, case["name"])
    bag = folder / "bag"
    if bag.exists():  # a half-written bag of a run that was killed: start the case again
        shutil.rmtree(bag)
    folder.mkdir(parents=True, exist_ok=True)
    settings = dict(case["settings"])
    if device:
        settings["device"] = device
    if cpu_threads:
        settings.setdefault("cpu_threads", cpu_threads)
    start = time.perf_counter()
    try:
        scene = load_scene(case["scene"])
        run = Run(scene, resolve(scene, **settings))
        result = run.execute(run.open_recording(bag))
        report, _ = analyse(bag)
    except Exception as err:  # a case that cannot be built or analysed is reported, not raised
        result, report = {"status": f"error: {type(err).__name__}: {err}"}, {}
    result.setdefault("wall_time_s", round(time.perf_counter() - start, 3))
    row = row_of(case, report, result, metrics)
    (folder / "metrics.json").write_text(json.dumps({"case": case, "report": report, "row": row}, indent=1,
                                                    default=str))
    return row
