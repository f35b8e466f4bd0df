"""The surge at DamBreak 1's velocity probe, converged: the 2d_until_reflection model (the x-z
section without the obstruction, scenes/reduce.py) run at each spacing until the obstruction's
reflection could reach the probe, and the peak x velocity there against the measured 2.21 m/s
(Yeh & Petroff). Prints one line per spacing: particles, steps, wall time, peak and its error.

    python bench/surge.py --dx 0.02 0.01 0.005 0.0025 [--set visco_bound_factor=0] [--threads 1]
"""
import argparse
import time

import warp as wp

MEASURED = 2.21  # [m/s] peak x velocity at the probe, Yeh & Petroff (data/yeh_petroff)


def peak_velocity(scene_name: str, dx: float, settings: dict, threads: int, rate: float = 500.0) -> dict:
    from gpusph_ros.runner import Run
    from gpusph_ros.scenes import reduce
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve

    scene = load_scene(scene_name)
    until = reduce.valid_until(scene)["velocity"]
    run = Run(scene, resolve(scene, dx=dx, model="2d_until_reflection", end_time=until, cpu_threads=threads,
                             **settings))
    start = time.perf_counter()
    peak, when, k = 0.0, 0.0, 1
    while k / rate <= until + 1e-12:
        run.solver.advance(k / rate)
        u = float(run.measurements.sample()["points"]["velocity"]["vel"][0])
        if u > peak:
            peak, when = u, k / rate
        k += 1
    return {"dx": dx, "particles": run.solver.n, "steps": run.solver.steps, "wall_s": time.perf_counter() - start,
            "valid_until": until, "peak": peak, "time": when, "excluded": run.solver.excluded_particles}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="dambreak1_lab")
    ap.add_argument("--dx", type=float, nargs="+", default=[0.02, 0.01, 0.005, 0.0025])
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a run setting")
    ap.add_argument("--threads", type=int, default=0, help="CPU threads (0 = every core)")
    args = ap.parse_args(argv)
    wp.config.log_level = wp.LOG_WARNING  # no per-module load lines
    from gpusph_ros.scenes.yaml_input import value

    settings = {key: value(text) for key, _, text in (item.partition("=") for item in args.set)}
    print(f"{args.scene}, 2d_until_reflection, settings {settings or 'default'}; measured peak {MEASURED} m/s")
    print(f"{'dx mm':>6} {'particles':>9} {'steps':>7} {'wall s':>8} {'valid to s':>10} {'peak m/s':>8} "
          f"{'at s':>6} {'error':>7} {'excl':>5}")
    for dx in args.dx:
        r = peak_velocity(args.scene, dx, settings, args.threads)
        print(f"{dx * 1000:>6.2f} {r['particles']:>9,} {r['steps']:>7,} {r['wall_s']:>8.1f} {r['valid_until']:>10.3f} "
              f"{r['peak']:>8.3f} {r['time']:>6.3f} {r['peak'] / MEASURED - 1:>+7.1%} {r['excluded']:>5}", flush=True)


if __name__ == "__main__":
    main()
