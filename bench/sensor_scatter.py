"""How much a pressure sensor's published series scatters from one output to the next, read as a
transducer (the mean over the steps since the last output, clipped at 0: the default) and as one
step's raw reading (``sampling: step``, ``clip: false``), on the 3D ``dambreak1_lab`` obstruction's
upstream face (issue 56).

Four sensors on the face's centre line (x = 0.90 m, y = 0.30 m) at 2, 6, 10 and 14 cm above the
floor, faces ``--diameter`` across, each read both ways, at the scene's output rate (100 Hz), to
``--end``. Over the quasi-static phase ``--window`` (the surge's drag on the obstruction after its
impact), per sensor and reading: the mean, the step-to-step scatter (RMS of the change from one
output to the next over the mean), the lowest value. One row per sensor and reading in ``--out``.

    python bench/sensor_scatter.py [--dx 0.02] [--end 1.1] [--window 0.6 1.1] [--set KEY=VALUE ...] [--out CSV]
"""
import argparse
import csv
from pathlib import Path

import numpy as np
import yaml

from series import run_series

REPO = Path(__file__).resolve().parents[1]
HEIGHTS = (0.02, 0.06, 0.10, 0.14)  # [m] above the floor
READINGS = {"transducer": {}, "raw": {"sampling": "step", "clip": False}}


def scene(diameter: float):
    from gpusph_ros.scenes.schema import parse_scene

    data = yaml.safe_load((REPO / "config" / "scenes" / "dambreak1_lab.yaml").read_text())
    for z in HEIGHTS:
        for reading, extra in READINGS.items():
            data["probes"][f"face_{round(z * 100):02d}cm_{reading}"] = {
                "type": "pressure_sensor", "position": [0.90, 0.30, z], "normal": [-1, 0, 0], "diameter": diameter,
                **extra}
    return parse_scene(data)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=0.02)
    ap.add_argument("--end", type=float, default=1.1)
    ap.add_argument("--window", type=float, nargs=2, default=(0.6, 1.1))
    ap.add_argument("--diameter", type=float, default=0.03)
    ap.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE", help="more run settings")
    ap.add_argument("--out", default=str(REPO / "docs" / "results" / "sensor_scatter.csv"))
    args = ap.parse_args()
    from gpusph_ros.scenes.settings import parse_set

    sets = dict(map(parse_set, args.set))
    record = run_series(scene(args.diameter), dx=args.dx, end_time=args.end, **sets)
    t = np.asarray(record["series"]["t"])
    inside = (t >= args.window[0]) & (t <= args.window[1])
    rows = []
    for z in HEIGHTS:
        for reading in READINGS:
            name = f"face_{round(z * 100):02d}cm_{reading}"
            p = np.asarray(record["series"][f"sensors/{name}"])[inside]
            mean = float(np.mean(p))
            scatter = float(np.sqrt(np.mean(np.diff(p) ** 2)) / mean) if mean > 0.0 else float("nan")
            rows.append({"dx": args.dx, "settings": " ".join(args.set), "height_m": z, "reading": reading,
                         "window_s": f"{args.window[0]}-{args.window[1]}", "mean_pa": round(mean, 1),
                         "scatter_of_mean": round(scatter, 3), "min_pa": round(float(p.min()), 1),
                         "particles": record["particles"], "steps": record["steps"],
                         "wall_s": round(record["wall_s"], 1), "status": record["status"]})
            print(f"{z:.2f} m {reading:10s} mean {mean:8.1f} Pa  scatter {100 * scatter:6.1f}%  min {p.min():8.1f} Pa")
    out = Path(args.out)
    new = not out.exists()
    with out.open("a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        if new:
            writer.writeheader()
        writer.writerows(rows)


if __name__ == "__main__":
    main()
