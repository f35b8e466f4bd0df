"""The CUDA build read without a GPU (sph/cuda_build.py, bench/cuda_code.py; issue 67).

- The PTX readers against known PTX: a float atomic add or reduction in any form is found, an
  integer one or a float atomic max is not; float64 arithmetic is counted per kernel, loads and
  stores of float64 data are not; instructions are counted per kernel, directives and labels not;
  a Warp entry name gives its function's name.
- A deliberately added kernel with a float atomic add, compiled for the oldest architecture this
  Warp's NVRTC builds for, is found in its PTX (the check can fail), and one without is clean.
- Every kernel the package's source defines is loaded by bench/cuda_code.py's runs (so that none
  escapes the build), and every Warp module that holds one compiles for CUDA, for the oldest
  architecture this Warp's NVRTC builds for (sm_75, where a build fails first), with no float
  atomic add in its PTX. sm_90 is `make cuda-check`'s (bench/cuda_code.py) and `make gpu-check`'s on
  the device's own architecture: about a minute of one core an architecture, the suite builds one.
"""
import sys

import pytest
import warp as wp

from gpusph_ros.sph import cuda_build

from conftest import REPO

PTX = """
.visible .entry sums_kernel(
	.param .u64 sums_kernel_param_0
)
{
	ld.global.f64 	%fd1, [%rd1];
	st.global.f64 	[%rd2], %fd1;
	atom.global.add.u32 	%r1, [%rd3], 1;
	atom.global.max.s32 	%r2, [%rd3], %r1;
	atom.global.add.f32 	%f2, [%rd4], %f1;
	red.global.add.f64 	[%rd5], %fd1;
	@%p1 red.global.gpu.add.noftz.f16 	[%rd6], %h1;
	add.f64 	%fd2, %fd1, %fd1;
}
.visible .entry plain_kernel(
	.param .u64 plain_kernel_param_0
)
{
	cvt.f64.f32 	%fd3, %f1;
	fma.rn.f64 	%fd4, %fd3, %fd3, %fd3;
	cvt.rn.f32.f64 	%f3, %fd4;
	@!%p2 setp.lt.f64 	%p3, %fd4, %fd3;
	add.f32 	%f4, %f3, %f3;
	mov.f64 	%fd5, %fd4;
}
"""


@pytest.mark.unit
def test_the_ptx_readers_find_float_atomic_adds_and_count_f64_arithmetic_per_kernel():
    found = [" ".join(line.split()[:2]) for line in cuda_build.float_atomic_adds(PTX)]
    assert found == ["atom.global.add.f32 %f2,", "red.global.add.f64 [%rd5],", "@%p1 red.global.gpu.add.noftz.f16"]
    assert cuda_build.f64_arithmetic(PTX) == {"sums_kernel": 1, "plain_kernel": 4}
    assert cuda_build.instructions(PTX) == {"sums_kernel": 8, "plain_kernel": 6}
    assert cuda_build.kernel_name("_time_passes__locals__choose_dt_fd3bd171_cuda_kernel_forward") == "choose_dt"
    assert cuda_build.kernel_name("build__locals__move_walls_b7db018d_cuda_kernel_forward") == "move_walls"


@wp.kernel(enable_backward=False, module="unique")
def _float_atomic_add(x: wp.array(dtype=wp.float32), total: wp.array(dtype=wp.float32)):
    wp.atomic_add(total, 0, x[wp.tid()])


@wp.kernel(enable_backward=False, module="unique")
def _integer_atomic_add(x: wp.array(dtype=wp.int32), total: wp.array(dtype=wp.int32)):
    wp.atomic_add(total, 0, x[wp.tid()])


@pytest.mark.physics
def test_a_float_atomic_add_is_found_in_the_cuda_build_and_an_integer_one_is_not(tmp_path):
    arch = cuda_build.oldest_arch()
    assert arch == min(cuda_build.nvrtc_archs())
    found = {}
    for kernel in (_float_atomic_add, _integer_atomic_add):
        ptx = cuda_build.compile_ptx(kernel.module, arch, tmp_path).read_text()
        found[kernel.key] = cuda_build.float_atomic_adds(ptx)
    assert found[_float_atomic_add.key] and all(".add.f32" in line for line in found[_float_atomic_add.key])
    assert found[_integer_atomic_add.key] == []


@pytest.mark.physics
def test_every_kernel_compiles_for_cuda_without_float_atomics_or_stray_float64(tmp_path):
    """bench/cuda_code.py's runs load every kernel the package defines; each Warp module that holds
    one compiles through NVRTC to PTX for the oldest architecture this Warp builds for, as a GPU
    would build it (Warp's default -O3: about 50 s on one core). No PTX of the
    package holds a float atomic add, and no kernel of a float32 build does float64 arithmetic but
    those cuda_build.F64_BY_DESIGN names, with the reason (issue 67: the corrected density's
    solve did, through Warp's 4 x 4 inverse)."""
    sys.path.insert(0, str(REPO / "bench"))
    import cuda_code

    arch = cuda_build.oldest_arch()
    defined = cuda_build.defined_kernels()
    assert len(defined) >= 59 and ("sph/passes.py", "interact") in defined
    if defined - cuda_build.loaded_kernels(cuda_build.loaded_modules()):  # not yet in this worker
        cuda_code.load_every_kernel()
    modules = cuda_build.loaded_modules()
    assert defined - cuda_build.loaded_kernels(modules) == set()
    failures, atomics, f64 = [], [], []
    for module in modules:
        try:
            ptx = cuda_build.compile_ptx(module, arch, tmp_path).read_text()
        except RuntimeError as err:
            failures.append(str(err))
            continue
        atomics += [f"{module.name}: {line}" for line in cuda_build.float_atomic_adds(ptx)]
        if cuda_build.precision(module) == "float32":
            f64 += [f"{cuda_build.kernel_name(k)}: {n}" for k, n in cuda_build.f64_arithmetic(ptx).items()
                    if n and cuda_build.kernel_name(k) not in cuda_build.F64_BY_DESIGN]
    assert failures == [] and atomics == [] and f64 == []
