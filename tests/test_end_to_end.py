"""End to end, as a user runs it: gpusph-run dambreak1_thesis at a coarse spacing for the first
0.6 s, then gpusph-analyze on the recording. A smoke test, not a tuned pass mark: the velocity
probe must see the surge (a peak between 1 and 3.5 m/s; Yeh & Petroff measured 2.2 m/s)."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.physics

REPO = Path(__file__).resolve().parents[1]


def test_run_then_analyze_dambreak1(tmp_path):
    out = tmp_path / "db1"
    run = subprocess.run([sys.executable, "-m", "gpusph_ros.cli", "run", "dambreak1_thesis", "--set", "dx=0.04",
                          "--set", "end_time=0.6", "--set", "particle_rate=10", "--out", str(out)],
                         cwd=REPO, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    assert "MIPPS" in run.stdout and "ETA" in run.stdout and "completed" in run.stdout
    analyze = subprocess.run([sys.executable, "-m", "gpusph_ros.cli", "analyze", str(out)], cwd=REPO,
                             capture_output=True, text=True, timeout=300)
    assert analyze.returncode == 0, analyze.stderr[-2000:]
    print("\n" + analyze.stdout)
    assert "experiment" in analyze.stdout and "this run" in analyze.stdout
    # the thesis ran 3.5-20 mm: at 4 cm one line says so instead of an empty GPUSPH column
    assert "the thesis has no run of scenario 3 at dx = 0.04 m" in analyze.stdout
    assert "GPUSPH (thesis)" not in analyze.stdout
    report = json.loads((out / "analysis/metrics.json").read_text())
    values = {m["key"]: m for m in report["metrics"]}
    assert 1.0 < values["peak_velocity"]["value"] < 3.5
    assert values["peak_velocity"]["experiment"] == 2.21
    assert values["peak_force_body"]["value"] > 0.0
    for chart in ("velocity.png", "force.png", "point_D.png", "errors.png"):
        assert (out / "analysis" / chart).stat().st_size > 10_000, chart
    bad = subprocess.run([sys.executable, "-m", "gpusph_ros.cli", "run", "dambreak1_thesis", "--set", "kernel=gauss",
                          "--out", str(tmp_path / "bad")], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert bad.returncode == 1 and "kernel: 'gauss' is not allowed; expected one of quadratic" in bad.stderr
