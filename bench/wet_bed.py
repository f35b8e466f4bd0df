"""Stoker's wet-bed surge (``stoker_2d``) and the wall under it: at each time, the bore speed, the
plateau's depth and depth-mean velocity against Stoker's, and on the plateau the mean density of
the wall's top layer against the fluid's bed layer (both within dx of the bed) with the bed layer's
velocity. A wall model that lets the bed's density drift from the fluid's shows here as a slowed
surge (the rho0 floor tried in the README: wall 1,010.5 against fluid 1,003.1 kg/m^3 at 1 s).

    python bench/wet_bed.py [--dx 0.005] [--set visco_bound_factor=0] [--times 0.2 0.4 0.6 0.8 1.0]
"""
import argparse
import time

import warp as wp

DAM = 0.6  # [m] the column's downstream face in stoker_2d
DEPTH, BED = 0.1, 0.01  # [m] the column and the wet bed


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=0.005)
    ap.add_argument("--times", type=float, nargs="+", default=[0.2, 0.4, 0.6, 0.8, 1.0])
    ap.add_argument("--set", action="append", default=["visco_bound_factor=0"], metavar="KEY=VALUE",
                    help="a run setting (default: the wall's artificial viscosity off, as test_stoker runs it)")
    args = ap.parse_args(argv)
    wp.config.log_level = wp.LOG_WARNING  # no per-module load lines
    from gpusph_ros.runner import Run
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve
    from gpusph_ros.theory.stoker import stoker, surge

    scene = load_scene("stoker_2d")
    run = Run(scene, resolve(scene, dx=args.dx, sets=args.set))
    s = stoker(DEPTH, BED)
    print(f"stoker_2d, dx {args.dx * 1000:g} mm, {run.solver.n:,} particles, settings {args.set}; Stoker: bore "
          f"{s.bore_speed:.4f} m/s, depth {s.h_m:.4f} m, velocity {s.u_m:.4f} m/s")
    print(f"{'t s':>5} {'bore m/s':>8} {'depth m':>8} {'vel m/s':>8} {'wall rho':>9} {'fluid rho':>9} "
          f"{'bed u':>6} {'wall min':>8} {'wall s':>7}")
    start = time.perf_counter()
    for t in args.times:
        run.solver.advance(t)
        snap = run.solver.snapshot()
        pos, rho, fluid = snap["pos"], snap["rho"], snap["ptype"] == 0
        got = surge(pos[fluid], snap["vel"][fluid], t, DAM, DEPTH, BED, args.dx)
        x, y = pos[:, 0], pos[:, 1]
        plateau = (x > DAM + s.xi_m * t) & (x < DAM + s.bore_speed * t)
        bed = fluid & plateau & (y < args.dx)
        wall = (snap["ptype"] == 1) & plateau & (y < 0.0) & (y > -args.dx)
        print(f"{t:>5.2f} {(got.bore - DAM) / t:>8.4f} {got.depth:>8.4f} {got.velocity:>8.4f} "
              f"{rho[wall].mean():>9.2f} {rho[bed].mean():>9.2f} {snap['vel'][bed][:, 0].mean():>6.3f} "
              f"{rho[snap['ptype'] == 1].min():>8.2f} {time.perf_counter() - start:>7.1f}", flush=True)


if __name__ == "__main__":
    main()
