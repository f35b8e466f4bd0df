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


def test_a_cuda_device_this_warps_nvrtc_cannot_build_for_is_refused_by_name(monkeypatch):
    """Issue 67: a GPU older than the oldest architecture this Warp's NVRTC builds for (sm_75 with
    Warp 1.19; sm_70 is refused by it) is refused at the start, naming the device and both
    capabilities, not left to fail at its first kernel's build."""
    from gpusph_ros.sph.config import ConfigError, check_device
    from gpusph_ros.sph.cuda_build import oldest_arch

    oldest = oldest_arch()
    assert oldest >= 60
    gpus = {"cuda:0": SimpleNamespace(alias="cuda:0", is_cuda=True, arch=oldest - 5, name="Tesla V100"),
            "cuda:1": SimpleNamespace(alias="cuda:1", is_cuda=True, arch=oldest, name="a newer GPU")}
    monkeypatch.setattr(wp, "get_devices", lambda: [SimpleNamespace(alias="cpu", is_cuda=False), *gpus.values()])
    monkeypatch.setattr(wp, "get_device", lambda name: gpus[name])
    with pytest.raises(ConfigError, match=rf"capability {oldest // 10}\.{oldest % 10} or later.*cuda:0 \(Tesla "
                                          rf"V100\) is {(oldest - 5) // 10}\.{(oldest - 5) % 10}"):
        check_device("cuda:0")
    check_device("cuda:1")
