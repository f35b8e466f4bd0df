"""`make gpu-check` on a machine without CUDA says so and exits 0, having checked nothing."""
import subprocess
import sys

import pytest
import warp as wp

from conftest import REPO

pytestmark = pytest.mark.unit


def test_gpu_check_without_cuda_says_so_and_exits_0(tmp_path):
    if wp.get_cuda_device_count() > 0:
        pytest.skip("this machine has a CUDA device: make gpu-check runs the real check")
    out = subprocess.run([sys.executable, str(REPO / "bench/gpu_check.py"), "--out", str(tmp_path / "check")],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "finds no CUDA device" in out.stdout
    assert not (tmp_path / "check").exists()  # nothing run, no report
