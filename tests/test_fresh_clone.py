"""A user's fresh clone has the repository and nothing beside it (no ../shared): the analysis of a
recording still fills the experiment and GPUSPH columns from the package's own data/, and says in
one line when that folder is missing instead of printing empty columns."""
import shutil
import subprocess
import sys

import pytest

from conftest import REPO
from test_analysis import record_synthetic_bore

ANALYZE = ("import sys, gpusph_ros; print('package:', gpusph_ros.__file__); "
           "from gpusph_ros.cli import analyze_main; sys.exit(analyze_main([sys.argv[1], '--no-charts']))")


def _analyze(clone, bag, cwd):
    out = subprocess.run([sys.executable, "-c", ANALYZE, str(bag)], cwd=cwd, capture_output=True, text=True,
                         env={"PYTHONPATH": str(clone), "PATH": "/usr/bin:/bin", "HOME": str(cwd)}, timeout=300)
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-2000:]
    assert f"package: {clone / 'gpusph_ros'}" in out.stdout  # the clone's code, not this checkout's
    return out.stdout


@pytest.mark.unit
def test_a_clone_with_nothing_beside_it_compares_with_experiment_and_gpusph(tmp_path):
    if shutil.which("git") is None or not (REPO / ".git").exists():
        pytest.skip("not a git checkout")
    clone = tmp_path / "alone" / "gpusph_ros"
    subprocess.run(["git", "clone", "-q", str(REPO), str(clone)], check=True, timeout=120)
    assert not (clone.parent / "shared").exists()
    bag = tmp_path / "alone" / "bore"
    record_synthetic_bore(bag)
    text = _analyze(clone, bag, clone.parent)
    row = next(line for line in text.splitlines() if line.startswith("mean depth-averaged velocity"))
    assert "0.772" in row and "0.71 (" in row  # experiment (Arnason et al., thesis) and GPUSPH Table 29
    assert "no reference data found" not in text
    shutil.rmtree(clone / "data")
    text = _analyze(clone, bag, clone.parent)
    assert text.count("no reference data found") == 1
    header = next(line for line in text.splitlines() if line.startswith("metric"))
    assert header.split() == ["metric", "unit", "this", "run"]
    row = next(line for line in text.splitlines() if line.startswith("mean depth-averaged velocity"))
    assert "0.772" not in row and float(row.split()[-1]) == pytest.approx(0.8, rel=0.01)
