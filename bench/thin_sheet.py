"""A thin sheet of water sliding over a horizontal plate and off its sharp edge, in 3D
(scenes.exact.thin_sheet): where its pressure is known (issues 56 and 68). On the plate the sheet is
hydrostatic, rho g h at its bottom (h its local depth, 3 spacings until the sheet's tail thins it);
off the edge it falls freely and its pressure is ambient, 0.

Issue 68's measures, over the plate and in the air beyond its edge (at least 0.1 m above the floor,
before the sheet lands):
- each layer's mean pressure (a layer: the particles that started in it), averaged over each output
  interval (``--sub`` samples an interval): its lowest, in rho U^2 / 2 (limit -0.1);
- the 1st percentile of the fluid's pressure at each output: its lowest, in rho U^2 / 2 (limit -1);
- each plate sensor (the transducer's mean over the steps, clipped at 0) against rho g h, h the
  local depth above it (the top particle's top), while the sheet covers it, and rho g d as before.
The sheet is periodic across and 9 spacings wide: its 9 particles across move alike, so a
percentile over them is that of 9-particle rows.

    python bench/thin_sheet.py [--dx 0.01] [--depth 3] [--speed 1.0] [--end 0.3] [--set KEY=VALUE ...]
"""
import argparse

import numpy as np

from gpusph_ros.scenes.exact import PLATE_END, PLATE_TOP, SHEET_START, thin_sheet
from gpusph_ros.scenes.exact import SHEET_SENSORS as SENSOR_X

RHO, G = 1000.0, 9.81


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=0.01)
    ap.add_argument("--depth", type=int, default=3, help="the sheet's depth in spacings")
    ap.add_argument("--speed", type=float, default=1.0, help="U [m/s]")
    ap.add_argument("--end", type=float, default=0.3)
    ap.add_argument("--rate", type=float, default=100.0)
    ap.add_argument("--sub", type=int, default=5, help="samples an output interval for the layers' means")
    ap.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE", help="more run settings")
    args = ap.parse_args()
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.measure.suite import Measurements
    from gpusph_ros.scenes.build import build_run
    from gpusph_ros.scenes.settings import resolve
    from gpusph_ros.sph import HealthError
    from gpusph_ros.sph.state import FLUID

    sc = thin_sheet(args.dx, args.depth)
    built = build_run(sc, resolve(sc, sets=args.set, dx=args.dx, end_time=args.end))
    fluid = built.particles.ptype == FLUID
    built.particles.vel[fluid, 0] = args.speed
    layer = np.floor((built.particles.pos[fluid, 2] - PLATE_TOP) / args.dx).astype(int)
    solver = built.solver()
    measurements = Measurements(solver, built)
    rho_g_d = RHO * G * args.depth * args.dx
    dynamic = 0.5 * RHO * args.speed ** 2
    print(f"rho g d = {rho_g_d:.1f} Pa, rho U^2 / 2 = {dynamic:.1f} Pa, {solver.n} particles; per output, "
          "in rho U^2 / 2: the layers' interval means and the 1st percentile, plate | air; the sensors "
          "[Pa] (rho g h)")
    worst = {"plate": [np.inf, np.inf], "air": [np.inf, np.inf]}  # [lowest layer mean, lowest 1st percentile]
    sensors = {x0: [] for x0 in SENSOR_X}
    for k in range(1, int(round(args.end * args.rate)) + 1):
        sums = {name: np.zeros(args.depth) for name in worst}
        counts = {name: np.zeros(args.depth) for name in worst}
        for q in range(1, args.sub + 1):
            try:
                solver.advance((k - 1 + q / args.sub) / args.rate)
            except HealthError as failed:
                print(f"failed: {failed}")
                break
            snap = solver.snapshot()
            x, z, p = snap["pos"][fluid, 0], snap["pos"][fluid, 2], snap["pressure"][fluid]
            groups = {"plate": x < PLATE_END, "air": (x > PLATE_END) & (z > 0.1)}
            for name, where in groups.items():
                for m in range(args.depth):
                    sel = where & (layer == m)
                    if sel.any():
                        sums[name][m] += p[sel].mean()
                        counts[name][m] += 1
        line = f"t {solver.time:5.3f}"
        for name, where in groups.items():
            held = counts[name] > 0
            if not held.any():
                continue
            means = sums[name][held] / counts[name][held] / dynamic
            p1 = np.percentile(p[where], 1) / dynamic
            worst[name] = [min(worst[name][0], means.min()), min(worst[name][1], p1)]
            line += f" | {name} " + " ".join(f"{v:+5.2f}" for v in means) + f" p1 {p1:+6.2f}"
        read = measurements.sample()["sensors"]
        for x0 in SENSOR_X:
            above = np.abs(x - x0) < args.dx
            h = (z[above].max() + 0.5 * args.dx - PLATE_TOP) if above.any() else 0.0
            reading = read[f"plate_{round(x0 * 100)}cm"]
            sensors[x0].append((solver.time, reading, RHO * G * h))
            line += f" | {reading:5.0f} ({RHO * G * h:4.0f})"
        print(line, flush=True)
        if q < args.sub:
            break
    for name, (mean, p1) in worst.items():
        print(f"{name}: lowest layer mean over an interval {mean:+.3f} rho U^2/2 (limit -0.1), lowest 1st "
              f"percentile {p1:+.3f} rho U^2/2 (limit -1)")
    for x0, rows in sensors.items():
        t, mean, hydro = np.asarray(rows).T
        covered = (t < (x0 - SHEET_START) / args.speed) & (hydro > 0.0)  # until the sheet's tail passes
        ratio = mean[covered] / hydro[covered] - 1.0
        print(f"sensor at x = {x0} m, {covered.sum()} outputs covered: mean {mean[covered].mean():.1f} Pa against "
              f"rho g d {rho_g_d:.1f} ({mean[covered].mean() / rho_g_d - 1:+.1%}); against rho g h: mean "
              f"{ratio.mean():+.1%}, worst {ratio[np.argmax(np.abs(ratio))]:+.1%}; scatter output to output "
              f"{np.sqrt(np.mean(np.diff(mean[covered]) ** 2)) / mean[covered].mean():.1%}")


if __name__ == "__main__":
    main()
