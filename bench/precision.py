"""float32 against float64: the same scene, the same numerics, run in both precisions on the same
device; where their probe and force series part (the thesis blamed its fine-spacing "hook",
Sections 4.2 and 5.1, on single precision without testing it).

    python bench/precision.py run --scene dambreak1_thesis --dx 0.01 [--device cuda:0] [--end-time 1.5] --out DIR
    python bench/precision.py report DIR [DIR ...]

For each series: the peak (largest |value|) in each precision and their difference, the RMS of
the difference over the peak, and the first time the two differ by more than 10% of the peak.
"""
import json
import sys
from pathlib import Path

import numpy as np

from series import parser, run_series, settings

PRECISIONS = ("float32", "float64")


def compare(a: dict, b: dict) -> list:
    """Rows comparing the float32 record ``a`` with the float64 record ``b``."""
    t = np.asarray(b["series"]["t"])
    n = min(len(a["series"]["t"]), len(t))
    rows = []
    for name in sorted(set(a["series"]) & set(b["series"]) - {"t"}):
        x, y = np.asarray(a["series"][name][:n]), np.asarray(b["series"][name][:n])
        peak = float(np.max(np.abs(y))) if n else 0.0
        if peak == 0.0:
            continue
        diff = np.abs(x - y)
        apart = np.nonzero(diff > 0.1 * peak)[0]
        rows.append({"series": name, "peak_f32": float(x[np.argmax(np.abs(x))]),
                     "peak_f64": float(y[np.argmax(np.abs(y))]),
                     "rms_rel": float(np.sqrt(np.mean(diff ** 2)) / peak),
                     "apart_at": float(t[apart[0]]) if len(apart) else None})
    return rows


def report(folder) -> str:
    records = [json.loads(p.read_text()) for p in sorted(Path(folder).glob("*.json"))]
    by_case = {}
    for r in records:
        by_case.setdefault((r["scene"], r["dx"], r["device"]), {})[r["precision"]] = r
    lines = []
    for (scene, dx, device), pair in sorted(by_case.items()):
        if set(pair) != set(PRECISIONS):
            continue
        a, b = pair["float32"], pair["float64"]
        lines += [f"\n{scene} at dx = {dx:g} m on {device}: {a['particles']:,} particles; "
                  f"float32 {a['steps']:,} steps in "
                  f"{a['wall_s']:.1f} s ({a['status']}), float64 {b['steps']:,} steps in {b['wall_s']:.1f} s "
                  f"({b['status']})",
                  "| series | peak float32 | peak float64 | peak difference | RMS difference / peak "
                  "| apart by 10% of peak from |",
                  "|---|---|---|---|---|---|"]
        for row in compare(a, b):
            apart = "never" if row["apart_at"] is None else f"t = {row['apart_at']:.2f} s"
            lines.append(f"| {row['series']} | {row['peak_f32']:.4g} | {row['peak_f64']:.4g} | "
                         f"{100 * (row['peak_f32'] / row['peak_f64'] - 1):+.1f}% | {row['rms_rel']:.3f} | {apart} |")
    return "\n".join(lines)


def main(argv=None):
    main_parser, p_run, _ = parser(__doc__, "runs/precision")
    p_run.add_argument("--scene", default="dambreak1_thesis")
    p_run.add_argument("--dx", type=float, nargs="+", default=[0.04])
    args = main_parser.parse_args(argv)
    if args.command == "report":
        print("\n".join(report(folder) for folder in args.folders))
        return 0
    extra = settings(args)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for dx in args.dx:
        for precision in PRECISIONS:
            r = run_series(args.scene, dx=dx, precision=precision, device=args.device, **extra)
            (out / f"{args.scene}_{dx:g}_{precision}.json").write_text(json.dumps(r))
            print(f"{args.scene} dx={dx:g} {precision}: {r['particles']:,} particles, {r['steps']:,} steps in "
                  f"{r['wall_s']:.1f} s, {r['mipps']:.2f} MIPPS on {r['device']}; {r['status']}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
