"""``device: auto`` (issue 57): the first CUDA device Warp sees, else the CPU, taken where the model is
built and said in the run's first line and on /diagnostics (Session.stats: ``device_choice``)."""
from types import SimpleNamespace

import pytest
import warp as wp

from gpusph_ros.ros.node_params import DEFAULTS, check
from gpusph_ros.runner import Run
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.scenes.settings import resolve
from gpusph_ros.sph.device import AUTO, choice, chosen_device

pytestmark = pytest.mark.unit


def _devices(*aliases):
    return [SimpleNamespace(alias=a, is_cuda=a.startswith("cuda")) for a in aliases]


def test_auto_picks_the_first_cuda_device_else_the_cpu(monkeypatch):
    monkeypatch.setattr(wp, "get_devices", lambda: _devices("cpu", "cuda:0", "cuda:1"))
    assert chosen_device(AUTO) == "cuda:0"
    monkeypatch.setattr(wp, "get_devices", lambda: _devices("cpu"))
    assert chosen_device(AUTO) == "cpu"
    assert chosen_device("cuda:1") == "cuda:1"  # a named device is the run's, found or not
    assert choice("cpu", "cpu") == ""
    assert choice(AUTO, "cpu") == "device auto: cpu, Warp sees no CUDA device"
    assert choice(AUTO, "cuda:0") == "device auto: cuda:0, the first CUDA device Warp sees"


def test_a_run_on_auto_steps_on_the_chosen_device_and_says_why():
    scene = load_scene("collapse_2d")
    run = Run(scene, resolve(scene, dx=0.05, device=AUTO))
    chosen = chosen_device(AUTO)
    assert str(run.solver.device) == chosen and run.solver.config.device == chosen
    assert f"on {chosen} ({choice(AUTO, chosen)})" in run.summary()
    assert run.device_choice == choice(AUTO, chosen)
    named = Run(scene, resolve(scene, dx=0.05, device="cpu"))
    assert named.device_choice == "" and "device auto" not in named.summary()


def test_the_node_takes_auto_and_refuses_a_device_it_lacks():
    assert check({**DEFAULTS, "device": AUTO}, ["device"]) is None
    assert "device: 'cuda:99' is not available here" in check({**DEFAULTS, "device": "cuda:99"}, ["device"])
