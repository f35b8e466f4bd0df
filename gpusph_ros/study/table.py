"""A study's results table (CSV and Parquet, and as Markdown for docs/), each metric's error
measure, and the headline: the cheapest setting within a tolerance of the experiment."""
import csv
import re
from pathlib import Path


def columns(rows) -> list:
    """Every key of every row, in first-seen order."""
    out = []
    for row in rows:
        out += [k for k in row if k not in out]
    return out


def write(rows, out_dir) -> list:
    """results.csv and results.parquet in ``out_dir``; their paths."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    cols = columns(rows)
    with open(out_dir / "results.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, cols)
        writer.writeheader()
        writer.writerows(rows)
    # one type per column: text where any row has text, else numbers (None = missing)
    data = {}
    for c in cols:
        values = [row.get(c) for row in rows]
        if any(isinstance(v, str) for v in values):
            values = [None if v is None else str(v) for v in values]
        elif any(isinstance(v, float) for v in values):
            values = [None if v is None else float(v) for v in values]
        data[c] = values
    pq.write_table(pa.table(data), out_dir / "results.parquet")
    return [out_dir / "results.csv", out_dir / "results.parquet"]


def read(path) -> list:
    """Rows of a results.csv, numbers as floats, empty cells as None."""
    def value(text):
        if text == "":
            return None
        try:
            return float(text)
        except ValueError:
            return {"True": True, "False": False}.get(text, text)

    with open(path, newline="") as f:
        return [{k: value(v) for k, v in row.items()} for row in csv.DictReader(f)]


def error_of(row, metric):
    """(error, label) of ``metric`` in ``row``: |percent error| against the experiment where the
    experiment has a value, the metric itself for an RMS error; (None, None) otherwise or when the
    case did not complete."""
    if row.get("status") != "completed":
        return None, None
    pct = row.get(f"{metric}_error_pct")
    if pct is not None:
        return abs(pct), "|error| against the experiment [%]"
    if metric.endswith("_rms") and row.get(metric) is not None:
        return row[metric], "RMS error against the experiment"
    return None, None


def pareto(points):
    """The (cost, error, item) points no other point beats on both; sorted by cost."""
    front, best = [], float("inf")
    for cost, error, item in sorted(points, key=lambda p: (p[0], p[1])):
        if error < best:
            front.append((cost, error, item))
            best = error
    return front


def cheapest_within(rows, metric, tolerance_pct=10.0, cost="wall_time_s"):
    """The completed row of least ``cost`` whose |error| against the experiment is within
    ``tolerance_pct``, or None."""
    ok = [r for r in rows if r.get("status") == "completed" and r.get(f"{metric}_error_pct") is not None
          and abs(r[f"{metric}_error_pct"]) <= tolerance_pct and r.get(cost) is not None]
    return min(ok, key=lambda r: r[cost]) if ok else None


def short_status(status: str) -> str:
    """``failed: density_bounds at t = 0.35 s`` for a health-check failure; the status otherwise."""
    found = re.search(r"health check '(\w+)' failed at step \d+ \(t = ([\d.e+-]+) s\)", status or "")
    return f"failed: {found[1]} at t = {float(found[2]):.3g} s" if found else (status or "?")


def thesis_tables(rows, metrics) -> str:
    """Per metric and scene, the thesis's comparison: a line per scenario and dx with ours beside
    GPUSPH's at the same dx and scenario (percent error against the experiment in brackets), our
    wall time, and how a run that did not complete ended."""
    from ..analysis.report import LABELS, fmt

    out = []
    for metric in metrics:
        label, unit = LABELS.get(metric, (metric, ""))
        for scene in dict.fromkeys(r["scene"] for r in rows):
            mine = [r for r in rows if r["scene"] == scene]
            exp = next((r.get(f"{metric}_experiment") for r in mine if r.get(f"{metric}_experiment") is not None),
                       None)
            out.append(f"\n{label} [{unit}], {scene}" + (f"; experiment {exp:.3g}" if exp is not None else ""))
            lines = [("scenario", "dx [mm]", "ours", "GPUSPH (thesis)", "wall [s]", "status")]
            for r in sorted(mine, key=lambda r: (list(dict.fromkeys(x["scenario"] for x in mine)).index(r["scenario"]),
                                                 r.get("dx") or 0.0)):
                done = r.get("status") == "completed"
                lines.append((r["scenario"], f"{(r.get('dx') or 0.0) * 1000:g}",
                              fmt(r.get(metric), r.get(f"{metric}_error_pct")) if done else "-",
                              fmt(r.get(f"{metric}_gpusph"), r.get(f"{metric}_gpusph_error_pct")),
                              fmt(r.get("wall_time_s")), short_status(r.get("status"))))
            widths = [max(len(line[k]) for line in lines) for k in range(6)]
            out += ["  ".join(c.ljust(w) for c, w in zip(line, widths)).rstrip() for line in lines]
    return "\n".join(out).lstrip("\n")


def markdown(rows, metrics) -> str:
    """One line per case: its scenario and dx, how it ended, steps and wall time, each metric (its
    percent error against the experiment beside it), the particles it excluded and the health
    peaks it reached (sph.Solver.health_peaks), so that one scenario reads against another."""
    from ..analysis.report import fmt

    def pct(value):
        return "-" if value is None else f"{100 * value:.1f}%"

    head = ["scenario", "dx [mm]", "status", "steps", "wall [s]", *metrics, "excluded",
            "peak clumped", "density / rho0", "energy rise / M g H"]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for r in rows:
        done = r.get("status") == "completed"
        lo, hi = r.get("min_density_ratio"), r.get("max_density_ratio")
        cells = [r["scenario"], f"{(r.get('dx') or 0.0) * 1000:g}", short_status(r.get("status")),
                 "-" if r.get("steps") is None else f"{int(r['steps']):,}", fmt(r.get("wall_time_s")),
                 *[fmt(r.get(m), r.get(f"{m}_error_pct")) if done else "-" for m in metrics],
                 f"{int(r.get('excluded_particles') or 0)} ({pct(r.get('excluded_fraction'))})",
                 pct(r.get("peak_clumped_fraction")),
                 "-" if lo is None or hi is None else f"{lo:.3f}-{hi:.3f}", pct(r.get("peak_energy_growth"))]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def headline(rows, metrics, tolerance_pct=10.0) -> str:
    """Per metric with an experimental value: the cheapest completed case within the tolerance."""
    lines = []
    for metric in metrics:
        if not any(r.get(f"{metric}_error_pct") is not None for r in rows):
            continue
        best = cheapest_within(rows, metric, tolerance_pct)
        if best is None:
            lines.append(f"{metric}: no case within {tolerance_pct:g}% of the experiment")
        else:
            lines.append(f"{metric}: cheapest within {tolerance_pct:g}%: {best['case']} ({best[metric]:.3g}, "
                         f"{best[f'{metric}_error_pct']:+.1f}%) in {best['wall_time_s']:.0f} s, "
                         f"{best['particle_steps']:.3g} particle-steps")
    return "\n".join(lines)
