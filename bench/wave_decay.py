"""How a paddle's wave loses height along a 2D flume: gauges every 0.1 m from 0.2 m to 2.4 m off a
piston paddle (``bench/wavemaker.py``'s flume, ``--length`` long, ``--depth`` of water), each fitted
with a sinusoid at the paddle's period over one window: after the ramp and the front have passed the
last gauge and before the far wall's reflection can come back to it (analysis.waves.steady_window).
Prints each gauge's height against the paddle's H, and the decay rate mu of the height beyond 0.5 m
(H(x) ~ e^(-mu x), a least-squares line through log H); one row per run is appended to ``--out``
(done runs skipped).

    python bench/wave_decay.py [--period 1.0] [--dx 0.02] [--walls particles|planes] [--set alpha=0.01 ...]
"""
import argparse
import csv
from pathlib import Path

import numpy as np

import csv_rows
from series import run_series

REPO = Path(__file__).resolve().parents[1]
FIELDS = ["period", "depth", "wave_height", "kh", "dx", "length", "walls", "settings", "particles", "wall_s", "window",
          "decay_per_m", "err_0.5_1.5m_pct", "heights"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--period", type=float, default=1.0)
    ap.add_argument("--depth", type=float, default=0.4)
    ap.add_argument("--height", type=float, default=0.03, help="[m] the wave height asked of the paddle")
    ap.add_argument("--length", type=float, default=9.0)
    ap.add_argument("--dx", type=float, default=0.02)
    ap.add_argument("--walls", choices=["particles", "planes"], default="particles")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--out", type=Path, default=REPO / "docs/results/wave_decay.csv")
    args = ap.parse_args()
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.analysis import waves
    from gpusph_ros.scenes.flume import PADDLE, wave_flume
    from gpusph_ros.scenes.settings import parse_set
    from gpusph_ros.theory import wavemaker

    settings = " ".join(args.set)
    key = (args.period, args.height, args.dx, args.length, args.walls, settings)
    if args.out.exists():
        with open(args.out) as f:
            if key in {(float(r["period"]), float(r["wave_height"]), float(r["dx"]), float(r["length"]), r["walls"],
                        r["settings"]) for r in csv.DictReader(f)}:
                raise SystemExit(f"{key} is in {args.out}")
    h = args.depth
    kh = wavemaker.wavenumber(args.period, h, 9.81) * h
    xs = np.round(np.arange(0.2, 2.41, 0.1), 3)  # from the paddle's face
    start, end = waves.steady_window(args.period, h, xs[-1], args.length - PADDLE[1], 2 * args.period)
    if start >= end - 2 * args.period:
        raise SystemExit(f"no two periods between {start:.2f} s and {end:.2f} s: a longer --length")
    scene = wave_flume(args.length, h, args.period, args.height, xs, walls=args.walls, first=0)
    print(f"T = {args.period} s, kh = {kh:.3f}, H = {args.height} m; window {start:.2f}-{end:.2f} s", flush=True)
    record = run_series(scene, dx=args.dx, end_time=end, output_rate=50, **dict(map(parse_set, args.set)))
    if record["status"] != "completed":
        raise SystemExit(record["status"])
    t = np.array(record["series"]["t"])
    eta = np.column_stack([record["series"][f"gauges/g{n}"] for n in range(len(xs))])
    window = (t >= start) & (t <= end)
    heights = np.array([2 * waves.sinusoid(t[window], eta[window, j], args.period)[0] for j in range(len(xs))])
    far = xs >= 0.5
    decay = -np.polyfit(xs[far], np.log(heights[far]), 1)[0]
    errors = 100 * (heights / args.height - 1)
    print("x from the paddle [m] and height against H:\n" +
          "\n".join(f"  {x:.1f}  {e:+.1f}%" for x, e in zip(xs, errors)))
    print(f"decay rate {decay:.3f} /m beyond 0.5 m; {record['wall_s']:.0f} s", flush=True)
    row = {"period": args.period, "depth": h, "wave_height": args.height, "kh": round(kh, 4), "dx": args.dx,
           "length": args.length, "walls": args.walls, "settings": settings, "particles": record["particles"],
           "wall_s": round(record["wall_s"], 1),
           "window": f"{start:.2f}-{end:.2f}", "decay_per_m": round(float(decay), 4),
           "err_0.5_1.5m_pct": round(float(errors[(xs >= 0.5) & (xs <= 1.5)].mean()), 1),
           "heights": " ".join(f"{e:+.1f}" for e in errors)}
    csv_rows.append(args.out, row, FIELDS)


if __name__ == "__main__":
    main()
