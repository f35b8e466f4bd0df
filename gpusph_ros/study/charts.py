"""A study's charts, from its results table alone.

- error against dx, one line per scenario, GPUSPH's runs of the same thesis scenario beside ours
  (the style of the thesis's Figures 10-12, 19-23, 40-48);
- error against wall time and against particle-steps, every completed case a point, the Pareto
  front marked: for a given accuracy, the cheapest setting; a case that excluded particles is
  ringed in grey with the share it lost.
"""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the file backend)

from ..analysis import reference as R  # noqa: E402
from ..analysis.report import LABELS  # noqa: E402
from .table import error_of, pareto  # noqa: E402

# metric -> (thesis table, column) of GPUSPH's runs; {scene} is the row's scene (DamBreak 2 depth)
THESIS = {
    "peak_velocity": ("dambreak1_peak_velocity.csv", "percent_error"),
    "peak_force_at_wall": ("dambreak1_peak_force_at_wall.csv", "percent_error"),
    "peak_force_0p06m": ("dambreak1_peak_force_0p06m.csv", "percent_error"),
    "velocity_rms": ("dambreak1_velocity_rms.csv", "rms_error_m_s"),
    "force_rms_0p06m": ("dambreak1_force_rms_0p06m.csv", "rms_error_N"),
    "mean_velocity": ("{scene}_mean_velocity.csv", "percent_error"),
}
COSTS = {"wall_time_s": "wall time [s]", "particle_steps": "particle-steps"}


def _groups(rows):
    """Completed rows by (scene, scenario), in first-seen order."""
    out = {}
    for row in rows:
        out.setdefault((row["scene"], row["scenario"]), []).append(row)
    return out


def error_vs_dx(rows, metric, data=None):
    """The figure, or None when no case has an error measure for ``metric``."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ylabel = None
    for (scene, scenario), group in _groups(rows).items():
        pts = sorted((r["dx"], *error_of(r, metric)) for r in group if error_of(r, metric)[0] is not None)
        if not pts:
            continue
        ylabel = pts[0][2]
        line, = ax.plot([p[0] * 1000 for p in pts], [p[1] for p in pts], "o-", label=f"ours: {scene}, {scenario}")
        exact = [r for r in group if r.get("gpusph_scenario") not in (None, "")]
        if metric in THESIS and exact and scene.startswith(("dambreak1_thesis", "dambreak2")):
            table, column = THESIS[metric]
            scen = int(exact[0]["gpusph_scenario"])
            dx, value = R.gpusph_series(data, table.format(scene=scene), column, scen)
            if len(dx):
                ax.plot(dx * 1000, abs(value), "s--", mfc="none", color=line.get_color(),
                        label=f"GPUSPH (thesis scenario {scen})")
    if ylabel is None:
        plt.close(fig)
        return None
    label, unit = LABELS.get(metric, (metric, ""))
    ax.set_xlabel("particle spacing dx [mm]")
    ax.set_ylabel(ylabel + (f" [{unit}]" if "RMS" in ylabel and unit else ""))
    ax.set_title(f"{label}: error against particle spacing")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def error_vs_cost(rows, metric, cost="wall_time_s"):
    """Every completed case's error against its cost, the Pareto front marked; None when no case
    has an error measure for ``metric``."""
    points = [(r[cost], *error_of(r, metric), r) for r in rows
              if r.get(cost) and error_of(r, metric)[0] is not None]
    if not points:
        return None
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for (scene, scenario), group in _groups([p[3] for p in points]).items():
        ax.plot([r[cost] for r in group], [error_of(r, metric)[0] for r in group], "o",
                label=f"{scene}, {scenario}")
    lost = [p for p in points if float(p[3].get("excluded_particles") or 0) > 0]
    if lost:  # a case that excluded particles (sph.health) is marked, its share of the fluid stated
        ax.plot([p[0] for p in lost], [p[1] for p in lost], "o", mfc="none", mec="grey", ms=11,
                label="excluded particles")
        for c, e, _, r in lost:
            ax.annotate(f"{float(r.get('excluded_fraction') or 0):.2%} excluded", (c, e), textcoords="offset points",
                        xytext=(4, -10), fontsize=6, color="grey")
    front = pareto([(c, e, r) for c, e, _, r in points])
    ax.plot([p[0] for p in front], [p[1] for p in front], "k-", drawstyle="steps-post", lw=1.2, label="Pareto front")
    for c, e, r in front:
        ax.annotate(f"{r['scenario']}, {r['dx'] * 1000:g} mm", (c, e), textcoords="offset points", xytext=(4, 4),
                    fontsize=7)
    label, unit = LABELS.get(metric, (metric, ""))
    ylabel = points[0][2]
    ax.set_xscale("log")
    ax.set_xlabel(COSTS[cost] + (" (log)"))
    ax.set_ylabel(ylabel + (f" [{unit}]" if "RMS" in ylabel and unit else ""))
    ax.set_title(f"{label}: error against cost")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def write(rows, metrics, out_dir, data=None) -> list:
    """PNG files of every chart that has data; their paths."""
    from pathlib import Path

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for metric in metrics:
        figures = {f"{metric}_vs_dx": error_vs_dx(rows, metric, data)}
        figures.update({f"{metric}_vs_{cost}": error_vs_cost(rows, metric, cost) for cost in COSTS})
        for name, fig in figures.items():
            if fig is not None:
                fig.savefig(out_dir / f"{name}.png", dpi=110)
                plt.close(fig)
                paths.append(out_dir / f"{name}.png")
    return paths
