"""The lint as a test, as ROS 2 packages run ament_flake8: ruff (pinned in requirements.txt) with the
repository's ruff.toml, on the whole tree."""
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO

pytestmark = pytest.mark.unit


def _ruff():
    beside = Path(sys.executable).with_name("ruff")  # the venv's, where `make` installed it
    return str(beside) if beside.is_file() else shutil.which("ruff")


def test_the_tree_is_lint_clean():
    ruff = _ruff()
    if ruff is None:
        pytest.skip("ruff is not installed (requirements.txt pins it)")
    out = subprocess.run([ruff, "check", "--no-cache", str(REPO)], cwd=REPO, capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-2000:]
