"""What a solver holds on its device, per particle and per family of arrays, with neighbour lists and
walking the cells (sph/neighbours.py): every array of ``Solver.device_bytes`` after a first output,
grouped by what it is for, and the plan's estimate beside it (scenes/resources.py). The table of
docs/results/speed.md.

    python bench/memory.py dambreak1_lab 0.03 [--set KEY=VALUE]
"""
import argparse

# each array by the family it belongs to (its holder and name: checkpoint.device_arrays); the
# reorder's scratch is the solver's _gathered, the rest of the arrays are a few bytes in all
FAMILIES = {
    "state (position, velocity, density, mass, h, kind, body, id)": (
        "solver.pos", "solver.vel", "solver.rho", "solver.mass", "solver.hsml", "solver.ptype", "solver.body",
        "solver.ids"),
    "predictor-corrector copies (half step, candidate)": (
        "solver._pos_h", "solver._vel_h", "solver._rho_h", "solver._pos_c", "solver._vel_c", "solver._rho_c"),
    "rates and pressure (acc, drho, XSPH, shifting, p, p / rho^2)": (
        "solver.acc", "solver._drho", "solver._xsph", "solver._shift", "solver.pressure", "fields.p_rho2"),
    "walls (acceleration, ghost offset)": ("solver.wall_acc", "solver.ghost"),
    "per-particle flags (spawned, needs a list, at fault, clumped)": (
        "solver._spawned", "solver._needs_list", "solver._faulty", "solver._clumped"),
    "SPS stress": ("fields.tau_diag", "fields.tau_off"),
    "cell sort (keys, order, cell ranges)": (
        "neighbours._keys", "neighbours._order", "neighbours._start", "neighbours._end"),
    "build positions": ("neighbours._x_build",),
    "neighbour lists and their count": ("neighbours.nbr", "neighbours.count"),
    "the lists' build: sorted copies": (
        "neighbours._pos_sorted", "neighbours._ptype_sorted", "neighbours._hsml_sorted"),
    "the walks: kinds, h and needs at the sort": (
        "neighbours._ptype_built", "neighbours._hsml_built", "neighbours._needs_built"),
}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("dx", type=float)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args()
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.scenes import resources
    from gpusph_ros.scenes.build import build_run
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve
    from gpusph_ros.sph import checkpoint

    scene = load_scene(args.scene)
    columns = {}
    for search in ("lists", "cells"):
        config = resolve(scene, sets=[f"dx={args.dx}", f"neighbour_search={search}", *args.set])
        solver = build_run(scene, config).solver()
        solver.advance(1.0 / config.output.output_rate)
        sizes = {path: a.size * wp.types.type_size_in_bytes(a.dtype) / solver.n
                 for path, a in checkpoint.device_arrays(solver).items()}
        grouped = {family: sum(sizes.pop(path, 0.0) for path in paths) for family, paths in FAMILIES.items()}
        total = solver.device_bytes() / solver.n
        grouped["the reorder's scratch (one array of each type)"] = total - sum(grouped.values()) - sum(sizes.values())
        grouped["the rest (flags, sums, clocks: a few bytes in all)"] = sum(sizes.values())
        grouped["total"] = total
        grouped["the plan's estimate"] = resources.device_bytes(solver.n, solver.config,
                                                                refined=bool(solver.config.zones))
        grouped["the plan's estimate"] /= solver.n
        columns[search] = grouped
    print(f"{args.scene} at dx = {args.dx} m ({solver.n:,} particles), bytes a particle on {solver.device}:\n")
    print("| family | lists | cells |\n| --- | --- | --- |")
    for family in columns["lists"]:
        print(f"| {family} | {columns['lists'][family]:.1f} | {columns['cells'][family]:.1f} |")


if __name__ == "__main__":
    main()
