"""A 2D jet impinging normally on a wall, whose loads are known exactly (issue: wall pressure that
agrees with the force): a block of fluid b wide moving at U onto a wall of boundary particles,
without gravity. Once the water-hammer transient of the first contact has passed and until the
jet's tail arrives, momentum gives the force per unit depth rho U^2 b, and the stagnation point
carries rho U^2 / 2. At each time this prints the net force on the wall's particles, the load of
the wall pressure read by the sensors along the face (measure/sensors.py) and the pressure at the
stagnation point three ways: the sensor's reconstruction, the fluid interpolated at the face, and
the wall particles' own.

    python bench/jet_impingement.py [--per-width 20] [--boundary dynamic] [--set key=value ...]
"""
import argparse
import time

import numpy as np
import warp as wp


def main(argv=None):
    from gpusph_ros.scenes.yaml_input import value

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-width", type=int, default=20, help="particles across the jet")
    ap.add_argument("--boundary", default="dynamic")
    ap.add_argument("--every", type=float, default=0.05, help="[s] between two samples")
    ap.add_argument("--window", type=float, nargs=2, default=[0.4, 1.4],
                    help="[s] the steady window: after the first contact's transient, before the tail arrives")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a solver setting")
    args = ap.parse_args(argv)
    settings = {key: value(text) for key, _, text in (item.partition("=") for item in args.set)}
    wp.config.log_level = wp.LOG_WARNING
    from gpusph_ros.measure.forces import BodyWrench
    from gpusph_ros.measure.probes import PointProbes
    from gpusph_ros.measure.sensors import WallPressure, face_load
    from gpusph_ros.scenes.exact import C0, WIDTH, U, impinging_jet, jet_force, jet_stagnation_pressure
    from gpusph_ros.sph import Solver

    cfg, particles, face, dx = impinging_jet(args.per_width, args.boundary, **settings)
    solver = Solver(cfg, particles)
    wrench = BodyWrench(solver, 0)
    # the wall's face sampled every dx/2 over the reach of the sheets
    ys = np.arange(-0.8, 0.8 + 1e-9, dx / 2)
    pts = np.column_stack([np.full(len(ys), face), ys, np.zeros(len(ys))])
    normals = np.tile([-1.0, 0.0, 0.0], (len(ys), 1))
    sensors = WallPressure(solver, pts, normals)
    at_face = PointProbes(solver, pts[len(ys) // 2:len(ys) // 2 + 1])
    areas = np.full(len(ys), dx / 2)
    force_exact, p_exact = jet_force(), jet_stagnation_pressure()
    print(f"2D jet, b = {WIDTH} m ({args.per_width} particles), U = {U} m/s, c0 = {C0} m/s, {args.boundary}, "
          f"{solver.n:,} particles, settings {settings}; exact: force {force_exact:.1f} N/m, stagnation "
          f"{p_exact:.0f} Pa")
    print(f"{'t s':>5} {'F particles':>11} {'err':>6} {'F sensors':>9} {'err':>6} {'p sensor':>8} {'err':>6} "
          f"{'p fluid@face':>12} {'p wall part.':>12} {'p +rho a.n':>10} {'p jet':>8} {'wall s':>7}")
    start = time.perf_counter()
    centre = np.abs(solver.snapshot()["pos"][:, 1]) < dx
    rows, profile = [], []
    impulse, span, forces, steps = 0.0, 0.0, [], []
    for t in np.arange(args.every, args.window[1] + 1e-9, args.every):
        if t <= args.window[0] + 1e-9:
            solver.advance(float(t))
        else:
            # every step of the window, one sample a step: the wrench's own mean between samples
            # gives the window's force, and these give its scatter from step to step, large where
            # nothing damps the fluid's motion normal to the wall; the sensors too, whose reading
            # at the stagnation point scatters by a quarter of rho U^2 / 2 from step to step at ten
            # across, so that samples a lattice period apart (dx / U) miss its mean by points
            while not solver.reached(float(t)):
                before = solver.time
                solver.step()
                forces.append(wrench.sample()[0][0])
                impulse += forces[-1] * (solver.time - before)
                span += solver.time - before
                p_step = sensors.sample()
                steps.append((solver.time, solver.time - before, float(p_step[len(ys) // 2]),
                              face_load(p_step, pts, normals, areas, np.zeros(3))[0][0],
                              face_load(np.maximum(p_step, 0.0), pts, normals, areas, np.zeros(3))[0][0]))
        fx = wrench.sample()[0][0]
        p_wall = sensors.sample()
        f_sensors = face_load(p_wall, pts, normals, areas, np.zeros(3))[0][0]
        # the same without the film's suction: the sheets along the wall hold no pressure below ambient
        f_positive = face_load(np.maximum(p_wall, 0.0), pts, normals, areas, np.zeros(3))[0][0]
        p_sensor = float(p_wall[len(ys) // 2])
        p_face = float(at_face.sample()["pressure"][0])
        snap = solver.snapshot()
        first = (snap["ptype"] == 1) & centre & (snap["pos"][:, 0] < face + dx)
        p_particles = float(snap["pressure"][first].mean())
        # the jet's own pressure, in its core more than 3 b upstream of the wall (ambient, 0, in the
        # exact solution): the stagnation point carries it plus rho U^2 / 2 (Bernoulli on the axis)
        core = (snap["ptype"] == 0) & (snap["pos"][:, 0] < face - 3 * WIDTH) & (np.abs(snap["pos"][:, 1]) < WIDTH / 4)
        p_jet = float(snap["pressure"][core].mean()) if core.any() else float("nan")
        p_momentum = momentum_corrected(solver, pts[len(ys) // 2], normals[0], p_sensor)

        def err(v, ref):
            return f"{100 * (v / ref - 1):+5.1f}%"

        if t >= args.window[0] - 1e-9:
            rows.append((fx, f_sensors, p_sensor, p_face, p_particles, p_momentum, f_positive, p_jet))
            profile.append(p_wall)
        print(f"{t:>5.2f} {fx:>11.2f} {err(fx, force_exact):>6} {f_sensors:>9.2f} {err(f_sensors, force_exact):>6} "
              f"{p_sensor:>8.1f} {err(p_sensor, p_exact):>6} {p_face:>12.1f} {p_particles:>12.1f} "
              f"{p_momentum:>10.1f} {p_jet:>8.1f} {time.perf_counter() - start:>7.1f}", flush=True)
    _, f_sensors, p_sensor, p_face, p_particles, p_momentum, f_positive, p_jet = np.nanmean(rows, axis=0)
    fx = impulse / span
    # the window's means over every step, each weighted by its step, and the standard error of the
    # stagnation pressure's from the means of ten blocks (the reading is correlated from step to step)
    t_step, w, p_steps, load_steps, clipped_steps = np.array(steps).T
    p_every, load_every, clipped_every = (float((v * w).sum() / w.sum()) for v in (p_steps, load_steps, clipped_steps))
    edges = np.linspace(args.window[0], args.window[1], 11)
    blocks = [p_steps[(t_step > a) & (t_step <= b)].mean() for a, b in zip(edges[:-1], edges[1:])]
    error = np.std(blocks) / np.sqrt(len(blocks))
    print(f"mean over {args.window[0]:g}-{args.window[1]:g} s ({len(rows)} samples; the force over its "
          f"{len(forces)} steps): force on the particles {fx:.1f} N/m ({100 * (fx / force_exact - 1):+.1f}%, "
          f"scatter from step to step {np.std(forces) / fx:.2f} of it), wall-pressure load {f_sensors:.1f} N/m "
          f"({100 * (f_sensors / force_exact - 1):+.1f}%; {100 * (f_positive / force_exact - 1):+.1f}% without the "
          f"pressures below ambient), stagnation pressure: sensor {p_sensor:.0f} Pa "
          f"({100 * (p_sensor / p_exact - 1):+.1f}%), fluid at the face {p_face:.0f} Pa, wall particles "
          f"{p_particles:.0f} Pa ({p_particles / p_exact:.1f} x), the sensor with the fluid's deceleration "
          f"{p_momentum:.0f} Pa ({100 * (p_momentum / p_exact - 1):+.1f}%); the jet's core {p_jet:.1f} Pa, the "
          f"sensor above it {p_sensor - p_jet:.0f} Pa ({100 * ((p_sensor - p_jet) / p_exact - 1):+.1f}%)")
    print(f"over every step of the window ({len(p_steps)}): stagnation pressure {p_every:.0f} Pa "
          f"({100 * (p_every / p_exact - 1):+.1f}% +- {100 * error / p_exact:.1f}%, scatter from step to step "
          f"{np.std(p_steps) / p_exact:.2f} of rho U^2 / 2), wall-pressure load {load_every:.1f} N/m "
          f"({100 * (load_every / force_exact - 1):+.1f}%; {100 * (clipped_every / force_exact - 1):+.1f}% without "
          f"the pressures below ambient)")
    mean = np.mean(profile, axis=0) / p_exact
    print("wall pressure along the face, mean over the window, in rho U^2 / 2: " + ", ".join(
        f"y/b {y / WIDTH:+.1f}: {v:.2f}" for y, v in zip(ys[::len(ys) // 16], mean[::len(ys) // 16])))


def momentum_corrected(solver, point, normal, p_sensor: float) -> float:
    """The sensor's reading with the term its reconstruction leaves out: across delta = 1.5 h in
    front of the face Euler's equation gives dp/dn = rho (g - a).n, and the sensor takes a = 0
    (a fluid at rest against the wall); here a is the fluid's acceleration Shepard-interpolated at
    the interpolation point (the solver's last force pass), so p_wall gains rho delta a.n."""
    from gpusph_ros.measure.sensors import OFFSET_H
    from gpusph_ros.sph import kernels

    cfg = solver.config
    delta = OFFSET_H * cfg.h
    x = np.asarray(point) + delta * np.asarray(normal)
    pos, acc = solver.pos.numpy().astype(np.float64), solver.acc.numpy().astype(np.float64)
    fluid = solver.ptype.numpy() == 0
    vol = (solver.mass.numpy() / solver.rho.numpy()).astype(np.float64)
    r = np.linalg.norm(pos[fluid] - x, axis=1)
    near = r < 2.0 * cfg.h
    w = kernels.evaluate(cfg.kernel, cfg.dim, cfg.h, r[near])[0] * vol[fluid][near]
    if w.sum() <= 0.0:
        return p_sensor
    a = (w[:, None] * acc[fluid][near]).sum(axis=0) / w.sum()
    return p_sensor + cfg.rho0 * delta * float(a @ np.asarray(normal))


if __name__ == "__main__":
    main()
