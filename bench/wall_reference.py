"""Wall pressure against a converged 2D reference: Lobovsky et al. (2014)'s dam break in 2D
(``lobovsky_2d``) against De Courcy et al. (2024)'s delta-SPH at H/400 on the same geometry
(data/decourcy_2024_dambreak_2d_converged), under each wall treatment and spacing.

Each run goes to t sqrt(g/H) = 6.5 in a tank 3H high (``--tank-height``; rows before it had
Lobovsky's 2H, over whose downstream wall a run-up without wall friction spills), with the four
sensors at H/100, H/20, H/10 and 0.267 H on the downstream wall, faces H/71.4 tall (8.4 mm at the
reference's H = 0.6 m, 4.2 mm here), sampled at 2 kHz. Per sensor, the pressure-time integral of
p / (rho g H) over t sqrt(g/H) in [2.3, 3.3] (the first impact), [3.3, 4.5] (after it) and
[4.5, 6.5] (the flow along the wall), against the
reference's over the same windows; the reading clipped at 0 as the reference clips it (its
README; ``--reading smoothed`` reads the sensors as the reference reads its own, measure/sensors.py);
and the onset, when P1 first passes 0.25 rho g H (analysis.metrics.first_impact), against the
reference's. One row per run is appended to the CSV as it ends; a run already there is skipped.

    python bench/wall_reference.py [--boundary dynamic mdbc adami] [--per-h 60 120] [--out CSV]
"""
import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

import csv_rows
from series import run_series

REPO = Path(__file__).resolve().parents[1]
END = 6.5  # [t sqrt(g/H)]
RATE = 2000.0  # [Hz] samples


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--boundary", nargs="+", default=["dynamic", "mdbc", "adami"])
    parser.add_argument("--per-h", type=int, nargs="+", default=[60], help="H / dx of each run")
    parser.add_argument("--out", type=Path, default=REPO / "docs/results/wall_reference.csv")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="more run settings")
    parser.add_argument("--tank-height", type=float, default=3.0, help="the walls' height in H (Lobovsky's: 2)")
    parser.add_argument("--reading", choices=["wall", "smoothed"], default="wall",
                        help="how the sensors read (smoothed: as the reference reads its own)")
    args = parser.parse_args()
    sys.path.insert(0, str(REPO))
    from gpusph_ros.analysis import metrics as M
    from gpusph_ros.analysis.metrics import REFERENCE_WINDOWS as WINDOWS
    from gpusph_ros.analysis.metrics import window_impulse as impulse
    from gpusph_ros.analysis.reference import data_dir, decourcy_pressures
    from gpusph_ros.scenes.reference import decourcy_scene
    from gpusph_ros.scenes.settings import parse_set

    reference = decourcy_pressures(data_dir())
    sc, H = decourcy_scene(args.reading, args.tank_height)
    g = 9.81
    t_unit, p_unit = np.sqrt(g / H), 1000.0 * g * H
    extra = dict(map(parse_set, args.set))
    done = set()
    if args.out.exists():
        with open(args.out) as f:
            done = {(r["boundary"], int(r["per_h"]), r["settings"]) for r in csv.DictReader(f)}
    ref_onset = M.first_impact(*reference[1])[0]
    ref = {k: [impulse(*reference[k], lo, hi) for lo, hi in WINDOWS] for k in (1, 2, 3, 4)}
    print("reference (De Courcy et al. 2024, H/400) impulses per window:",
          "; ".join(f"P{k} " + " / ".join(f"{v:.3f}" for v in ref[k]) for k in ref), f"onset {ref_onset:.3f}")
    for per_h in args.per_h:
        for boundary in args.boundary:
            settings = " ".join(args.set + ([f"reading={args.reading}"] if args.reading != "wall" else [])
                                + ([f"tank={args.tank_height:g}H"] if args.tank_height != 2.0 else []))
            if (boundary, per_h, settings) in done:
                continue
            start = time.perf_counter()
            rec = run_series(sc, dx=H / per_h, boundary=boundary, end_time=(END + 0.02) / t_unit, output_rate=RATE,
                             particle_rate=0.0, **extra)
            wall = time.perf_counter() - start
            s = rec["series"]
            t = np.asarray(s["t"]) * t_unit
            row = {"boundary": boundary, "per_h": per_h, "settings": settings, "dx": H / per_h,
                   "particles": rec.get("particles"), "steps": rec.get("steps"), "wall_s": round(wall, 1),
                   "status": rec.get("status", "")[:120]}
            onset = float("nan")
            for k in (1, 2, 3, 4):
                p = np.asarray(s[f"sensors/sensor_{k}"]) / p_unit
                if k == 1 and len(t):
                    onset = M.first_impact(t, p)[0]
                for w, (lo, hi) in enumerate(WINDOWS):
                    for name, series in (("", p), ("clipped_", np.maximum(p, 0.0))):
                        value = impulse(t, series, lo, hi)
                        row[f"{name}P{k}_w{w + 1}"] = round(value, 4)
                        row[f"{name}P{k}_w{w + 1}_err_pct"] = round(100.0 * (value / ref[k][w] - 1.0), 1)
                row[f"P{k}_peak"] = round(float(p.max()), 3) if len(p) else float("nan")
            row["onset"] = round(onset, 3)
            row["onset_shift"] = round(onset - ref_onset, 3)
            csv_rows.append(args.out, row)
            cells = [" / ".join(f"{row.get(f'clipped_P{k}_w{w}_err_pct', float('nan')):+.0f}" for w in (1, 2, 3))
                     for k in (1, 2, 3, 4)]
            print(f"{boundary:8s} H/{per_h}: {wall:6.0f} s, {row['status'][:40]}; clipped windows P1-P4: "
                  f"{' | '.join(cells)}; onset {row['onset_shift']:+.3f}", flush=True)


if __name__ == "__main__":
    main()
