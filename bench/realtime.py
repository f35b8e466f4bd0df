"""What runs in real time on this machine (issue 57): for each case, the finest spacing at which the
node's run keeps a real-time factor of 1, with the particle cloud at 10 Hz and each body's wrench,
pose and twist at 200 Hz (``wrench_rate``), a controller commanding the driven body at each output.

    python bench/realtime.py [--cases paddle_2d box_3d] [--window 1.0] [--out docs/results/realtime.csv]

Cases: ``paddle_2d`` (the built-in 2D flume, 0.4 m of water, its piston paddle driven) and
``box_3d`` (a 3D tank 0.8 x 0.4 m with 0.2 m of water and a 0.2 m cube driven through its surface).
The run is built from the node's own parameters (``node_params.run_settings``: its defaults, the
cloud at each output), stepped headless, and every message of every output and wrench-rate time is
built and serialised as the node does before it publishes; the DDS publish itself is left out. The
controller commands a twist of 0.2 sin(pi t) m/s along x (the paddle) or z (the cube) at each output.

Each spacing is stepped WARM s first (kernels load, the loop is captured), then timed over
``--window`` s of simulated time, or until the wall time reaches 4 windows. The real-time factor is
simulated time over wall time: ``rtf`` with the messages, ``rtf_steps`` over the solver's steps
alone. Spacings run from coarse to fine and stop two after the last that holds 1. Rows go to the CSV
as each spacing ends.
"""
import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

from rclpy.serialization import serialize_message

BENCH = Path(__file__).resolve().parent
sys.path.insert(0, str(BENCH.parent))
from bench.csv_rows import append  # noqa: E402
from gpusph_ros.ros import node_params  # noqa: E402
from gpusph_ros.runner import Run  # noqa: E402

WARM = 0.1  # [s] simulated before the timing
CLOUD, WRENCH = 10.0, 200.0  # [Hz] simulated
BOX_3D = """name: box_3d
description: A 3D tank 0.8 x 0.4 m with 0.2 m of water and a 0.2 m cube driven through its surface.
dim: 3
tank: [0.8, 0.4, 0.4]
fluid:
  - {name: water, lo: [0.0, 0.0, 0.0], hi: [0.8, 0.4, 0.2]}
obstacles:
  - {name: cube, lo: [0.3, 0.1, 0.12], hi: [0.5, 0.3, 0.32], displaces_fluid: true,
     motion: {type: driven, max_speed: 0.5, max_acceleration: 5.0, timeout: 0.5}}
"""
# case: (scene, driven body, axis of its commanded twist, spacings coarse to fine [m])
CASES = {"paddle_2d": ("paddle_2d", "paddle", 0, (0.1, 0.09, 0.08, 0.07, 0.06, 0.05, 0.04, 0.03, 0.02)),
         "box_3d": (None, "cube", 2, (0.1, 0.09, 0.08, 0.07, 0.06, 0.05, 0.04, 0.03))}


def trial(scene: str, body: str, axis: int, dx: float, window: float) -> dict:
    values = {**node_params.DEFAULTS, "scene": scene, "dx": dx, "output_rate": CLOUD, "wrench_rate": WRENCH,
              "end_time": WARM + window}
    run = Run(*node_params.run_settings(values))
    twist = [0.0, 0.0, 0.0]

    def command():
        twist[axis] = 0.2 * math.sin(math.pi * run.solver.time)
        taken, why = run.command(body, "twist", run.solver.time, twist, (0.0, 0.0, 0.0))
        assert taken, why

    def step() -> int:
        k = run.next_output
        size = sum(len(serialize_message(msg)) for _, msg in run.step_output())
        if run.next_output != k:
            command()
        return size

    command()
    while run.solver.time < WARM - 1e-9:
        step()
    t0, steps0, wall0, start, sent = run.solver.time, run.solver.steps, run.wall, time.perf_counter(), 0
    while not run.done and time.perf_counter() - start < 4.0 * window:
        sent += step()
    wall, simulated = time.perf_counter() - start, run.solver.time - t0
    return {"dx": dx, "particles": run.solver.n, "fluid": run.model.fluid_particles,
            "steps": run.solver.steps - steps0, "simulated_s": round(simulated, 6), "wall_s": round(wall, 3),
            "steps_per_s": round((run.solver.steps - steps0) / wall, 1), "rtf": round(simulated / wall, 3),
            "rtf_steps": round(simulated / (run.wall - wall0), 3), "bytes_per_s": round(sent / simulated)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    parser.add_argument("--window", type=float, default=1.0, help="[s] simulated, timed at each spacing")
    parser.add_argument("--out", type=Path, default=BENCH.parent / "docs" / "results" / "realtime.csv")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        for case in args.cases:
            scene, body, axis, spacings = CASES[case]
            if scene is None:
                scene = str(Path(folder) / f"{case}.yaml")
                Path(scene).write_text(BOX_3D)
            finest, misses = None, 0
            for dx in spacings:
                row = {"case": case, **trial(scene, body, axis, dx, args.window)}
                append(args.out, row)
                print(", ".join(f"{k} {v}" for k, v in row.items()), flush=True)
                if row["rtf"] >= 1.0:
                    finest, misses = dx, 0
                else:
                    misses += 1
                    if misses == 2:
                        break
            print(f"{case}: the finest spacing that holds real time here: "
                  f"{'none of ' + str(spacings) if finest is None else f'{finest:g} m'}", flush=True)


if __name__ == "__main__":
    main()
