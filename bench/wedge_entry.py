"""A 2D wedge entering still water at constant speed against Wagner's theory (Wagner 1932; as
Faltinsen 2005, Hydrodynamics of High-Speed Marine Vehicles, Ch. 8): a wedge of deadrise beta, apex at
the surface at t = 0, driven down at V (motion translate); before its chines wet, the vertical force
per unit length is F = rho pi^3 V^3 t / (4 tan^2 beta) (the wetted half-width c = pi V t / (2 tan beta),
the flat plate's added mass rho pi c^2 / 2). Prints the force on the wedge's particles (the mean over
the steps since the last sample) against it every 5 ms, and the mean ratio over 0.02-0.06 s.

    python bench/wedge_entry.py 0.01 [boundary=dynamic ...]   # dx [m], then solver settings
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

    wp.config.log_level = wp.LOG_WARNING
    dx = float(sys.argv[1]) if len(sys.argv) > 1 else 0.01
    settings = {k: value(v) for k, _, v in (a.partition("=") for a in sys.argv[2:])}
    beta, speed = 30.0, 1.0
    top = 0.3 + 0.2 * math.tan(math.radians(beta))
    scene = parse_scene({"name": "wedge", "dim": 2, "tank": [1.0, 0.6],
                         "fluid": [{"name": "water", "lo": [0, 0], "hi": [1.0, 0.3]}],
                         "obstacles": [{"name": "wedge", "lo": [0.3, 0.3], "hi": [0.7, top], "shape": "wedge",
                                        "deadrise_deg": beta, "motion": {"type": "translate",
                                                                         "velocity": [0.0, -speed]}}]})
    solver = Solver(*(lambda m: (m.config, m.particles))(build(scene, dx=dx, **settings)))
    wrench = BodyWrench(solver, 0)
    coef = math.pi ** 3 / (4 * math.tan(math.radians(beta)) ** 2)
    print(f"wedge {beta:g} deg at {speed} m/s, dx = {dx} m, {solver.n} particles, {settings}; Wagner F / (rho V^3 t) "
          f"= {coef:.2f}; the chines wet at {0.2 * math.tan(math.radians(beta)) / (math.pi / 2 * speed):.4f} s")
    start, rows = time.perf_counter(), []
    for t in np.arange(0.005, 0.0701, 0.005):
        solver.advance(float(t))
        force = wrench.sample()[0][1]
        rows.append((t, force, force / (1000.0 * coef * speed ** 3 * t)))
        print(f"t {t:.3f} s  F {force:8.1f} N/m  Wagner {1000 * coef * speed ** 3 * t:8.1f}  ratio {rows[-1][2]:.3f}  "
              f"{time.perf_counter() - start:.0f} s", flush=True)
    r = np.array(rows)
    window = (r[:, 0] >= 0.02) & (r[:, 0] <= 0.06)
    print(f"mean ratio over 0.02-0.06 s: {r[window, 2].mean():.3f}")


if __name__ == "__main__":
    main()
