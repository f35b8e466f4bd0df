"""Uniform and zoned runs of one case side by side: each run's error against the measurement and the
wall time it cost, one row per run appended to a CSV as it ends (a sweep stopped is continued: a
run already in the CSV is skipped), and the speed-against-accuracy chart of the CSV's runs.

    python bench/zone_study.py STUDY [--out CSV] [--case NAME ...] [--chart PNG]

Studies (``STUDIES``), every run with only the solver (bench/series.py), both cores:

- ``dambreak1``: the laboratory column (``dambreak1_lab``) to 1.5 s; the peak net force on the
  obstruction after the 0.04 s moving average gpusph-analyze takes, against Yeh & Petroff's 33.5 N.
  The zone: a 0.5 box 0.1 m around the obstruction, up to 0.36 m (the column is 0.30 m deep) so that
  the slots it reserves are not spent on the air.
- ``lobovsky``: Lobovsky et al. (2014) in 2D (``lobovsky_2d``) through the first impact, to 0.7 s;
  the first-impact pressure-time integrals at the sensors 3, 15, 30 and 80 mm up the wall
  (metrics.first_impact) against the measured ones; the chart's error is the mean |error| of the
  three lower ones (``lobovsky_error``). The zone: the last 0.3 m of the tank, up to 0.3 m (the 0.5 zone of
  docs/variable_resolution.md). The density bound is 1.3 rho0 (``rho_max_ratio``, 1.25 by default):
  the wall particle in the corner the surge hits reaches 1.22 rho0 in the uniform 5 mm run, as
  rho0 (1 + u / c0) says for 3 m/s against c0 = 17 m/s, and passes 1.25 in the zoned one; a wall
  particle cannot be excluded, so the default bound fails the run there.
- ``dambreak2``: the 0.10 m bore of Arnason et al. (2009) in the flume's x-z section (``model: 2d``
  of ``dambreak2_010``, as docs/results/dambreak2.md's best runs; zones across the flume's width
  become the section's), with Wendland and laminar + SPS, to 13 s; every wall a wall of particles,
  since zones take no planes; the mean depth-averaged velocity at x = 11.1 m over
  the 6 s behind the bore against the measured 0.553 m/s. Zones: ``probe``, 3 m around the probe; ``bed``,
  the whole wet bed from 0.5 m upstream of the gate (the 0.02 m bed is half a 4 cm spacing deep).
"""
import argparse
import csv
import functools
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import warp as wp
import yaml

import csv_rows
from series import run_series

LOBOVSKY_HEIGHTS_MM = (3, 15, 30, 80)


def dambreak1_force(series: dict) -> dict:
    from gpusph_ros.analysis.metrics import moving_average

    t, fx = np.asarray(series["t"]), np.asarray(series["wrenches/obstruction/fx"])
    _, smooth = moving_average(t, fx)
    k, j = int(np.argmax(np.abs(fx))), int(np.argmax(np.abs(smooth)))
    return {"peak_fx_N": round(float(fx[k]), 2), "t_peak_s": round(float(t[k]), 3),
            "peak_fx_0.04s_N": round(float(smooth[j]), 2), "t_peak_0.04s_s": round(float(t[j]), 3)}


@functools.lru_cache(maxsize=None)
def lobovsky_measured() -> dict:
    """Lobovsky et al.'s measured first-impact integrals by sensor height [mm]."""
    from gpusph_ros.analysis import metrics as M
    from gpusph_ros.analysis import reference as R

    measured = R.lobovsky_pressures(R.data_dir())
    return {mm: M.first_impact(*measured[k])[1] for k, mm in enumerate(LOBOVSKY_HEIGHTS_MM, start=1)}


def lobovsky_impulses(series: dict) -> dict:
    """The first-impact integrals in rho g H sqrt(H/g), H = 0.3 m; NaN where a sensor's impact did
    not start and end within the run."""
    from gpusph_ros.analysis import metrics as M

    g, depth, rho0 = 9.81, 0.3, 1000.0
    t = np.asarray(series["t"]) * np.sqrt(g / depth)
    out = {}
    for k, mm in enumerate(LOBOVSKY_HEIGHTS_MM, start=1):
        p = np.asarray(series[f"sensors/sensor_{k}"]) / (rho0 * g * depth)
        out[f"impulse_{mm}mm"] = round(M.first_impact(t, p)[1], 3)
    return out


def lobovsky_error(row: dict):
    """Mean |error| [%] of the integrals at 3, 15 and 30 mm, the sensors the surge's first impact
    reaches: at 80 mm the pressure passes the impact's threshold only after the run's end in most
    runs (docs/results/lobovsky.md)."""
    measured = lobovsky_measured()
    values = [_number(row.get(f"impulse_{mm}mm")) for mm in LOBOVSKY_HEIGHTS_MM[:3]]
    if None in values:
        return None
    return float(np.mean([abs(v / measured[mm] - 1.0) * 100.0 for v, mm in zip(values, LOBOVSKY_HEIGHTS_MM)]))


def dambreak2_bore(series: dict) -> dict:
    from gpusph_ros.analysis import metrics as M

    t, u = np.asarray(series["t"]), np.asarray(series["columns/bore/u"])
    if len(t) < 2:
        return {"arrival_s": "", "mean_velocity_m_s": ""}
    arrival = M.bore_arrival(t, u)
    mean, covered = M.mean_behind(t, u, arrival)
    return {"arrival_s": round(arrival, 2), "mean_velocity_m_s": round(mean, 4), "covered_s": round(covered, 1)}


def _number(value):
    """A CSV cell as a finite float, or None."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        return None
    return value if np.isfinite(value) else None


def _relative(column: str, measured: float):
    """The error of a row's ``column`` against ``measured`` [%]."""
    def error(row: dict):
        value = _number(row.get(column))
        return None if value is None else abs(value / measured - 1.0) * 100.0
    return error


@dataclass
class Study:
    scene: str  # a built-in scene's name
    end: float  # [s] simulated
    measure: object  # series -> {column: value}
    error: object  # a CSV row -> its |error| against the measurement [%], None where it measured nothing
    label: str  # the chart's y axis
    cases: dict = field(default_factory=dict)  # name -> (dx, refine or None)
    settings: dict = field(default_factory=dict)  # run settings every case takes
    changes: dict = field(default_factory=dict)  # scene keys every case replaces


def _zone(name, lo, hi, ratio=0.5):
    return [{"name": name, "lo": lo, "hi": hi, "ratio": ratio}]


STUDIES = {
    "dambreak1": Study("dambreak1_lab", 1.5, dambreak1_force, _relative("peak_fx_0.04s_N", 33.5),
                       "|error| of the peak force on the obstruction [%]",
                       {"uniform_1.5cm": (0.015, None), "uniform_3cm": (0.03, None),
                        "zoned_3cm_1.5cm": (0.03, _zone("near", [0.80, 0.14, 0.0], [1.12, 0.46, 0.36]))}),
    "lobovsky": Study("lobovsky_2d", 0.7, lobovsky_impulses, lobovsky_error,
                      "mean |error| of the first-impact integrals, 3-30 mm [%]",
                      {"uniform_10mm": (0.01, None), "uniform_5mm": (0.005, None),
                       "uniform_2.5mm": (0.0025, None),
                       "zoned_10mm_5mm": (0.01, _zone("wall", [1.31, 0.0], [1.61, 0.3])),
                       "zoned_5mm_2.5mm": (0.005, _zone("wall", [1.31, 0.0], [1.61, 0.3]))},
                      {"rho_max_ratio": 1.3}),
    "dambreak2": Study("dambreak2_010", 13.0, dambreak2_bore, _relative("mean_velocity_m_s", 0.553),
                       "|error| of the mean bore velocity at x = 11.1 m [%]",
                       {"uniform_2cm": (0.02, None), "uniform_4cm": (0.04, None),
                        "zoned_4cm_2cm_probe": (0.04, _zone("probe", [9.6, 0.0, 0.0], [12.6, 1.6, 0.2])),
                        "zoned_4cm_2cm_bed": (0.04, _zone("bed", [5.4, 0.0, 0.0], [16.6, 1.6, 0.2]))},
                       {"model": "2d", "kernel": "wendland", "viscosity": "sps"}, {"walls": "particles"}),
}


def scene_of(study: Study, refine):
    from gpusph_ros.scenes.schema import load_scene, parse_scene

    data = {**yaml.safe_load(load_scene(study.scene).text), **study.changes}
    if refine:
        data["refine"] = refine
    return parse_scene(data)


def run_case(study: Study, dx: float, refine) -> dict:
    record = run_series(scene_of(study, refine), dx=dx, end_time=study.end, **study.settings)
    return {"particles": record["particles"], "steps": record["steps"], "wall_s": round(record["wall_s"], 1),
            "status": record["status"], **study.measure(record["series"])}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study", choices=sorted(STUDIES))
    ap.add_argument("--out", default=None, help="the CSV (default runs/zone_STUDY.csv)")
    ap.add_argument("--case", nargs="+", default=None, help="run only these (none: only --chart)")
    ap.add_argument("--chart", help="draw the CSV's runs, error against wall time, into this PNG")
    args = ap.parse_args(argv)
    wp.config.log_level = wp.LOG_WARNING
    study = STUDIES[args.study]
    out = Path(args.out or f"runs/zone_{args.study}.csv")
    out.parent.mkdir(parents=True, exist_ok=True)
    done = {row["case"] for row in csv.DictReader(out.open())} if out.exists() else set()
    for name, (dx, refine) in study.cases.items():
        if (args.case and name not in args.case) or name in done:
            continue
        row = {"case": name, "dx_m": dx, "end_s": study.end, **run_case(study, dx, refine)}
        csv_rows.append(out, row)
        print(row, flush=True)
    if args.chart:
        chart(study, args.study, out, Path(args.chart))


def chart(study: Study, name: str, csv_path: Path, png: Path):
    """|error| over the wall time, one point a run: uniform squares, zoned circles."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    points = [(row, error) for row in csv.DictReader(csv_path.open()) if (error := study.error(row)) is not None]
    fig, ax = plt.subplots(figsize=(6, 4))
    for row, error in points:
        wall = float(row["wall_s"])
        zoned = row["case"].startswith("zoned")
        ax.plot(wall, error, "o" if zoned else "s", color="C1" if zoned else "C0", markersize=8)
        ax.annotate(f"{row['case']} ({int(row['particles']):,} slots)", (wall, error), textcoords="offset points",
                    xytext=(6, 4), fontsize=8)
    ax.set_xlim(0.0, 1.5 * max(float(row["wall_s"]) for row, _ in points))  # room for the labels
    ax.set_ylim(0.0, None)
    ax.set_xlabel(f"wall time to {study.end:g} s [s], 2-core CPU")
    ax.set_ylabel(study.label, fontsize=9)
    ax.set_title(f"{name}: uniform (squares) and zoned (circles)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=100)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
