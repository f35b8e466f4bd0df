"""The GPU check (`make gpu-check`): everything this project has measured on a CPU, measured again
on the first CUDA device Warp sees, in one report file, in about 10 minutes on one GPU (the steps'
limits add up to 11 min 10 s; the first builds the kernels the others would build).

0. bench/cuda_code.py: every kernel of the package compiled for the GPU's architecture through
   Warp's NVRTC into Warp's cache (a build error fails here, first);
1. the unit and physics tests with every solver on cuda:0 ($GPUSPH_ROS_DEVICE);
2. bench/step_counts.py on cuda:0: launches, sorts, fills, copies and host reads of each kind of
   step, the host's syncs per output, and the step loop eager against replayed from its captured
   graph (sph/graph.py), at about 10^5 particles;
3. bench/repeat.py on cuda:0: the same run twice, bit for bit (DamBreak 1 with dynamic and Adami
   walls, in its zone under multirate, and with a floating box; 2 cm, 0.1 s), digests compared;
4. bench/solver.py on cuda:0 at about 10^5, 10^6, 4x10^6 and 10^7 particles of DamBreak 1, float32
   and float64 (MIPPS, neighbours, steps/s); a size the GPU's memory cannot hold is refused by the
   build, named in the output, and the others go on; then at 10^6, float32, with neighbour lists
   against walking the cells (the GPU's default, chosen for its memory: sph/neighbours.py);
5. bench/node.py's cloud cost per output at about 10^6 particles on the GPU;
6. DamBreak 1 of the experiment (dambreak1_lab, 0.30 m column) at dx = 1 cm to t = 1 s with
   gpusph-run, its real-time factor (wall time over simulated time, start-up included), and
   gpusph-analyze's table of it against Yeh & Petroff.

Each step has a time limit and its output goes into the report whatever happens; a step that
fails or runs out of time is marked so and the check exits 1. On a machine where Warp finds no
CUDA device it says so and exits 0, having checked nothing.

    python bench/gpu_check.py [--out runs/gpu-check] [--cpu]

--cpu rehearses the same report on Warp's CPU device (`make gpu-check-cpu`), every step shrunk so
that it takes under 3 minutes: the script itself checked where no GPU is.
"""
import argparse
import datetime
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import warp as wp

REPO = Path(__file__).resolve().parents[1]
BENCH = REPO / "bench"


def steps(device: str, out: Path) -> list:
    """(title, command, time limit [s]) of each step; on "cpu", the rehearsal's shrunk ones."""
    py = sys.executable
    cpu = device == "cpu"
    dx, end = ("0.03", 0.05) if cpu else ("0.01", 1.0)
    bag = out / f"dambreak1_lab_{float(dx) * 100:g}cm"
    tests = ["tests/test_graph.py", "tests/test_step_counts.py"] if cpu else ["-m", "unit or physics", "tests"]
    arch = None if cpu else wp.get_device(device).arch
    return [
        # first: a build error fails here in a minute, not after the tests; on the GPU the cubins go
        # into Warp's cache, where the later steps find them built
        ("the CUDA build of every kernel" + ("" if cpu else f" (sm_{arch})"),
         [py, str(BENCH / "cuda_code.py"), *(["--no-compile"] if cpu else ["--arch", str(arch), "--cache"])],
         120 if cpu else 90),
        (f"{'the step-loop tests' if cpu else 'unit and physics tests'} on {device}",
         [py, "-m", "pytest", "-q", *tests], 60 if cpu else 150),
        ("what a step asks of the device; eager against replayed",
         [py, str(BENCH / "step_counts.py"), "--device", device, "--dx", "0.03" if cpu else "0.015",
          "--span", "0.02" if cpu else "0.1"], 60),
        ("the same run twice, bit for bit",
         [py, str(BENCH / "repeat.py"), "--device", device, "--dx", "0.05" if cpu else "0.02",
          "--end", "0.02" if cpu else "0.1"], 60),
        ("solver throughput, DamBreak 1",
         [py, str(BENCH / "solver.py"), "--device", device, "--particles",
          *(["1e4"] if cpu else ["1e5", "1e6", "4e6", "1e7"]), "--seconds", "1" if cpu else "3"],
         45 if cpu else 120),
        ("neighbour lists against walking the cells, DamBreak 1",
         [py, str(BENCH / "solver.py"), "--device", device, "--particles", "1e4" if cpu else "1e6",
          "--precision", "float32", "--search", "lists", "cells", "--seconds", "1" if cpu else "3"], 30),
        ("cloud cost per output",
         [py, str(BENCH / "node.py"), "cloud", "--device", device, "--particles", "1e4" if cpu else "1e6"], 40),
        (f"DamBreak 1 (0.30 m column) at {float(dx) * 100:g} cm: run",
         [py, "-m", "gpusph_ros.cli", "run", "dambreak1_lab", "--set", f"dx={dx}", "--set", f"device={device}",
          "--set", f"end_time={end}", "--out", str(bag)], 60 if cpu else 90),
        (f"DamBreak 1 (0.30 m column) at {float(dx) * 100:g} cm: analysis",
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
    parser.add_argument("--cpu", action="store_true", help="rehearse the report on the CPU, every step shrunk")
    args = parser.parse_args()
    wp.config.log_level = wp.LOG_WARNING
    if not args.cpu and wp.get_cuda_device_count() == 0:
        print("gpu-check: Warp finds no CUDA device on this machine; nothing to check "
              f"(devices: {', '.join(d.alias for d in wp.get_devices())}; --cpu rehearses the report on the CPU)")
        return 0
    device = "cpu" if args.cpu else "cuda:0"
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    report = out / "report.md"
    env = {**os.environ, "GPUSPH_ROS_DEVICE": device, "PYTHONUNBUFFERED": "1"}
    if args.cpu:
        from gpusph_ros.sph.launch import usable_cores

        machine = f"CPU rehearsal (Warp's cpu device, {usable_cores()} threads): no GPU figure below"
    else:
        gpu = wp.get_device(device)
        machine = f"GPU: {gpu.name} ({device}, {gpu.total_memory / 2**30:.1f} GiB), host {os.cpu_count()} CPU threads"
    lines = [f"# gpu-check, {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC",
             "", f"{machine}, Warp {wp.config.version}, Python {sys.version.split()[0]}", ""]
    failed = []
    start = time.perf_counter()
    for title, command, limit in steps(device, out):
        if "--out" in command:  # the run's recording of an earlier check: gpusph-run refuses to write over it
            shutil.rmtree(command[command.index("--out") + 1], ignore_errors=True)
        print(f"gpu-check: {title} (limit {limit} s) ...", flush=True)
        ok, wall, text = run_step(title, command, limit, env)
        print(f"gpu-check: {title}: {'ok' if ok else 'FAILED'} in {wall:.0f} s", flush=True)
        if not ok:
            failed.append(title)
        if ok and title.endswith(": run"):
            end = float(next(c for c in command if str(c).startswith("end_time=")).split("=")[1])
            text += f"\n\nreal-time factor: {wall / end:.1f} s of wall time a simulated second (start-up included)"
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
