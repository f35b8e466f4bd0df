"""The CUDA code of every kernel, built and read without a GPU (issue 67).

Steps, on Warp's CPU device, a set of small runs that together load every kernel the package
defines (RUNS: 2D and 3D, float32 and float64, every wall model, viscosity, shifting, zones, every
kind of body, sensors, gauges, blocks, the cloud, a checkpoint round trip, lists and cells), then
compiles each loaded Warp module for each --arch through Warp's NVRTC (PTX, no device needed) and
reads the PTX: float atomic adds or reductions (none may stand in the package's modules) and, in
the float32 builds, float64 arithmetic per kernel. Prints a table and writes it as CSV with --out.

Exit status 1 where a module fails to compile (its name and NVRTC's message printed), a kernel of
the package was never loaded by RUNS, a float atomic add stands in the package's PTX, or a kernel of
a float32 build does float64 arithmetic that ``cuda_build.F64_BY_DESIGN`` does not name.

    python bench/cuda_code.py [--arch 75 --arch 90] [--out docs/results/cuda_code.csv] [--jobs 2]

``--cache`` compiles to cubin into Warp's own kernel cache instead (for the GPU about to load them:
`make gpu-check`'s first step, which fails fast on a build error and leaves the later steps' kernels
built); ``--no-compile`` only checks that the runs load every kernel (the CPU rehearsal).

Registers per thread and spills need a cubin and a reader of its ELF notes (cuobjdump), which the
PyPI CUDA wheels here do not ship; PTX says neither, so they are not reported.
"""
import argparse
import concurrent.futures
import csv
import os
import sys
import tempfile
import time
from pathlib import Path

# a scene with every kind of body: floating, driven, prescribed (sinusoid), a cylinder
BODIES = {"name": "bodies", "dim": 2, "tank": [0.8, 0.4],
          "fluid": [{"name": "water", "lo": [0.1, 0], "hi": [0.8, 0.2]}],
          "obstacles": [{"name": "box", "lo": [0.3, 0.18], "hi": [0.4, 0.23], "displaces_fluid": True,
                         "floating": {"density": 500}},
                        {"name": "disc", "shape": "cylinder", "lo": [0.56, 0.16], "hi": [0.64, 0.24],
                         "displaces_fluid": True, "floating": {"density": 500}},
                        {"name": "paddle", "lo": [0.04, 0.0], "hi": [0.1, 0.4],
                         "motion": {"type": "sinusoid", "amplitude": [0.01, 0.0], "period": 0.5, "phase_deg": -90}}],
          # every kind of probe, sensors of both readings, a transducer with a response
          "probes": {"p": {"type": "point", "position": [0.5, 0.1]},
                     "c": {"type": "column", "position": [0.5]},
                     "u": {"type": "profile", "position": [0.5], "heights": [0.05, 0.1]},
                     "g": {"type": "gauge", "position": [0.5]},
                     "t": {"type": "gauge", "position": [0.7], "reading": "top"},
                     "s": {"type": "pressure_sensor", "position": [0.8, 0.05], "normal": [-1, 0], "diameter": 0.02,
                           "response": 0.001},
                     "r": {"type": "pressure_sensor", "position": [0.8, 0.1], "normal": [-1, 0], "diameter": 0.02,
                           "reading": "smoothed", "sampling": "step", "clip": False}}}
# (scene, settings): each run steps END s and takes a checkpoint round trip
RUNS = [
    ("dambreak1_lab_zoned", {"dx": 0.08}),
    ("dambreak1_lab", {"dx": 0.08, "neighbour_search": "cells", "precision": "float64"}),
    ("dambreak1_lab", {"dx": 0.08, "neighbour_search": "lists", "boundary": "mdbc", "viscosity": "sps",
                       "wall_flux": "normal"}),
    ("dambreak1_thesis", {"dx": 0.08, "boundary": "dynamic", "shifting": True, "xsph": True, "shepard_every": 5}),
    ("dambreak1_thesis", {"dx": 0.08, "boundary": "monaghan_kajtar", "viscosity": "laminar"}),
    ("dambreak1_thesis", {"dx": 0.06, "boundary": "lennard_jones"}),
    ("collapse_2d", {"dx": 0.04, "shifting": True, "cavitation": True}),
    # plane walls at this spacing gain energy from the release: the check is widened, the kernels are the point
    ("dambreak1_lab", {"dx": 0.06, "boundary": "dynamic", "wall_planes": True, "energy_growth_ratio": 10.0}),
    ("paddle_2d", {"dx": 0.08, "wrench_rate": 200.0}),
    (BODIES, {"dx": 0.04, "neighbour_search": "cells"}),
    (BODIES, {"dx": 0.04, "precision": "float64"}),
]
END = 0.03  # [s] simulated: enough to load the passes of a step, an output and a list rebuild


def load_every_kernel(runs=RUNS, end=END):
    """Step each of ``runs`` to ``end`` on the CPU, its outputs measured and a checkpoint restored."""
    import warp as wp

    from gpusph_ros.runner import Run
    from gpusph_ros.scenes.schema import load_scene, parse_scene
    from gpusph_ros.scenes.settings import resolve

    wp.config.quiet = True
    for scene, settings in runs:
        print(f"  {scene if isinstance(scene, str) else scene['name']} {settings}", flush=True)
        scene = load_scene(scene) if isinstance(scene, str) else parse_scene(scene)
        run = Run(scene, resolve(scene, end_time=max(end, 1.0 / 100.0), output_rate=100.0, particle_rate=100.0,
                                 device="cpu", **settings))
        while not run.done:
            run.step_output()
        run.restore(run.checkpoint())


def _compile(job):
    """(module name, arch, ptx text ("" into the cache) or None, error text, seconds) of one compile:
    run in a worker."""
    module, arch, out = job
    from gpusph_ros.sph.cuda_build import compile_cached, compile_ptx

    start = time.perf_counter()
    try:
        if out is None:
            compile_cached(module, arch)
            return module.name, arch, "", "", time.perf_counter() - start
        ptx = compile_ptx(module, arch, Path(out)).read_text()
        return module.name, arch, ptx, "", time.perf_counter() - start
    except RuntimeError as err:
        return module.name, arch, None, str(err), time.perf_counter() - start


def build_and_read(archs, jobs: int = 1, cache: bool = False) -> dict:
    """Load every kernel, compile every module of the package for ``archs`` (none: no compile; ``cache``:
    cubin into Warp's cache, unread), read the PTX: {rows, failures, unloaded, atomics, seconds}."""
    from gpusph_ros.sph import cuda_build

    start = time.perf_counter()
    load_every_kernel()
    loaded = time.perf_counter() - start
    modules = cuda_build.loaded_modules()
    unloaded = sorted(cuda_build.defined_kernels() - cuda_build.loaded_kernels(modules))
    out = None if cache else tempfile.mkdtemp(prefix="cuda_code_")
    work = [(m, arch, out) for m in modules for arch in archs]
    # compiles are independent; Warp's module objects are not picklable, so threads, which NVRTC
    # (a C library) runs side by side
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        results = list(pool.map(_compile, work))
    precision = {m.name: cuda_build.precision(m) for m in modules}
    rows, failures, atomics = [], [], []
    for name, arch, ptx, error, seconds in results:
        if ptx is None:
            failures.append(error)
            continue
        if not ptx:  # into the cache: built, not read
            continue
        atomics += [f"{name}: sm_{arch}: {line}" for line in cuda_build.float_atomic_adds(ptx)]
        counts = cuda_build.instructions(ptx)
        for kernel, f64 in cuda_build.f64_arithmetic(ptx).items():
            rows.append({"module": name, "precision": precision[name], "arch": arch,
                         "kernel": cuda_build.kernel_name(kernel), "instructions": counts[kernel],
                         "f64_arithmetic": f64, "compile_s": round(seconds, 2)})
    return {"rows": rows, "failures": failures, "unloaded": unloaded, "atomics": atomics, "modules": len(modules),
            "loaded_s": loaded, "compile_s": time.perf_counter() - start - loaded}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--arch", type=int, action="append", help="sm_ARCH (repeat); default: the oldest this "
                        "Warp's NVRTC builds for, and 90")
    parser.add_argument("--out", type=Path, help="a CSV of the rows")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--cache", action="store_true", help="cubin into Warp's kernel cache, not read")
    parser.add_argument("--no-compile", action="store_true", help="only check that the runs load every kernel")
    args = parser.parse_args()
    from gpusph_ros.sph.cuda_build import oldest_arch

    archs = [] if args.no_compile else (args.arch or sorted({oldest_arch(), 90}))
    found = build_and_read(archs, args.jobs, args.cache)
    rows = found["rows"]
    built = (f"compiled for {', '.join(f'sm_{a}' for a in archs)}{' into the cache' if args.cache else ''} in "
             f"{found['compile_s']:.0f} s ({args.jobs} at a time)" if archs else "not compiled (--no-compile)")
    print(f"{found['modules']} modules of the package loaded by {len(RUNS)} runs in {found['loaded_s']:.0f} s; {built}")
    from gpusph_ros.sph.cuda_build import F64_BY_DESIGN

    heavy = sorted((r for r in rows if r["precision"] == "float32" and r["f64_arithmetic"] and r["arch"] == archs[0]),
                   key=lambda r: -r["f64_arithmetic"])
    if rows:
        print(f"\nfloat64 arithmetic in float32 builds (sm_{archs[0]}), per kernel:")
        print("| kernel | f64 instructions | of all | why |\n| --- | --- | --- | --- |")
    for r in heavy:
        print(f"| {r['kernel']} | {r['f64_arithmetic']} | {r['instructions']} | "
              f"{F64_BY_DESIGN.get(r['kernel'], '**not by design**')} |")
    stray = sorted({r["kernel"] for r in heavy if r["kernel"] not in F64_BY_DESIGN})
    if args.out and rows:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        with open(args.out, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
    for text, items in (("failed to compile", found["failures"]), ("never loaded by the runs", found["unloaded"]),
                        ("float atomic adds", found["atomics"]),
                        ("kernels with float64 arithmetic in a float32 build, not in F64_BY_DESIGN", stray)):
        print(f"\n{len(items)} {text}" + "".join(f"\n  {item}" for item in items))
    return 1 if found["failures"] or found["unloaded"] or found["atomics"] or stray else 0


if __name__ == "__main__":
    sys.exit(main())
