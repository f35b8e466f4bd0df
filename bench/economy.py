"""Scene economy on DamBreak 2: the full 3D flume, the thin periodic slab and the 2D section at the
same dx, each run to the scene's end time; what each costs and what each measures.

    python bench/economy.py run --scene dambreak2_010 --dx 0.015 --models full slab 2d [--device cuda:0]
        [--set kernel=wendland viscosity=sps] --out DIR
    python bench/economy.py report DIR [DIR ...]

``run`` needs only the solver (no ROS): per model it writes DIR/<scene>_<model>_<dx>.json with the
particle counts, steps, wall time, MIPPS, how the run ended, and the bore column's and profile's
series at the scene's output rate. ``report`` turns those files into the economy table: arrival
time, mean bore velocity over the 6 s behind it against Arnason et al. (2009) and the thesis's
GPUSPH at the same dx, the normalised profile against the experiment (0.15 m case), particles
and wall time (same device).
"""
import json
import sys
from pathlib import Path

import numpy as np
import warp as wp

from series import parser, run_series, settings


def run(scene_name: str, dx: float, model: str, device: str, out_dir: Path, extra: dict):
    record = run_series(scene_name, dx=dx, model=model, device=device, **extra)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / f"{scene_name}_{model}_{dx:g}.json").write_text(json.dumps(record))
    print(f"{scene_name} {model:>5} dx={dx:g}: {record['particles']:,} particles "
          f"({record['fluid_particles']:,} fluid), "
          f"{record['steps']:,} steps in {record['wall_s']:.1f} s, {record['mipps']:.2f} MIPPS on {record['device']}; "
          f"{record['status']}", flush=True)
    return record


def metrics(record: dict, data):
    from gpusph_ros.analysis import metrics as M
    from gpusph_ros.analysis import reference as R

    series = record["series"]
    t, u = np.asarray(series["t"]), np.asarray(series["columns/bore/u"])
    case = record["scene"]
    arrival = M.bore_arrival(t, u)
    mean, covered = M.mean_behind(t, u, arrival)
    heights = sorted((k for k in series if k.startswith("profiles/profile/")), key=lambda k: int(k.rsplit("h", 1)[1]))
    normalised = [M.mean_behind(t, np.asarray(series[k]), arrival)[0] / mean for k in heights]
    experiment = R.experiment_value(data, case, "mean_bore_velocity_6s_window")
    gpusph = None
    for scenario in (1, 2, 3):
        value = R.gpusph_value(data, f"{case}_mean_velocity.csv", "mean_velocity_m_s", scenario, record["dx"],
                               0.10 if case.endswith("010") else 0.15)
        if value is not None:
            gpusph = value if gpusph is None else min(gpusph, value, key=lambda v: abs(v - experiment))
    profile_error = None
    if case.endswith("015"):
        exp = R.experiment_profile(data)
        n = min(len(exp[1]), len(normalised))
        profile_error = float(np.sqrt(np.mean((np.asarray(normalised[:n]) - exp[1][:n]) ** 2)))
    return {"arrival_s": arrival, "mean_velocity": mean, "covered_s": covered, "experiment": experiment,
            "error_pct": 100.0 * (mean / experiment - 1.0) if experiment else None, "gpusph_best": gpusph,
            "gpusph_error_pct": 100.0 * (gpusph / experiment - 1.0) if gpusph and experiment else None,
            "profile": normalised, "profile_rms": profile_error}


def report(folders, data) -> str:
    records = [json.loads(p.read_text()) for folder in folders for p in sorted(Path(folder).glob("dambreak2_*.json"))]
    order = {"full": 0, "slab": 1, "2d": 2}
    records.sort(key=lambda r: (r["scene"], r["dx"], r["device"], order.get(r["model"], 9)))
    lines = ["| case | model | dx [m] | particles | fluid | device | steps | wall [s] | MIPPS | arrival [s] | "
             "mean bore velocity [m/s] | error vs experiment | GPUSPH (thesis, same dx) | profile RMS (u/U) | ended |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in records:
        done = r["status"] == "completed"
        m = metrics(r, data) if done or len(r["series"]["t"]) > 20 else None

        def f(value, spec):
            return "-" if value is None else format(value, spec)

        lines.append(
            f"| {r['scene']} | {r['model']} | {r['dx']:g} | {r['particles']:,} | {r['fluid_particles']:,} | "
            f"{r['device']} | {r['steps']:,} | {r['wall_s']:.0f} | {r['mipps']:.2f} | "
            f"{f(m and m['arrival_s'], '.2f')} | {f(m and m['mean_velocity'], '.3f')} | "
            f"{f(m and m['error_pct'], '+.1f')}% | {f(m and m['gpusph_error_pct'], '+.1f')}% | "
            f"{f(m and m['profile_rms'], '.3f')} | {'completed' if done else r['status'][:60]} |")
    return "\n".join(lines)


def main(argv=None):
    main_parser, p_run, _ = parser(__doc__, "runs/economy")
    p_run.add_argument("--scene", nargs="+", default=["dambreak2_010", "dambreak2_015"])
    p_run.add_argument("--dx", type=float, default=0.015)
    p_run.add_argument("--models", nargs="+", default=["full", "slab", "2d"])

    args = main_parser.parse_args(argv)
    wp.config.log_level = wp.LOG_WARNING
    if args.command == "run":
        for scene in args.scene:
            for model in args.models:
                run(scene, args.dx, model, args.device, Path(args.out), settings(args))
        return 0
    from gpusph_ros.analysis.reference import data_dir

    print(report(args.folders, data_dir()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
