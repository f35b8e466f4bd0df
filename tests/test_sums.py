"""Fixed-order sums and the allocation-free scan (sph/sums.py, sph/scan.py) against exact answers,
and the strict CPU mode (sph/device_calls.strict) refusing what CUDA refuses inside a capture."""
import math

import numpy as np
import pytest
import warp as wp

from gpusph_ros.sph import sums
from gpusph_ros.sph.device_calls import GpuRefusal, strict
from gpusph_ros.sph.scan import SPAN as SCAN_SPAN
from gpusph_ros.sph.scan import Scan
from gpusph_ros.sph.scan import sizes as scan_sizes

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("cuda", [False, True])
@pytest.mark.parametrize("n", [0, 1, 2, SCAN_SPAN - 1, SCAN_SPAN, SCAN_SPAN + 1, SCAN_SPAN ** 2 + 1, 200_003])
def test_the_scan_is_numpys_exclusive_cumulative_sum(n, cuda):
    # 1, 2 and 3 levels of blocks on a CPU, up to 6 in a GPU's layout (run here on the CPU)
    values = np.random.default_rng(n).integers(0, 9, n).astype(np.int32)
    out = wp.full(n, -1, dtype=wp.int32, device="cpu")
    Scan(n, "cpu", cuda=cuda)(wp.array(values, dtype=wp.int32, device="cpu"), out)
    assert np.array_equal(out.numpy(), np.concatenate([[0], np.cumsum(values)[:-1]]).astype(np.int32)[:n])


def test_a_gpu_sums_and_scans_with_at_least_1e5_threads_at_a_million_particles():
    """Issue 67: one thread per 256 particles ran 3,907 threads at 10^6 particles, where a GPU needs
    tens of thousands in flight; a CPU keeps its layout (and so its sums, bit for bit)."""
    gpu, cpu = sums.layout(10 ** 6, cuda=True), sums.layout(10 ** 6, cuda=False)
    assert gpu["threads"][0] == 125_000 and gpu["rows"] == [125_000, 489, 2]  # the tree's levels, then total
    assert (cpu["count"], cpu["lead"], cpu["step"], cpu["span"], cpu["rows"]) == (3907, 256, 1, 256, [3907])
    gpu_scan, cpu_scan = scan_sizes(10 ** 6, cuda=True), scan_sizes(10 ** 6, cuda=False)
    assert gpu_scan[1] == 125_000 and len(gpu_scan) == 8  # 7 levels
    assert cpu_scan == [10 ** 6, 3907, 16, 1]


@pytest.mark.parametrize("n", [1, 255, 256, 257, 10_000])
@pytest.mark.parametrize("cuda", [False, True])
def test_every_particle_is_in_exactly_one_block(n, cuda):
    # both layouts, the GPU's too, as arithmetic: block k's j-th member is k lead + j step
    cut = sums.layout(n, cuda)
    k, j = np.meshgrid(np.arange(cut["count"]), np.arange(cut["span"]), indexing="ij")
    members = (k * cut["lead"] + j * cut["step"]).ravel()
    assert np.array_equal(np.sort(members[members < n]), np.arange(n))


@wp.kernel(enable_backward=False)
def _slot_sums(values: wp.array(dtype=wp.float64), part: wp.array2d(dtype=wp.float64), lead: int, step: int,
               members: int):
    k = wp.tid()
    for s in range(part.shape[1]):
        part[k, s] = wp.float64(0.0)
    for j in range(members):
        i = sums.member(k, j, lead, step)
        if i < values.shape[0]:
            part[k, i % 3] = part[k, i % 3] + values[i]


@pytest.mark.parametrize("n, cuda", [(5000, False), (5000, True), (600_000, True)])
def test_partial_sums_add_to_the_exact_totals(n, cuda):
    # the GPU's layout on the CPU device: 5,000 particles in one level of block sums, 600,000 in a
    # tree of three (75,000 -> 293 -> 2 rows)
    values = np.arange(n, dtype=np.float64)  # integers: every order sums them exactly
    part = sums.Partials(n, 3, wp.float64, "cpu", cuda=cuda)
    wp.launch(_slot_sums, dim=part.count, inputs=[wp.array(values, dtype=wp.float64), *part.args()], device="cpu")
    out = wp.array([1.0, 2.0, 3.0, 4.0], dtype=wp.float64, device="cpu")
    part.total(out, offset=1, add=True)
    expected = [values[values % 3 == s].sum() for s in range(3)]
    assert out.numpy().tolist() == [1.0, 2.0 + expected[0], 3.0 + expected[1], 4.0 + expected[2]]
    part.total(out)
    assert out.numpy().tolist() == expected + [4.0 + expected[2]]


def test_the_gpu_layouts_float_sums_repeat_bit_for_bit_and_stay_within_rounding():
    """Floats in the GPU's layout (on the CPU device): the same sums twice, bit for bit, and within
    1e-12 of the exactly rounded sums (math.fsum) of 200,000 terms each."""
    n = 600_000
    values = np.random.default_rng(3).random(n)
    got = []
    for _ in range(2):
        part = sums.Partials(n, 3, wp.float64, "cpu", cuda=True)
        wp.launch(_slot_sums, dim=part.count, inputs=[wp.array(values, dtype=wp.float64), *part.args()], device="cpu")
        out = wp.zeros(3, dtype=wp.float64, device="cpu")
        part.total(out)
        got.append(out.numpy())
    assert np.array_equal(got[0], got[1])
    idx = np.arange(n)
    expected = [math.fsum(values[idx % 3 == s]) for s in range(3)]
    assert np.allclose(got[0], expected, rtol=1e-12, atol=0.0)


def test_strict_mode_refuses_inside_a_captured_region_what_cuda_refuses_there():
    flag = wp.ones(1, dtype=wp.int32, device="cpu")
    src, dst = wp.zeros(8, dtype=wp.int32, device="cpu"), wp.zeros(8, dtype=wp.int32, device="cpu")
    attempts = {"an allocation": lambda: wp.zeros(4, dtype=wp.float32, device="cpu"),
                "a Warp utility": lambda: wp.utils.array_scan(src, dst, inclusive=False),
                "a host read": lambda: flag.numpy()}
    with strict():
        for what, call in attempts.items():
            call()  # outside a captured region: allowed
            with pytest.raises(GpuRefusal, match=what):
                wp.capture_if(flag, on_true=call)
            with pytest.raises(GpuRefusal, match=what):
                with wp.ScopedCapture("cpu"):
                    call()
        scan = Scan(8, "cpu")  # its scratch allocated outside: allowed
        wp.capture_if(flag, on_true=lambda: scan(src, dst))  # inside, it allocates nothing
    wp.capture_if(flag, on_true=attempts["an allocation"])  # the mode ends with its block
