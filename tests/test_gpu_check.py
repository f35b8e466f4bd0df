"""`make gpu-check` on a machine without CUDA says so and exits 0, having checked nothing; its CPU
rehearsal (`--cpu`) writes every section of the report, the step counts, graph-against-eager,
same-run-twice and lists-against-cells tables among them, with every step passing."""
import re
import subprocess
import sys

import pytest
import warp as wp

from conftest import REPO


@pytest.mark.unit
def test_gpu_check_without_cuda_says_so_and_exits_0(tmp_path):
    if wp.get_cuda_device_count() > 0:
        pytest.skip("this machine has a CUDA device: make gpu-check runs the real check")
    out = subprocess.run([sys.executable, str(REPO / "bench/gpu_check.py"), "--out", str(tmp_path / "check")],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "finds no CUDA device" in out.stdout
    assert not (tmp_path / "check").exists()  # nothing run, no report


@pytest.mark.study
def test_the_cpu_rehearsal_writes_every_section_of_the_report(tmp_path):
    out = subprocess.run([sys.executable, str(REPO / "bench/gpu_check.py"), "--cpu", "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=360)
    report = (tmp_path / "report.md").read_text()
    assert out.returncode == 0, out.stdout + out.stderr + report
    sections = re.findall(r"^## (.*): (ok|FAILED) \(\d+ s\)$", report, flags=re.M)
    assert len(sections) == 9 and all(state == "ok" for _, state in sections), sections
    assert re.search(r"^\d+ modules of the package loaded by \d+ runs", report, flags=re.M)  # the build's step
    assert "0 never loaded by the runs" in report
    assert re.search(r"^cpu +lists .*\n^cpu +cells ", report, flags=re.M)  # the two searches side by side
    assert "every case repeats bit for bit" in report  # bench/repeat.py: the same run twice
    assert "no GPU figure below" in report and "every step passed" in report
    assert re.search(r"^\| ordinary \| \d+ \| \d+ \| 0 \|", report, flags=re.M)  # no sort on an ordinary step
    assert re.search(r"^\| replayed \| 2 \| 0 \| 0 \| 1 \|", report, flags=re.M)  # one replay an output
    assert "real-time factor" in report and "MIPPS" in report
