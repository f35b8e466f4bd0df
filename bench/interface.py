"""A still 2D tank with a refinement zone: how far an interface between spacings disturbs it. At
each time, by side of the interface (the zone's particles, the rest), the mean pressure over rho0 g d
in depth bins (interior, 5 cm from the end walls) and the largest and mean speed over sqrt(g H);
the fluid's mass against its start. With ``--zone none`` the same tank is uniform. ``--first-step``
prints instead, after one step, the fluid's mean and largest horizontal acceleration in bands
2.5 cm wide across the tank, 3 to 17 cm deep: where an interface pushes the fluid before it moves.

    python bench/interface.py [--zone middle|upper|none] [--dx 0.01] [--set boundary=mdbc] [--first-step]
"""
import argparse
import time

import numpy as np
import warp as wp

LENGTH, DEPTH, HEIGHT = 0.6, 0.2, 0.3  # [m]
ZONES = {"middle": ([0.2, 0.0], [0.4, HEIGHT]),  # two vertical interfaces through the whole depth
         "upper": ([0.0, 0.1], [LENGTH, HEIGHT])}  # one horizontal interface at mid-depth
BINS = ((0.2, 0.4), (0.4, 0.6), (0.6, 0.8), (0.8, 0.95))  # [H] depth bins


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--zone", choices=[*ZONES, "none"], default="middle")
    ap.add_argument("--dx", type=float, default=0.01)
    ap.add_argument("--times", type=float, nargs="+", default=[0.25, 0.5, 1.0, 1.5, 2.0])
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a run setting")
    ap.add_argument("--first-step", action="store_true", help="the horizontal acceleration after one step, by band")
    args = ap.parse_args(argv)
    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.scenes.build import build_run
    from gpusph_ros.scenes.schema import parse_scene
    from gpusph_ros.scenes.settings import resolve

    data = {"name": "still", "dim": 2, "tank": [LENGTH, HEIGHT],
            "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [LENGTH, DEPTH]}]}
    if args.zone != "none":
        lo, hi = ZONES[args.zone]
        data["refine"] = [{"name": args.zone, "lo": lo, "hi": hi, "ratio": 0.5}]
    scene = parse_scene(data)
    model = build_run(scene, resolve(scene, dx=args.dx, sets=args.set))
    solver = model.solver()
    cfg = model.config
    fluid0 = model.particles.ptype == 0
    mass0 = model.particles.mass[fluid0].sum()
    scale = np.sqrt(cfg.g_norm * DEPTH)
    print(f"still tank, zone {args.zone}, dx {args.dx * 1000:g} mm, {solver.n:,} particles, settings {args.set}")
    if args.first_step:
        return first_step(solver, cfg)
    print(f"{'t s':>5} {'steps':>6} {'wall s':>6} {'side':>6}  p / rho0 g d - 1 by depth "
          + " ".join(f"{a:g}-{b:g}H" for a, b in BINS) + "   max |u|  mean |u| (sqrt gH)")
    start = time.perf_counter()
    for t in args.times:
        solver.advance(t)
        snap = solver.snapshot()
        f = snap["ptype"] == 0
        x, p, u = snap["pos"][f], snap["pressure"][f], np.linalg.norm(snap["vel"][f], axis=1) / scale
        fine = snap_fine(solver, f)
        depth = DEPTH - x[:, 1]
        interior = (x[:, 0] > 0.05) & (x[:, 0] < LENGTH - 0.05)
        for side, sel in (("coarse", ~fine), ("fine", fine)):
            if not sel.any():
                continue
            errors = []
            for a, b in BINS:
                s = sel & interior & (depth > a * DEPTH) & (depth < b * DEPTH)
                errors.append(p[s].mean() / (cfg.rho0 * cfg.g_norm * depth[s].mean()) - 1.0 if s.any() else np.nan)
            print(f"{t:5.2f} {solver.steps:6d} {time.perf_counter() - start:6.0f} {side:>6}  "
                  + " ".join(f"{100 * e:+6.1f}%" for e in errors)
                  + f"   {100 * u[sel].max():6.2f}% {100 * u[sel].mean():6.3f}%")
        print(f"      fluid mass / start - 1: {snap['mass'][f].sum() / mass0 - 1.0:+.1e}", flush=True)


def first_step(solver, cfg):
    """The mean and largest horizontal acceleration of the fluid, in g, by band, after one step."""
    solver.step()
    snap = solver.snapshot()
    acc = np.empty((solver.n, 3))
    acc[solver.ids.numpy()] = solver.acc.numpy()  # the last force pass's, in the caller's order
    f = snap["ptype"] == 0
    x, a = snap["pos"][f], acc[f, 0] / cfg.g_norm
    deep = (x[:, 1] > 0.03) & (x[:, 1] < 0.17)
    print(f"{'band centre m':>13} {'mean a_x g':>10} {'max |a_x| g':>11}")
    for centre in np.arange(0.05, LENGTH - 0.04, 0.025):
        band = deep & (np.abs(x[:, 0] - centre) < 0.0125)
        print(f"{centre:13.3f} {a[band].mean():+10.4f} {np.abs(a[band]).max():11.4f}")


def snap_fine(solver, fluid) -> np.ndarray:
    """Which fluid particles (in the snapshot's order) are finer than the scene's dx."""
    h = np.empty(solver.n)
    h[solver.ids.numpy()] = solver.hsml.numpy()
    return h[fluid] < solver.config.h * (1.0 - 1e-6)


if __name__ == "__main__":
    main()
