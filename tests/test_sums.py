"""Fixed-order sums and the allocation-free scan (sph/sums.py, sph/scan.py) against exact answers,
and the strict CPU mode (sph/device_calls.strict) refusing what CUDA refuses inside a capture."""
import numpy as np
import pytest
import warp as wp

from gpusph_ros.sph import sums
from gpusph_ros.sph.device_calls import GpuRefusal, strict
from gpusph_ros.sph.scan import SPAN as SCAN_SPAN
from gpusph_ros.sph.scan import Scan

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("n", [0, 1, 2, SCAN_SPAN - 1, SCAN_SPAN, SCAN_SPAN + 1, SCAN_SPAN ** 2 + 1, 200_003])
def test_the_scan_is_numpys_exclusive_cumulative_sum(n):
    # 1, 2 and 3 levels of blocks
    values = np.random.default_rng(n).integers(0, 9, n).astype(np.int32)
    out = wp.full(n, -1, dtype=wp.int32, device="cpu")
    Scan(n, "cpu")(wp.array(values, dtype=wp.int32, device="cpu"), out)
    assert np.array_equal(out.numpy(), np.concatenate([[0], np.cumsum(values)[:-1]]).astype(np.int32)[:n])


@pytest.mark.parametrize("n", [1, 255, 256, 257, 10_000])
@pytest.mark.parametrize("layout", ["cpu", "gpu"])
def test_every_particle_is_in_exactly_one_block(n, layout):
    # both layouts, the GPU's too, as arithmetic: block k's j-th member is k lead + j step
    count = -(-n // sums.SPAN)
    lead, step = (sums.SPAN, 1) if layout == "cpu" else (1, count)
    k, j = np.meshgrid(np.arange(count), np.arange(sums.SPAN), indexing="ij")
    members = (k * lead + j * step).ravel()
    assert np.array_equal(np.sort(members[members < n]), np.arange(n))


@wp.kernel(enable_backward=False)
def _slot_sums(values: wp.array(dtype=wp.float64), part: wp.array2d(dtype=wp.float64), lead: int, step: int):
    k = wp.tid()
    for s in range(part.shape[1]):
        part[k, s] = wp.float64(0.0)
    for j in range(sums.SPAN):
        i = sums.member(k, j, lead, step)
        if i < values.shape[0]:
            part[k, i % 3] = part[k, i % 3] + values[i]


def test_partial_sums_add_to_the_exact_totals():
    n = 5000
    values = np.arange(n, dtype=np.float64)  # integers: every order sums them exactly
    part = sums.Partials(n, 3, wp.float64, "cpu")
    wp.launch(_slot_sums, dim=part.count, inputs=[wp.array(values, dtype=wp.float64), *part.args()], device="cpu")
    out = wp.array([1.0, 2.0, 3.0, 4.0], dtype=wp.float64, device="cpu")
    part.total(out, offset=1, add=True)
    expected = [values[values % 3 == s].sum() for s in range(3)]
    assert out.numpy().tolist() == [1.0, 2.0 + expected[0], 3.0 + expected[1], 4.0 + expected[2]]
    part.total(out)
    assert out.numpy().tolist() == expected + [4.0 + expected[2]]


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
