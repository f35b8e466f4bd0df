"""A thin sheet of water sliding over a horizontal plate and off its sharp edge, in 3D
(scenes.exact.thin_sheet): where its pressure is known (issue 56). On the plate the sheet is
hydrostatic, rho g d at its bottom (d its depth, 3 spacings); off the edge it falls freely and its
pressure is ambient, 0. At each output: the lowest and the 1st-percentile pressure of the fluid over
the plate and of the fluid in the air beyond its edge (at least 0.1 m above the floor, before it
lands), and the plate's sensors under the sheet (the transducers' mean over the steps, clipped at
0, and their raw step readings). The issue's limits: a sensor's mean no lower than -5% of rho g d;
the fluid's pressure in the sheet no lower than -0.1 rho U^2 / 2.

    python bench/thin_sheet.py [--dx 0.01] [--depth 3] [--speed 1.0] [--end 0.5] [--set KEY=VALUE ...]
"""
import argparse

import numpy as np

from gpusph_ros.scenes.exact import PLATE_END, PLATE_TOP, SHEET_START, thin_sheet
from gpusph_ros.scenes.exact import SHEET_SENSORS as SENSOR_X


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=0.01)
    ap.add_argument("--depth", type=int, default=3, help="the sheet's depth in spacings")
    ap.add_argument("--speed", type=float, default=1.0, help="U [m/s]")
    ap.add_argument("--end", type=float, default=0.5)
    ap.add_argument("--rate", type=float, default=100.0)
    ap.add_argument("--verbose", action="store_true", help="where the lowest pressure over the plate is, and each "
                    "layer's mean pressure there")
    ap.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE", help="more run settings")
    args = ap.parse_args()
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.measure.suite import Measurements
    from gpusph_ros.scenes.build import build_run
    from gpusph_ros.scenes.settings import resolve
    from gpusph_ros.sph.state import FLUID

    sc = thin_sheet(args.dx, args.depth)
    built = build_run(sc, resolve(sc, sets=args.set, dx=args.dx, end_time=args.end))
    fluid = built.particles.ptype == FLUID
    built.particles.vel[fluid, 0] = args.speed
    solver = built.solver()
    measurements = Measurements(solver, built)
    rho_g_d = 1000.0 * 9.81 * args.depth * args.dx
    dynamic = 0.5 * 1000.0 * args.speed ** 2
    print(f"rho g d = {rho_g_d:.1f} Pa, rho U^2 / 2 = {dynamic:.1f} Pa, {solver.n} particles; "
          "pressures [Pa]: plate min / p1, air min / p1 (count), sensors mean (raw)")
    worst = {"plate": 0.0, "air": 0.0}
    sensors = {}
    for k in range(1, int(round(args.end * args.rate)) + 1):
        solver.advance(k / args.rate)
        snap = solver.snapshot()
        read = measurements.sample()["sensors"]
        f = snap["ptype"] == FLUID
        x, z, p = snap["pos"][f, 0], snap["pos"][f, 2], snap["pressure"][f]
        groups = {"plate": x < PLATE_END, "air": (x > PLATE_END) & (z > 0.1)}
        line = f"t {solver.time:5.3f}"
        for name, where in groups.items():
            if where.any():
                worst[name] = min(worst[name], float(p[where].min()))
                line += f" | {name} {p[where].min():8.1f} / {np.percentile(p[where], 1):8.1f} ({where.sum()})"
        for x0 in SENSOR_X:
            name = f"plate_{round(x0 * 100)}cm"
            sensors.setdefault(x0, []).append((solver.time, read[name], read[name + "_raw"]))
            line += f" | {read[name]:6.1f} ({read[name + '_raw']:6.1f})"
        if args.verbose and groups["plate"].any():
            where = groups["plate"]
            j = np.argmin(np.where(where, p, np.inf))
            line += f" | min at x {x[j]:.3f} z {z[j]:.3f}; layers " + " ".join(
                f"{np.mean(p[where & (np.abs(z - zl) < 0.25 * args.dx)]):.0f}"
                for zl in PLATE_TOP + (np.arange(args.depth) + 0.5) * args.dx)
        print(line, flush=True)
    print(f"lowest fluid pressure over the plate {worst['plate']:.1f} Pa = {worst['plate'] / dynamic:+.3f} rho U^2/2; "
          f"in the air {worst['air']:.1f} Pa = {worst['air'] / dynamic:+.3f} rho U^2/2 (limit -0.1)")
    for x0, rows in sensors.items():
        t, mean, raw = np.asarray(rows).T
        covered = t < (x0 - SHEET_START) / args.speed  # until the sheet's tail passes
        print(f"sensor at x = {x0} m: while covered, mean {mean[covered].mean():.1f} Pa (raw "
              f"{raw[covered].mean():.1f}, lowest raw {raw[covered].min():.1f}) against rho g d {rho_g_d:.1f}")


if __name__ == "__main__":
    main()
