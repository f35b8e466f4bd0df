"""The CUDA build of the package's kernels, made and read on a machine with no GPU.

Warp compiles a module for a CUDA architecture through its NVRTC without a device
(``wp.compile_aot_module(module, arch=A, use_ptx=True)``). This module finds the Warp modules that
hold the package's kernels once a run has loaded them, compiles each to PTX, and reads the PTX for
what a GPU punishes: a float atomic add or reduction (its sum's bits follow the threads' order,
which the fixed-order sums of ``sums.py`` exist to avoid) and float64 arithmetic in a float32 build
(half the float32 rate on an H100, 1/64 on the RTX cards many users have).

``defined_kernels`` reads the package's source for every ``@wp.kernel``, so that a check can say
which kernels a set of runs never loaded (a kernel that no run loads is never compiled here).
"""
import ast
import re
from pathlib import Path

import warp as wp

PACKAGE = Path(__file__).resolve().parents[1]
# atom/red .add on a float type, at any scope or state space (atom.global.add.f32,
# red.global.gpu.add.noftz.f16, atom.shared.add.f64, ...)
FLOAT_ATOMIC_ADD = re.compile(r"\b(?:atom|red)(?:\.[a-z]+)*\.add(?:\.noftz)?\.(?:f16|bf16|f32|f64)\b")
# float64 arithmetic: an operation on .f64 operands, or a conversion to or from f64 (a load, store
# or move of a float64 value is data, not arithmetic: a clock's time is float64 in every build)
F64_ARITHMETIC = re.compile(
    r"^\s*(?:@!?%p\d+\s+)?(?:add|sub|mul|fma|mad|div|rcp|sqrt|rsqrt|abs|neg|min|max|setp|selp|testp|copysign|"
    r"ex2|lg2|sin|cos)(?:\.[a-z0-9]+)*\.f64\b|^\s*(?:@!?%p\d+\s+)?cvt(?:\.[a-z0-9]+)*\.f64\.|"
    r"^\s*(?:@!?%p\d+\s+)?cvt(?:\.[a-z0-9]+)*\.[a-z0-9]+\.f64\b", re.M)
ENTRY = re.compile(r"^\s*\.(?:visible\s+)?\.entry\s+([A-Za-z_][A-Za-z0-9_]*)", re.M)
# an instruction line of a kernel's body (not a directive, a label, a brace or a declaration)
INSTRUCTION = re.compile(r"^\s*(?:@!?%p\d+\s+)?[a-z][a-z0-9]*(?:\.[a-z0-9_]+)*(?:\s[^;]*)?;")
# the function's name in the entry Warp gives a kernel: <scope>__locals__<name>_<hash>_cuda_kernel_forward
WARP_ENTRY = re.compile(r"^(.+)_[0-9a-f]{8}_cuda_kernel_forward$")

# float64 arithmetic a float32 build keeps, by kernel, and why (docs/results/cuda_code.md has each
# kernel's count against its instructions): time is float64 in every build so that the clock lands on
# output times; sums of many terms accumulate in float64 in a fixed order (sums.py); a rigid body's
# pose is float64 (it integrates over the whole run). None of these does float64 work on more than a
# body's particles, a sensor's thread or one thread, but for the clock's step read in integrate and
# check_displacement (the same two to four instructions in every thread) and the census's sums,
# every 16 steps.
F64_BY_DESIGN = {
    "choose_dt": "the step and the clock, one thread a step",
    "integrate": "the clock read and compared (uniform: the same four instructions in every thread)",
    "move_walls": "a moving body's pose, on its particles only",
    "wrench_terms": "a floating body's particle's force and torque in float64, on its particles only",
    "wrench_sums": "a floating body's force and torque summed in float64, over its particles' rows only",
    "add_into": "a step's work of the moving bodies added to the run's, one thread",
    "work_on_fluid": "the work of moving bodies summed in float64, on their particles only",
    "wrench_part": "a body's wrench summed in float64 for the published wrench (an output, not a step)",
    "census": "the fluid's energy summed in float64, every 16 steps",
    "wall_energy": "the repulsive walls' energy summed in float64, with the census",
    "check_particles": "an excluded particle's mass counted in integer units, on excluded particles only",
    "check_displacement": "the clock's step read (uniform: the same two instructions in every thread)",
    "transduce": "a sensor's face mean and response in float64, one thread a sensor",
    "census_check": "the census's totals, one thread",
    "exclusion_check": "the excluded mass's totals and the time of the first, one thread a step",
    "tick": "the clock advanced, one thread a step",
}


def nvrtc_archs() -> list:
    """The CUDA architectures (75 for sm_75, ...) this Warp's NVRTC builds for, oldest first."""
    wp.init()
    from warp._src.context import runtime  # Warp keeps the list on its runtime, not in its API

    return sorted(runtime.nvrtc_supported_archs)


def oldest_arch() -> int:
    """The oldest architecture this Warp's NVRTC builds for (75 with Warp 1.19)."""
    archs = nvrtc_archs()
    if not archs:
        raise RuntimeError("this Warp has no NVRTC: no CUDA build can be made on this machine")
    return archs[0]


def _kernels_in(path: Path) -> list:
    """The names of the functions decorated ``@wp.kernel`` (any form of the decorator) in ``path``."""
    tree = ast.parse(path.read_text(), str(path))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and any(
                ast.unparse(d.func if isinstance(d, ast.Call) else d) == "wp.kernel" for d in node.decorator_list):
            out.append(node.name)
    return out


def defined_kernels() -> set:
    """{(file relative to the package, kernel name)} of every kernel the package's source defines."""
    return {(str(path.relative_to(PACKAGE)), name) for path in sorted(PACKAGE.rglob("*.py"))
            for name in _kernels_in(path)}


def _ours(kernel) -> "tuple | None":
    file = getattr(getattr(kernel.func, "__code__", None), "co_filename", "")
    try:
        return str(Path(file).resolve().relative_to(PACKAGE)), kernel.func.__name__
    except ValueError:
        return None


def loaded_modules() -> list:
    """The Warp modules loaded in this process that hold a kernel of the package, by name."""
    from warp._src.context import user_modules

    return sorted((m for m in user_modules.values() if any(_ours(k) for k in _module_kernels(m))),
                  key=lambda m: m.name)


def _module_kernels(module) -> list:
    kernels = module.kernels
    return list(kernels.values()) if isinstance(kernels, dict) else list(kernels)


def loaded_kernels(modules) -> set:
    """{(file, kernel name)} of the package's kernels in ``modules``."""
    return {key for m in modules for k in _module_kernels(m) if (key := _ours(k))}


def compile_ptx(module, arch: int, out_dir: Path) -> Path:
    """``module`` compiled for sm_``arch`` to PTX under ``out_dir``; RuntimeError with NVRTC's
    message where it fails."""
    try:
        paths = wp.compile_aot_module(module, arch=arch, module_dir=str(out_dir), use_ptx=True)
    except Exception as err:  # Warp raises what NVRTC said as it likes: said here with the module
        raise RuntimeError(f"{module.name}: sm_{arch}: {type(err).__name__}: {err}") from None
    ptx = [Path(p) for p in paths if str(p).endswith(".ptx")]
    if not ptx:
        raise RuntimeError(f"{module.name}: sm_{arch}: Warp wrote no PTX ({', '.join(map(str, paths))})")
    return ptx[0]


def compile_cached(module, arch: int):
    """``module`` compiled for sm_``arch`` to cubin into Warp's own kernel cache, where a device of
    that architecture finds it when it loads the module; RuntimeError with NVRTC's message."""
    try:
        wp.compile_aot_module(module, arch=arch, use_ptx=False)
    except Exception as err:
        raise RuntimeError(f"{module.name}: sm_{arch}: {type(err).__name__}: {err}") from None


def float_atomic_adds(ptx: str) -> list:
    """The float atomic adds and reductions in a PTX text, one line each."""
    return [line.strip() for line in ptx.splitlines() if FLOAT_ATOMIC_ADD.search(line)]


def kernel_name(entry: str) -> str:
    """The function's name in a PTX entry name of Warp's (``entry`` itself where not Warp's)."""
    found = WARP_ENTRY.match(entry)
    return found.group(1).rsplit("__locals__", 1)[-1] if found else entry


def precision(module) -> str:
    """float32 or float64: the ``scalar`` a kernel of ``module`` was built with (the factory's
    argument, read from the kernel function's closure), else the scalar of most of its kernels'
    floating-point arguments (struct fields included); "-" where none says."""
    for kernel in _module_kernels(module):
        func = kernel.func
        cells = dict(zip(func.__code__.co_freevars, (c.cell_contents for c in func.__closure__ or ())))
        if cells.get("scalar") in (wp.float32, wp.float64):
            return cells["scalar"].__name__

    def scalars(t):
        if hasattr(t, "vars"):  # a struct
            for var in t.vars.values():
                yield from scalars(var.type)
            return
        dtype = getattr(t, "dtype", t)
        scalar = getattr(dtype, "_wp_scalar_type_", dtype)
        if scalar in (wp.float32, wp.float64):
            yield scalar.__name__

    found = [s for kernel in _module_kernels(module) for arg in kernel.adj.args for s in scalars(arg.type)]
    if not found:
        return "-"
    return max(("float32", "float64"), key=found.count)


def _per_kernel(ptx: str, pattern) -> dict:
    """{entry (kernel) name: lines of its body that ``pattern`` matches} of a PTX text."""
    out, name = {}, None
    for line in ptx.splitlines():
        entry = ENTRY.match(line)
        if entry:
            name = entry.group(1)
            out[name] = 0
        elif name is not None and pattern.match(line):
            out[name] += 1
    return out


def instructions(ptx: str) -> dict:
    """{entry (kernel) name: instructions in it} of a PTX text."""
    return _per_kernel(ptx, INSTRUCTION)


def f64_arithmetic(ptx: str) -> dict:
    """{entry (kernel) name: float64 arithmetic instructions in it} of a PTX text."""
    return _per_kernel(ptx, F64_ARITHMETIC)
