"""A 2D piston (or flap) wavemaker against linear wavemaker theory (Biesel; theory/wavemaker.py): the
wave height the paddle makes, read by gauges 2, 3 and 4 depths down the flume (past the evanescent
modes), against H of the scene's motion, at the paddle's period.

A flume ``--length`` long with ``--depth`` of water; the paddle's amplitude ramps in over two
periods. Each gauge's elevation is fitted, over the window after the ramp and the wave's arrival
(group velocity) and before the far wall's reflection can return (at sqrt(g h): analysis.waves),
with a sinusoid at the paddle's period (least squares: mean, sine and cosine): H = 2 x its
amplitude; the period is the fitted sinusoid's by a scan of periods around the paddle's. One row per
run is appended to ``--out`` as it ends; a run already there is skipped.

    python bench/wavemaker.py --period 1.0 2.0 [--kind piston|flap] [--dx 0.02] [--set alpha=0.01]
"""
import argparse
import csv
from pathlib import Path

import numpy as np

import csv_rows
from series import run_series

REPO = Path(__file__).resolve().parents[1]
FIELDS = ["kind", "period", "depth", "wave_height", "kh", "dx", "settings", "particles", "wall_s", "window",
          "H_g1", "H_g2", "H_g3", "err_g1_pct", "err_g2_pct", "err_g3_pct", "period_fit", "excluded"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--period", type=float, nargs="+", default=[1.0, 2.0])
    ap.add_argument("--kind", choices=["piston", "flap"], default="piston")
    ap.add_argument("--depth", type=float, default=0.4)
    ap.add_argument("--height", type=float, default=0.03, help="[m] the wave height asked of the paddle")
    ap.add_argument("--length", type=float, default=10.0)
    ap.add_argument("--dx", type=float, default=0.02)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--out", type=Path, default=REPO / "docs/results/wavemaker.csv")
    args = ap.parse_args()
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.analysis import waves
    from gpusph_ros.scenes.flume import PADDLE, wave_flume
    from gpusph_ros.scenes.settings import parse_set
    from gpusph_ros.theory import wavemaker

    done = set()
    if args.out.exists():
        with open(args.out) as f:
            done = {(r["kind"], float(r["period"]), float(r["dx"]), r["settings"]) for r in csv.DictReader(f)}
    settings = " ".join(args.set)
    h, g = args.depth, 9.81
    gauges = [2 * h, 3 * h, 4 * h]  # from the paddle's face
    for period in args.period:
        if (args.kind, period, args.dx, settings) in done:
            print(f"{args.kind} T = {period} s: already in {args.out}")
            continue
        kh = wavemaker.wavenumber(period, h, g) * h
        start, end = waves.steady_window(period, h, gauges[-1], args.length - PADDLE[1], 2 * period, g)
        if start >= end - period:
            raise SystemExit(f"T = {period} s: no whole period between the ramp's arrival at the last gauge "
                             f"({start:.2f} s) and the reflection's ({end:.2f} s); a longer --length")
        scene = wave_flume(args.length, h, period, args.height, gauges, kind=args.kind)
        print(f"{args.kind} T = {period} s, kh = {kh:.3f}, H = {args.height} m; window {start:.2f}-{end:.2f} s",
              flush=True)
        record = run_series(scene, dx=args.dx, end_time=end, output_rate=50, **dict(map(parse_set, args.set)))
        if record["status"] != "completed":
            raise SystemExit(record["status"])
        times = np.array(record["series"]["t"])
        levels = np.column_stack([record["series"][f"gauges/g{n + 1}"] for n in range(3)])
        window = (times >= start) & (times <= end)
        heights = [2 * waves.sinusoid(times[window], levels[window, n], period)[0] for n in range(3)]
        period_fit = waves.period_of(times[window], levels[window, 0], period)
        row = {"kind": args.kind, "period": period, "depth": h, "wave_height": args.height, "kh": round(kh, 4),
               "dx": args.dx, "settings": settings, "particles": record["particles"],
               "wall_s": round(record["wall_s"], 1),
               "window": f"{start:.2f}-{end:.2f}", **{f"H_g{n + 1}": round(v, 5) for n, v in enumerate(heights)},
               **{f"err_g{n + 1}_pct": round(100 * (v / args.height - 1), 1) for n, v in enumerate(heights)},
               "period_fit": round(period_fit, 4), "excluded": record["excluded"]}
        print(row, flush=True)
        csv_rows.append(args.out, row, FIELDS)


if __name__ == "__main__":
    main()
