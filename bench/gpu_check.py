"""The GPU check (`make gpu-check`): everything this project has measured on a CPU, measured again
on the first CUDA device Warp sees, in one report file, in under 8 minutes on one GPU (the steps'
limits add up to 7 min 45 s).

1. the unit and physics tests with every solver on cuda:0 ($GPUSPH_ROS_DEVICE);
2. bench/solver.py on cuda:0 at about 10^5, 10^6 and 4x10^6 particles of DamBreak 1, float32 and
   float64 (MIPPS, neighbours, steps/s);
3. bench/node.py's cloud cost per output at about 10^6 particles on the GPU;
4. DamBreak 1 of the experiment (dambreak1_lab, 0.30 m column) at dx = 1 cm to t = 1 s with
   gpusph-run, and gpusph-analyze's table of it against Yeh & Petroff.

Each step has a time limit and its output goes into the report whatever happens; a step that
fails or runs out of time is marked so and the check exits 1. On a machine where Warp finds no
CUDA device it says so and exits 0, having checked nothing.

    python bench/gpu_check.py [--out runs/gpu-check] [--quick]

--quick shrinks every step (fewer tests, 10^5 particles only, 0.1 s of DamBreak 1) to check the
script itself.
"""
import argparse
import datetime
import os
import subprocess
import sys
import time
from pathlib import Path

import warp as wp

REPO = Path(__file__).resolve().parents[1]
BENCH = REPO / "bench"


def steps(quick: bool, out: Path) -> list:
    """(title, command, time limit [s]) of each step."""
    py = sys.executable
    bag = out / "dambreak1_lab_1cm"
    return [
        ("unit and physics tests on cuda:0",
         [py, "-m", "pytest", "-q", *(["-x"] if quick else []), "-m", "unit" if quick else "unit or physics",
          str(REPO / "tests")], 90 if quick else 180),
        ("solver throughput, DamBreak 1",
         [py, str(BENCH / "solver.py"), "--device", "cuda:0", "--particles",
          *(["1e5"] if quick else ["1e5", "1e6", "4e6"]), "--seconds", "2" if quick else "6"], 60 if quick else 120),
        ("cloud cost per output",
         [py, str(BENCH / "node.py"), "cloud", "--device", "cuda:0", "--particles", "1e5" if quick else "1e6"], 45),
        ("DamBreak 1 (0.30 m column) at 1 cm: run",
         [py, "-m", "gpusph_ros.cli", "run", "dambreak1_lab", "--set", "dx=0.01", "--set", "device=cuda:0",
          "--set", f"end_time={0.1 if quick else 1.0}", "--out", str(bag)], 60 if quick else 90),
        ("DamBreak 1 (0.30 m column) at 1 cm: analysis",
         [py, "-m", "gpusph_ros.cli", "analyze", str(bag)], 30),
    ]


def run_step(title: str, command: list, limit: float, env: dict) -> tuple:
    """(ok, wall seconds, output) of one step."""
    start = time.perf_counter()
    try:
        done = subprocess.run(command, cwd=REPO, env=env, capture_output=True, text=True, timeout=limit)
        ok, text = done.returncode == 0, done.stdout + done.stderr
        if not ok:
            text += f"\n[exit status {done.returncode}]"
    except subprocess.TimeoutExpired as err:
        ok = False
        text = ((err.stdout or b"").decode(errors="replace") + (err.stderr or b"").decode(errors="replace")
                + f"\n[stopped at its limit of {limit:.0f} s]")
    return ok, time.perf_counter() - start, text


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default=str(REPO / "runs" / "gpu-check"), help="report and recording folder")
    parser.add_argument("--quick", action="store_true", help="shrink every step, to check the script")
    args = parser.parse_args()
    wp.config.log_level = wp.LOG_WARNING
    if wp.get_cuda_device_count() == 0:
        print("gpu-check: Warp finds no CUDA device on this machine; nothing to check "
              f"(devices: {', '.join(d.alias for d in wp.get_devices())})")
        return 0
    gpu = wp.get_device("cuda:0")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    report = out / "report.md"
    env = {**os.environ, "GPUSPH_ROS_DEVICE": "cuda:0", "PYTHONUNBUFFERED": "1"}
    lines = [f"# gpu-check, {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC",
             "", f"GPU: {gpu.name} (cuda:0, {gpu.total_memory / 2**30:.1f} GiB), Warp {wp.config.version}, "
             f"Python {sys.version.split()[0]}, host {os.cpu_count()} CPU threads", ""]
    failed = []
    start = time.perf_counter()
    for title, command, limit in steps(args.quick, out):
        print(f"gpu-check: {title} (limit {limit} s) ...", flush=True)
        ok, wall, text = run_step(title, command, limit, env)
        print(f"gpu-check: {title}: {'ok' if ok else 'FAILED'} in {wall:.0f} s", flush=True)
        if not ok:
            failed.append(title)
        lines += [f"## {title}: {'ok' if ok else 'FAILED'} ({wall:.0f} s)", "",
                  "`" + " ".join(str(c).replace(str(REPO) + "/", "") for c in command) + "`", "",
                  "```", text.strip()[-20000:], "```", ""]
        report.write_text("\n".join(lines))  # what has run so far survives a later step's crash
    lines.append(f"total {time.perf_counter() - start:.0f} s; "
                 + (f"failed: {', '.join(failed)}" if failed else "every step passed"))
    report.write_text("\n".join(lines) + "\n")
    print(f"gpu-check: report in {report}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
