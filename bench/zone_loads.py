"""DamBreak 1 (the laboratory column) with and without a refinement zone around the obstruction: the
peak net force on the obstruction (33.5 N measured by Yeh & Petroff), sampled at 100 Hz, raw and
after the 0.04 s moving average gpusph-analyze takes (analysis/metrics.py), and the wall time, one
row per case appended to a CSV as each ends, so a long sweep can be stopped and continued.

    python bench/zone_loads.py [--end 1.5] [--out runs/zone_loads.csv] [--case NAME ...] [--chart PNG]

Cases: ``uniform_1.5cm``, ``uniform_3cm`` and ``zoned_3cm_1.5cm``: a 0.5 zone, a box ``--margin`` m
around the obstruction (0.90-1.02 x 0.24-0.36 m) and up to 0.36 m (the column is 0.30 m deep), so
that the slots it reserves are not spent on the air above. A case already in the CSV is skipped.
``--chart`` draws the CSV's cases as the error of the peak (0.04 s average) against the measured
33.5 N over their wall time: the speed-against-accuracy chart, uniform and zoned side by side.
"""
import argparse
import csv
import time
from pathlib import Path

import numpy as np
import warp as wp
import yaml

MEASURED_PEAK = 33.5  # [N] Yeh & Petroff's net force on the obstruction (thesis Section 4.2)


def cases(margin: float):
    zone = [{"name": "near", "lo": [0.90 - margin, 0.24 - margin, 0.0], "hi": [1.02 + margin, 0.36 + margin, 0.36],
             "ratio": 0.5}]
    return {"uniform_1.5cm": (0.015, None), "uniform_3cm": (0.03, None), "zoned_3cm_1.5cm": (0.03, zone)}


def run_case(dx, refine, end, rate=100.0):
    from gpusph_ros.analysis.metrics import moving_average
    from gpusph_ros.measure.forces import BodyWrench
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import parse_scene
    from gpusph_ros.share import config_dir

    data = yaml.safe_load((config_dir("scenes") / "dambreak1_lab.yaml").read_text())
    if refine:
        data["refine"] = refine
    model = build(parse_scene(data), dx=dx)
    solver = model.solver()
    wrench = BodyWrench(solver, 0)
    start = time.perf_counter()
    times = np.arange(1.0, round(end * rate) + 1.0) / rate
    fx = []
    for t in times:
        solver.advance(float(t))
        fx.append(float(wrench.sample()[0][0]))
    wall = time.perf_counter() - start
    _, smooth = moving_average(times, fx)
    k, j = int(np.argmax(np.abs(fx))), int(np.argmax(np.abs(smooth)))
    return {"particles": solver.n, "steps": solver.steps, "wall_s": round(wall, 1),
            "peak_fx_N": round(fx[k], 2), "t_peak_s": times[k], "peak_fx_0.04s_N": round(float(smooth[j]), 2),
            "t_peak_0.04s_s": times[j], "error_0.04s": f"{100 * (abs(smooth[j]) / MEASURED_PEAK - 1):+.1f}%"}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--end", type=float, default=1.5)
    ap.add_argument("--margin", type=float, default=0.1)
    ap.add_argument("--out", default="runs/zone_loads.csv")
    ap.add_argument("--case", nargs="+", default=None)
    ap.add_argument("--chart", help="draw the CSV's cases, error against wall time, into this PNG")
    args = ap.parse_args(argv)
    wp.config.log_level = wp.LOG_WARNING
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    done = {row["case"] for row in csv.DictReader(out.open())} if out.exists() else set()
    for name, (dx, refine) in cases(args.margin).items():
        if (args.case and name not in args.case) or name in done:
            continue
        row = {"case": name, "end_s": args.end, "margin_m": args.margin if refine else "",
               **run_case(dx, refine, args.end)}
        new = not out.exists()
        with out.open("a", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(row))
            if new:
                writer.writeheader()
            writer.writerow(row)
        print(row, flush=True)
    if args.chart:
        chart(out, Path(args.chart))


def chart(csv_path: Path, png: Path):
    """|error| of the 0.04 s peak against 33.5 N over the wall time, one point a case."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = list(csv.DictReader(csv_path.open()))
    fig, ax = plt.subplots(figsize=(6, 4))
    for row in rows:
        wall, error = float(row["wall_s"]), abs(float(row["peak_fx_0.04s_N"]) / MEASURED_PEAK - 1) * 100
        zoned = row["case"].startswith("zoned")
        ax.plot(wall, error, "o" if zoned else "s", color="C1" if zoned else "C0", markersize=8)
        ax.annotate(f"{row['case']} ({int(row['particles']):,} slots)", (wall, error), textcoords="offset points",
                    xytext=(6, 4), fontsize=8)
    ax.set_xlim(0.0, 1.5 * max(float(row["wall_s"]) for row in rows))  # room for the labels
    ax.set_ylim(0.0, None)
    ax.set_xlabel("wall time to 1.5 s [s], one CPU")
    ax.set_ylabel("|error| of the peak force on the obstruction [%]")
    ax.set_title("DamBreak 1, laboratory column: uniform and zoned", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=100)
    plt.close(fig)


if __name__ == "__main__":
    main()
