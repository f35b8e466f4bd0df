"""Edited state files against a live solver (bench/state_fuzz.py), a short round: every array and
host value of a real state mutated in turn, written, read back and restored. The process never
dies, a refused state leaves the run bit for bit as it was, and an accepted one runs. The bench
runs the long round (10 minutes)."""
import re
import subprocess
import sys

import pytest

from conftest import REPO

pytestmark = pytest.mark.physics


def test_edited_states_never_kill_the_process_and_a_refusal_changes_nothing():
    out = subprocess.run([sys.executable, str(REPO / "bench/state_fuzz.py"), "--minutes", "0.3"],
                         capture_output=True, text=True, timeout=240)
    assert out.returncode == 0, out.stdout + out.stderr
    tried = int(re.search(r"(\d+) cases", out.stdout).group(1))
    refused = int(re.search(r"refused (\d+)", out.stdout).group(1))
    assert tried >= 300 and refused >= tried // 2, out.stdout
