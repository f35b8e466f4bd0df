"""A 2D wedge entering still water at constant speed against two Wagner-type models
(theory/water_entry.py): a wedge of deadrise beta, apex at the surface at t = 0, driven down at V
(motion translate); before its chines wet, the vertical force per unit length is F = C rho V^3 t, with
C = pi^3 / (4 tan^2 beta) in Wagner's theory and C from the whole Bernoulli pressure on the body in the
modified Logvinovich model (Korobkin 2004). Prints the force on the wedge's particles (the mean over
the steps since the last sample) against both, twenty times before the chines wet, and the mean ratios
over 0.27-0.82 of that time (0.02-0.06 s at 30 degrees).

    python bench/wedge_entry.py 0.01 [deadrise_deg=30] [boundary=dynamic ...]   # dx [m], then settings
"""
import math
import sys
import time

import numpy as np
import warp as wp


def main():
    from gpusph_ros.measure.forces import BodyWrench
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import parse_scene
    from gpusph_ros.scenes.yaml_input import value
    from gpusph_ros.sph import Solver
    from gpusph_ros.theory import water_entry

    wp.config.log_level = wp.LOG_WARNING
    dx = float(sys.argv[1]) if len(sys.argv) > 1 else 0.01
    settings = {k: value(v) for k, _, v in (a.partition("=") for a in sys.argv[2:])}
    beta, speed = float(settings.pop("deadrise_deg", 30.0)), 1.0
    top = 0.3 + 0.2 * math.tan(math.radians(beta))
    scene = parse_scene({"name": "wedge", "dim": 2, "tank": [1.0, 0.6],
                         "fluid": [{"name": "water", "lo": [0, 0], "hi": [1.0, 0.3]}],
                         "obstacles": [{"name": "wedge", "lo": [0.3, 0.3], "hi": [0.7, top], "shape": "wedge",
                                        "deadrise_deg": beta, "motion": {"type": "translate",
                                                                         "velocity": [0.0, -speed]}}]})
    solver = Solver(*(lambda m: (m.config, m.particles))(build(scene, dx=dx, **settings)))
    wrench = BodyWrench(solver, 0)
    wagner, mlm = water_entry.wagner_coefficient(beta), water_entry.mlm_coefficient(beta)
    print(f"wedge {beta:g} deg at {speed} m/s, dx = {dx} m, {solver.n} particles, {settings}; F / (rho V^3 t): "
          f"Wagner {wagner:.2f}, modified Logvinovich {mlm:.2f}; the chines wet at "
          f"{water_entry.wetting_time(0.2, beta, speed):.4f} s")
    start, rows = time.perf_counter(), []
    wet = water_entry.wetting_time(0.2, beta, speed)
    for t in np.linspace(wet / 20, wet, 20):
        solver.advance(float(t))
        force = wrench.sample()[0][1]
        rows.append((t, force / (1000.0 * wagner * speed ** 3 * t), force / (1000.0 * mlm * speed ** 3 * t)))
        print(f"t {t:.3f} s  F {force:8.1f} N/m  over Wagner {rows[-1][1]:.3f}  over MLM {rows[-1][2]:.3f}  "
              f"{time.perf_counter() - start:.0f} s", flush=True)
    r = np.array(rows)
    window = (r[:, 0] >= 0.27 * wet) & (r[:, 0] <= 0.82 * wet)
    print(f"mean over {0.27 * wet:.4f}-{0.82 * wet:.4f} s: {r[window, 1].mean():.3f} of Wagner's force, "
          f"{r[window, 2].mean():.3f} of the modified Logvinovich model's")


if __name__ == "__main__":
    main()
