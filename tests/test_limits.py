"""Limits and failure behaviour of the layers under the node: input files that cannot exhaust the
machine or leak their contents, a resource plan before any allocation, scene geometry that
removes fluid only when told to, and output folders checked before a run is built."""
import io
import re
from contextlib import redirect_stderr
from pathlib import Path

import pytest

from gpusph_ros.cli import run_main
from gpusph_ros.scenes import resources, yaml_input
from gpusph_ros.scenes.build import build, build_run
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.scenes.settings import parse_set, resolve
from gpusph_ros.sph import Solver
from gpusph_ros.sph.config import ConfigError

from conftest import planned_bytes

pytestmark = pytest.mark.unit

SECRET = "the-contents-of-this-file-must-not-leak"


def _scene_error(tmp_path, data: bytes) -> str:
    path = tmp_path / "scene.yaml"
    path.write_bytes(data)
    with pytest.raises(ConfigError) as err:
        load_scene(str(path))
    text = str(err.value)
    assert str(path) in text and SECRET not in text
    return text


@pytest.mark.parametrize("data, words", [
    (b"\x00\x01\x02" + SECRET.encode(), ["binary"]),
    (("name: caf\xe9 " + SECRET).encode("latin-1"), ["UTF-8", "byte 9"]),
    (b"[" * 100_000 + b"]" * 100_000, ["nested", "32"]),
    (b"a: &x [1, 2]\nb: *x\n" + b"# " + SECRET.encode(), ["anchors and aliases", "line 1"]),
    ((SECRET + ": [unclosed\n").encode(), ["valid YAML", "line 2"]),
    ((SECRET + " is a line of text\n").encode(), ["a YAML mapping", "str"]),
])
def test_a_bad_scene_file_is_named_and_its_contents_never_quoted(tmp_path, data, words):
    text = _scene_error(tmp_path, data)
    for word in words:
        assert word in text, text


def test_an_alias_bomb_and_a_huge_file_are_refused_at_once(tmp_path):
    bomb = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{chr(98 + k)}: &{chr(98 + k)} [*{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}]\n"
        for k in range(9))
    assert "anchors and aliases" in _scene_error(tmp_path, bomb.encode())
    assert "at most 1024 KiB" in _scene_error(tmp_path, b"probes:\n" + b"  # padding\n" * 200_000)


def test_yaml_1_2_numbers():
    assert parse_set("dx=1e-6") == ("dx", 1e-6)
    assert parse_set("end_time=2") == ("end_time", 2)
    assert parse_set("kernel=wendland") == ("kernel", "wendland")
    assert yaml_input.parse("[1e3, -2.5E-2, .5, 7]", "f", "w") == [1000.0, -0.025, 0.5, 7]


@pytest.mark.parametrize("scene, dx, boundary, sets", [
    ("dambreak1_thesis", 0.06, "dynamic", []),
    ("dambreak1_lab", 0.04, "monaghan_kajtar", []),
    ("collapse_2d", 0.005, "lennard_jones", []),
    ("dambreak2_010", 0.05, "dynamic", []),
    ("dambreak2_015", 0.05, "monaghan_kajtar", ["model=slab"]),
    ("dambreak1_lab", 0.04, "dynamic", ["wall_planes=true"]),
])
def test_the_particle_bound_holds_and_the_memory_estimate_is_close(scene, dx, boundary, sets, monkeypatch):
    bounds = []
    original = resources.particle_bound
    monkeypatch.setattr(resources, "particle_bound", lambda *a: bounds.append(original(*a)) or bounds[-1])
    s = load_scene(scene)
    model = build_run(s, resolve(s, sets=[f"dx={dx}", f"boundary={boundary}", *sets]))
    n = len(model.particles)
    assert n <= bounds[-1] <= 2.5 * n  # an upper bound, not a wild one
    if boundary == "dynamic":  # walls with a volume: counted exactly (gpusph-plan --estimate prices with it)
        assert bounds[-1] == n
    solver = Solver(model.config, model.particles)
    assert resources.device_bytes(n, model.config) == pytest.approx(planned_bytes(solver), rel=0.02)


def test_a_spacing_too_fine_is_refused_with_the_numbers_before_any_allocation():
    with pytest.raises(ConfigError) as err:
        build(load_scene("dambreak1_thesis"), dx=1.0e-4)
    text = str(err.value)
    assert text.startswith("dx: 0.0001") and "particles" in text and "GiB" in text and "max_particles" in text
    with pytest.raises(ConfigError) as err:  # below the setting's range: refused before any planning
        build(load_scene("dambreak1_thesis"), dx=1.0e-6)
    assert str(err.value).startswith("dx: 1e-06") and "[0.0001, 10]" in str(err.value)
    with pytest.raises(ConfigError) as err:
        build(load_scene("dambreak1_thesis"), dx=0.03, max_particles=1000)
    assert "max_particles is 1,000" in str(err.value)
    with pytest.raises(ConfigError) as err:  # under max_particles, over this machine's memory
        build(load_scene("dambreak1_thesis"), dx=0.001, max_particles=10 ** 12)
    assert re.search(r"of host memory in all; this machine has [\d.]+ GiB free$", str(err.value)), str(err.value)


def test_a_device_this_machine_lacks_is_refused_where_a_model_is_built_with_the_list():
    for device in ("tpu", "cuda:7"):
        with pytest.raises(ConfigError) as err:
            build(load_scene("dambreak1_thesis"), dx=0.06, device=device)
        text = str(err.value)
        assert text.startswith(f"device: '{device}'") and "a Warp device of this machine: cpu" in text


def _with_obstacle(tmp_path, obstacle: str) -> str:
    text = load_scene("dambreak1_thesis").text.replace("obstacles:", "obstacles:\n" + obstacle, 1)
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    return str(path)


def test_an_obstacle_over_the_fluid_is_an_error_unless_it_says_so(tmp_path):
    over = "  - {name: over, lo: [0.0, 0.0, 0.0], hi: [0.2, 0.2, 0.3]%s}"
    with pytest.raises(ConfigError) as err:
        build(load_scene(_with_obstacle(tmp_path, over % "")), dx=0.05)
    assert "obstacles[0]" in str(err.value) and "displaces_fluid: true" in str(err.value)
    model = build(load_scene(_with_obstacle(tmp_path, over % ", displaces_fluid: true")), dx=0.05)
    assert model.fluid_particles > 0
    filling = "  - {name: all, lo: [0.0, 0.0, 0.0], hi: [1.6, 0.67, 0.4], displaces_fluid: true}"
    with pytest.raises(ConfigError) as err:
        build(load_scene(_with_obstacle(tmp_path, filling)), dx=0.05)
    assert str(err.value).startswith("fluid:") and "outside the obstacles" in str(err.value)


@pytest.mark.parametrize("out, words", [
    ("", ["--out", "empty path"]),
    ("{file}", ["--out", "is a file"]),
    ("{file}/bag", ["--out", "lies under", "which is a file"]),
])
def test_gpusph_run_refuses_an_output_folder_it_cannot_write_before_building(tmp_path, out, words):
    file = tmp_path / "a_file"
    file.write_text("x")
    err = io.StringIO()
    with redirect_stderr(err):
        code = run_main(["dambreak1_thesis", "--set", "dx=1e-6", "--out", out.format(file=file)])
    assert code == 1
    for word in words:
        assert word in err.getvalue(), err.getvalue()


@pytest.mark.parametrize("contents, named", [
    (f"password: {SECRET}\n", "password"),  # a key file's mapping: the key is named, its value is the secret
    (f"root:{SECRET}:20228:0:99999:7:::\ndaemon:*:20228:0:99999:7:::\n", None),  # a shadow file: the key is
])
def test_no_entry_point_quotes_a_file_that_is_no_scene_run_or_study(tmp_path, contents, named):
    """gpusph-run (scene and run configuration), gpusph-plan and gpusph-sweep refuse a file whose
    YAML is a mapping of keys no scene, run configuration or study has, in one line, exit 1, and
    repeat none of its values, nor a key that does not read as a field name."""
    from gpusph_ros.cli import plan_main, sweep_main

    path = tmp_path / "private.yaml"
    path.write_text(contents)
    calls = [(run_main, [str(path), "--out", str(tmp_path / "a")]),
             (run_main, ["collapse_2d", "--run-config", str(path), "--out", str(tmp_path / "b")]),
             (plan_main, [str(path)]), (plan_main, ["collapse_2d", "--run-config", str(path)]),
             (sweep_main, [str(path), "--out", str(tmp_path / "c")])]
    for main, argv in calls:
        err = io.StringIO()
        with redirect_stderr(err):
            assert main(argv) == 1, (main.__name__, argv)
        message = err.getvalue().strip()
        assert len(message.splitlines()) == 1 and "not allowed" in message, (main.__name__, message)
        assert SECRET not in message, (main.__name__, message)
        if named:
            assert f": {named}: not allowed" in message, message


def test_no_recording_goes_into_the_operating_systems_folders(tmp_path):
    """record_dir and --out: the root and the system's folders are refused whatever the permissions
    (a node running as root accepted /etc), also through '..' and a link; anywhere else is as before."""
    from gpusph_ros.output.folders import folder_problem

    link = tmp_path / "etc_link"
    link.symlink_to("/etc")
    depth = len(Path.cwd().parts)
    for path, folder in (("/etc", "/etc"), ("/", "/"), ("/" + "../" * 3 + "etc/bags", "/etc"),
                         ("../" * depth + "usr/local/bags", "/usr"), (str(link / "bags"), "/etc")):
        problem = folder_problem(path)
        assert problem and f"lies in {folder}," in problem, (path, problem)
    assert folder_problem(tmp_path / "bags") is None
