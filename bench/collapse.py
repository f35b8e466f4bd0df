"""Martin & Moyce 1952 column collapse at several resolutions: surge front against the table,
with no time shift, and the wall time each resolution cost; each run then goes on to the scene's
end (past the surge's impact on the far wall) and says how many fluid particles it excluded.

``--across`` runs the same column in 3D (issue 68, item 2: is a 3D front late where a 2D one is
not?): ``periodic``, a slab 9 spacings wide and periodic across, with no side walls; or a width in
metres between two side walls of particles.

    python bench/collapse.py [--per-width 20 30 40] [--precision float32] [--across periodic|WIDTH]
                             [--set KEY=VALUE ...]
"""
import argparse
import time

import numpy as np
import warp as wp

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene, parse_scene
from gpusph_ros.scenes.settings import parse_set
from gpusph_ros.share import data_dir

SCENE = load_scene("collapse_2d")
WIDTH = SCENE.fluid[0].hi[0]
END_TIME = float(SCENE.run_settings["end_time"])  # 0.3 s: past the impact on the far wall
TABLE = data_dir("martin_moyce_1952_collapse/ocellaris") / "martin_moyce_1952_table2_surge_front.txt"


def scene(across: str, dx: float):
    """The column's scene: the 2D one, or (``across``) in 3D, periodic across a slab 9 spacings wide
    (the shortest periodic axis the neighbour search allows) or between side walls that far apart."""
    if not across:
        return SCENE
    width = 9 * dx if across == "periodic" else float(across)
    (length, height, _), column = SCENE.tank, SCENE.fluid[0]
    return parse_scene({"name": "collapse_3d", "dim": 3, "tank": [length, width, height], "depth": SCENE.depth,
                        "walls": "particles", **({"periodic": [False, True, False]} if across == "periodic" else {}),
                        "fluid": [{"name": "column", "lo": [0.0, 0.0, 0.0],
                                   "hi": [column.hi[0], width, column.hi[1]]}],
                        "run": {"end_time": END_TIME}})


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--per-width", type=int, nargs="+", default=[20, 30, 40])
    parser.add_argument("--precision", default="float32")
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--across", default="", help="3D: 'periodic' (a slab 9 spacings wide) or a width [m] "
                        "between side walls; none: 2D")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a solver setting")
    args = parser.parse_args()
    settings = dict(map(parse_set, args.set))
    wp.config.log_level = wp.LOG_WARNING  # no per-module load lines
    table = np.loadtxt(TABLE)
    points = table[(table[:, 0] >= 1.0) & (table[:, 0] <= 2.55)]
    rate = np.sqrt(2 * 9.81 / WIDTH)
    print("T      Z_exp  " + "  ".join(f"a/{k:<3d} Z   err  " for k in args.per_width))
    results = []
    for per_width in args.per_width:
        model = build(scene(args.across, WIDTH / per_width), dx=WIDTH / per_width, precision=args.precision,
                      device=args.device, **settings)
        solver = model.solver()
        start = time.perf_counter()
        fronts = []
        for T in points[:, 0]:
            solver.advance(float(T / rate))
            snap = solver.snapshot()
            fronts.append(snap["pos"][snap["ptype"] == 0, 0].max() / WIDTH)
        wall = time.perf_counter() - start
        if not args.across:  # the 3D runs stop at the table's last front: they cost 10-20 times more
            solver.advance(END_TIME)
        results.append((per_width, solver.n, solver.time, solver.steps, wall, fronts,
                        (solver.excluded_particles, solver.excluded_fraction)))
    for k, (T, Z) in enumerate(points):
        cells = "  ".join(f"{r[5][k]:5.3f} {100 * (r[5][k] / Z - 1):+5.1f}%" for r in results)
        print(f"{T:5.2f}  {Z:5.2f}  {cells}")
    for per_width, n, reached, steps, wall, _, (excluded, share) in results:
        print(f"a/{per_width}: {n} particles, {wall:.1f} s wall to T = {points[-1, 0]:.2f} ({args.precision}, "
              f"{args.device}, compilation included on a first run); to t = {reached:g} s {steps} "
              f"steps, {excluded} fluid particles excluded ({100 * share:.3f}% of the fluid)")


if __name__ == "__main__":
    main()
