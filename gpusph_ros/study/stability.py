"""Where a method fails: the largest stable CFL number and the smallest stable sound-speed
coefficient of each combination of kernel x viscosity x boundary x density treatment x particle
shifting x XSPH, on a small dam break, and how each failure showed itself.

A run is stable when it reaches the end time with every health check quiet (``sph.health.CHECKS``:
NaN, leaving the domain, density bounds, wall penetration, a step's displacement, clumping, energy
growth; strict: no particle excluded) and the neighbour lists never overflow. Each limit is found
by bisection on a log scale between a stable and an unstable value (``search``), each probe a run
from rest. The CFL search keeps the sound-speed coefficient at its default (c0 = 10 sqrt(g H));
the sound-speed search keeps CFL 0.3.

Boundaries: ``lennard_jones``, ``monaghan_kajtar`` and ``dynamic`` walls of boundary particles,
``planes`` particle-less walls (``scenes.reduce`` wall_planes). Density treatments: ``none``,
``shepard`` (thesis Eq. 2.28 every 40 steps, as the thesis ran it), ``delta`` (delta-SPH).
Shifting (Lind et al. 2012, DualSPHysics' coefficients) and XSPH (thesis Eq. 2.22, eps 0.5) are
each ``off`` or ``on``.
"""
from __future__ import annotations

import csv
import itertools
import math
import multiprocessing
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from ..sph import boundaries, kernels, viscosity

KERNELS = kernels.NAMES
VISCOSITIES = viscosity.NAMES
BOUNDARIES = boundaries.STUDIED
DENSITIES = ("none", "shepard", "delta")
SWITCHES = ("off", "on")
SWITCHED = ("shifting", "xsph")  # the dimensions that are off or on
CFL_RANGE = (0.1, 1.0)
C0_RANGE = (2.0, 20.0)
C0_SEARCH_CFL = 0.3  # the CFL of the sound-speed search, where docs/stability was measured
COLUMNS = ("kernel", "viscosity", "boundary", "density", "shifting", "xsph", "cfl_max", "cfl_failure", "c0_coef_min",
           "c0_failure", "runs", "wall_s")


@dataclass(frozen=True)
class Combination:
    kernel: str
    viscosity: str
    boundary: str
    density: str
    shifting: str = "off"
    xsph: str = "off"

    def settings(self) -> dict:
        """Run settings (``scenes.settings.resolve`` keys) of this combination."""
        out = {"kernel": self.kernel, "viscosity": self.viscosity,
               "density_diffusion": "delta" if self.density == "delta" else "none",
               "shepard_every": 40 if self.density == "shepard" else 0,
               "shifting": self.shifting == "on", "xsph": self.xsph == "on"}
        return {**out, **boundaries.model(self.boundary).run_settings()}


def combinations(kernels=KERNELS, viscosities=VISCOSITIES, boundaries=BOUNDARIES, densities=DENSITIES,
                 shiftings=SWITCHES, xsphs=SWITCHES) -> list:
    return [Combination(*c) for c in itertools.product(kernels, viscosities, boundaries, densities, shiftings, xsphs)]


def trial(scene_name: str, settings: dict) -> str:
    """Run ``scene_name`` from rest under ``settings``; "" when it reaches the end time, else the
    name of the check that stopped it."""
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from ..scenes.build import build_run
    from ..scenes.schema import load_scene
    from ..scenes.settings import resolve
    from ..sph import HealthError, NeighbourOverflow

    scene = load_scene(scene_name)
    # strict unless the settings say otherwise: a fault of one particle is a failure here, as when
    # docs/stability was measured (before particles could be excluded)
    config = resolve(scene, **{"max_excluded_fraction": 0.0, **settings})
    model = build_run(scene, config)
    solver = model.solver()
    try:
        solver.advance(config.output.end_time)
    except HealthError as err:
        return err.check
    except NeighbourOverflow:
        return "neighbour_overflow"
    return ""


def search(fails, lo: float, hi: float, stable_at: str, iterations: int):
    """Bisect on a log scale for the limit of stability within [lo, hi].

    ``fails(x)`` runs at x and returns "" or the failure. ``stable_at`` is "lo" when small values
    are the stable ones (CFL: the largest stable is sought), "hi" when large values are (c0: the
    smallest stable). Returns (limit, failure seen just past it, runs); the limit is ``hi`` (or
    ``lo``) when even the far end is stable, and None when even the safe end fails."""
    safe, risky = (lo, hi) if stable_at == "lo" else (hi, lo)
    failure = fails(risky)
    runs = 1
    if not failure:
        return risky, "", runs
    safe_failure = fails(safe)
    runs += 1
    if safe_failure:
        return None, safe_failure, runs
    for _ in range(iterations):
        middle = math.sqrt(safe * risky)
        result = fails(middle)
        runs += 1
        if result:
            risky, failure = middle, result
        else:
            safe = middle
    return safe, failure, runs


def limits(combination: Combination, scene: str, end_time: float, dx: float, iterations: int,
           device: str = "cpu") -> dict:
    """The row of ``combination``: its CFL and sound-speed limits and their failure modes."""
    start = time.perf_counter()
    # one thread a run: the runs are small and many, so they go side by side instead
    base = {**combination.settings(), "dx": dx, "end_time": end_time, "output_rate": 1.0 / end_time,
            "particle_rate": 0.0, "device": device, "cpu_threads": 1}
    cfl, cfl_failure, cfl_runs = search(lambda x: trial(scene, {**base, "cfl": x}), *CFL_RANGE, "lo", iterations)
    c0, c0_failure, c0_runs = search(lambda x: trial(scene, {**base, "cfl": C0_SEARCH_CFL, "c0_coef": x}), *C0_RANGE,
                                     "hi", iterations)
    return {"kernel": combination.kernel, "viscosity": combination.viscosity, "boundary": combination.boundary,
            "density": combination.density, "shifting": combination.shifting, "xsph": combination.xsph,
            "cfl_max": cfl, "cfl_failure": cfl_failure, "c0_coef_min": c0, "c0_failure": c0_failure,
            "runs": cfl_runs + c0_runs, "wall_s": round(time.perf_counter() - start, 1)}


def run_study(out_dir, scene: str = "collapse_2d", end_time: float = 0.3, dx: float = 0.05715 / 10,
              iterations: int = 4, workers: int = 2, combos=None, device: str = "cpu", progress=print) -> list:
    """Every combination's row, written to ``out_dir``/stability.csv as each finishes; then the
    Markdown table and the map beside it."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    combos = combos or combinations()
    rows = []
    # spawned workers: each loads Warp afresh instead of inheriting a forked runtime
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = [pool.submit(limits, c, scene, end_time, dx, iterations, device) for c in combos]
        for future in futures:
            rows.append(future.result())
            write(rows, out_dir / "stability.csv")
            if progress:
                r = rows[-1]
                progress(f"[{len(rows)}/{len(combos)}] {label(r)}: "
                         f"CFL <= {fmt(r['cfl_max'])} ({r['cfl_failure'] or 'none'}), c0 >= {fmt(r['c0_coef_min'])} "
                         f"sqrt(gH) ({r['c0_failure'] or 'none'}), {r['runs']} runs, {r['wall_s']} s")
    report(out_dir)
    return rows


def report(out_dir) -> list:
    """stability.md and stability_map.png from ``out_dir``/stability.csv; their paths."""
    out_dir = Path(out_dir)
    rows = read(out_dir / "stability.csv")
    (out_dir / "stability.md").write_text(table(rows) + "\n")
    return [out_dir / "stability.md", chart(rows, out_dir / "stability_map.png")]


def fmt(value) -> str:
    return "fails" if value is None or value == "" else f"{float(value):.3g}"


def write(rows, path):
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)


def read(path) -> list:
    rows = []
    with open(path, newline="") as fh:
        for row in csv.DictReader(fh):
            for key in ("cfl_max", "c0_coef_min", "wall_s", "runs"):
                row[key] = None if row[key] in ("", "None") else float(row[key])
            for key in SWITCHED:  # a table from before these dimensions: both off
                row[key] = row.get(key) or "off"
            rows.append(row)
    return rows


def table(rows) -> str:
    """A Markdown table: one line a combination."""
    lines = ["| kernel | viscosity | boundary | density | shifting | XSPH | largest stable CFL | fails by | "
             "smallest stable c0 [sqrt(gH)] | fails by |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['kernel']} | {r['viscosity']} | {r['boundary']} | {r['density']} | {r['shifting']} | "
                     f"{r['xsph']} | {fmt(r['cfl_max'])} | "
                     f"{r['cfl_failure'] or '-'} | {fmt(r['c0_coef_min'])} | {r['c0_failure'] or '-'} |")
    return "\n".join(lines)


def label(row) -> str:
    """A combination in one line, its switches named only when on."""
    extras = [name for name in SWITCHED if row.get(name) == "on"]
    return " ".join([row["kernel"], row["viscosity"], row["boundary"], row["density"], *extras])


ABBREVIATIONS = {"non_finite": "N", "outside_domain": "O", "density_bounds": "D", "wall_penetration": "W",
                 "displacement": "M", "clumping": "C", "energy_growth": "E", "excluded_fraction": "X",
                 "zone_reserve": "Z", "zone_edge": "B", "neighbour_overflow": "L", "": ""}


def chart(rows, path):
    """The stability map: rows kernel x viscosity x shifting x XSPH, columns boundary x density; colour the limit,
    letter the failure past it (N NaN, O out of domain, D density, W wall penetration, M displacement,
    C clumping, E energy growth, X excluded fraction, L neighbour-list overflow); grey and x where
    even the safe end fails."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    present = {(r["kernel"], r["viscosity"], r["shifting"], r["xsph"]) for r in rows}
    ys = [y for y in itertools.product(KERNELS, VISCOSITIES, SWITCHES, SWITCHES) if y in present]
    xs = [(b, d) for b in BOUNDARIES for d in DENSITIES if any(r["boundary"] == b and r["density"] == d for r in rows)]
    at = {(r["kernel"], r["viscosity"], r["shifting"], r["xsph"], r["boundary"], r["density"]): r for r in rows}
    fig, axes = plt.subplots(1, 2, figsize=(16, 0.45 * len(ys) + 2.5), constrained_layout=True)
    for ax, key, failure, title, cmap, lo_hi in (
            (axes[0], "cfl_max", "cfl_failure", "largest stable CFL (higher is better)", "viridis", CFL_RANGE),
            (axes[1], "c0_coef_min", "c0_failure", "smallest stable c0 / sqrt(gH) (lower is better)", "viridis_r",
             C0_RANGE)):
        grid = np.full((len(ys), len(xs)), np.nan)
        for i, y in enumerate(ys):
            for j, x in enumerate(xs):
                r = at.get((*y, *x))
                if r is None:
                    continue
                if r[key] is not None:
                    grid[i, j] = r[key]
                letter = ABBREVIATIONS.get(r[failure], "?")
                ax.text(j, i, f"x{letter}" if r[key] is None else letter, ha="center", va="center", fontsize=8,
                        color="0.3" if r[key] is None else "black")
        colours = plt.get_cmap(cmap).with_extremes(bad="0.88")  # grey: unstable even at the safe end
        image = ax.imshow(grid, cmap=colours, vmin=lo_hi[0], vmax=lo_hi[1], aspect="auto")
        ax.set_xticks(range(len(xs)), [f"{b}\n{d}" for b, d in xs], rotation=90, fontsize=7)
        ax.set_yticks(range(len(ys)), [" / ".join([k, v] + [n for n, on in (("shifting", sh), ("XSPH", xs_))
                                                              if on == "on"]) for k, v, sh, xs_ in ys], fontsize=7)
        ax.set_title(title, fontsize=9)
        fig.colorbar(image, ax=ax, shrink=0.8)
    fig.suptitle("Stability map (letter: how the first unstable value failed; N NaN, O out of domain, D density, "
                 "W wall penetration, M displacement, C clumping, E energy growth, X excluded fraction, "
                 "L list overflow; grey, x: fails even at the safe end)",
                 fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
