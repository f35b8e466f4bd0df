"""sim_node's parameter table and checks (gpusph_ros.ros.node_params), and the shipped parameter
files: every file names known parameters and describes a run."""
from pathlib import Path

import pytest
import yaml

from gpusph_ros.ros import node_params
from gpusph_ros.ros.node_params import DEFAULTS, PARAMS, check, run_settings
from gpusph_ros.scenes.schema import builtin_names

pytestmark = pytest.mark.unit

REPO = Path(__file__).resolve().parents[1]


def _values(**changes):
    return {**DEFAULTS, **changes}


def test_the_issue_list_of_parameters_is_declared():
    from gpusph_ros.scenes.settings import RUN_KEYS

    names = {p.name for p in PARAMS}
    assert names == {"scene", "dx", "kernel", "viscosity", "sps", "boundary", "density_diffusion", "precision",
                     "device", "cfl", "c0", "end_time", "output_rate", "real_time_factor", "publish_particles",
                     "particle_fields", "record_dir", "frame_id", "autostart", "model", "crop", "wall_planes",
                     "max_excluded_fraction", "max_left_fraction", "mdbc_slip", "visco_bound_factor", "compression",
                     "stamps", "state_file", "clock", "max_lag", "wrench_rate"} | (
        set(RUN_KEYS) - set(node_params.NOT_NODE_SETTINGS))  # every run setting gpusph-run takes (issue 66)
    for p in PARAMS:
        assert p.description and p.applies in (node_params.RESET, node_params.LIVE, node_params.RECORDING,
                                               node_params.STARTUP, node_params.SERVICE)


def test_a_setting_declared_for_completeness_leaves_the_scenes_own_at_its_default(tmp_path):
    """Issue 66, item 7 declared every run setting; one at its default must not override the
    scene's run: section (a sinking column's energy_growth_ratio: 0 became 0.05 and failed the run),
    and set off its default it does."""
    scene = tmp_path / "s.yaml"
    scene.write_text("name: s\ndim: 2\ntank: [0.4, 0.3]\nfluid:\n  - {name: w, lo: [0, 0], hi: [0.1, 0.1]}\n"
                     "run: {energy_growth_ratio: 0.0, alpha: 0.05}\n")
    config = run_settings(_values(scene=str(scene)))[1].solver
    assert (config.energy_growth_ratio, config.alpha) == (0.0, 0.05)
    config = run_settings(_values(scene=str(scene), energy_growth_ratio=0.2, alpha=0.3))[1].solver
    assert (config.energy_growth_ratio, config.alpha) == (0.2, 0.3)


def test_defaults_describe_a_run():
    assert check(_values()) is None
    scene, config = run_settings(_values())
    assert scene.name == "dambreak1_thesis" and config.numerics["dx"] == 0.03
    assert config.output.end_time == 3.0 and config.output.output_rate == 100.0  # the scene's own
    assert config.output.particle_every == 1  # a cloud at every output


@pytest.mark.parametrize("changes, words", [
    ({"kernel": "gauss"}, ["kernel", "'gauss'", "quadratic, cubic_spline, wendland"]),
    ({"viscosity": "sps"}, ["viscosity", "artificial, laminar", "sps true"]),
    ({"sps": True}, ["sps", "laminar", "'artificial'"]),
    ({"boundary": "planes"}, ["boundary", "lennard_jones, monaghan_kajtar, dynamic"]),
    ({"dx": 0.0}, ["dx", "[0.0001, 10]"]),
    ({"dx": 1.0e-4}, ["dx: 0.0001", "a coarser spacing", "max_particles is 200,000,000"]),  # was left pending
    ({"cfl": 1.5}, ["cfl", "[0.01, 1]"]),
    ({"device": "cuda:7"}, ["device", "'cuda:7'", "cpu"]),
    ({"scene": "no_such_scene"}, ["scene", "no_such_scene", "dambreak1_thesis"]),
    ({"particle_fields": ["vx", "speed"]}, ["particle_fields", "'speed'", "density"]),
    ({"particle_fields": ["vx", "vx"]}, ["particle_fields", "twice"]),
    ({"frame_id": " "}, ["frame_id"]),
    ({"frame_id": "../.."}, ["frame_id: '../..' is not a ROS frame name", "e.g. world or robot1/odom"]),
    ({"frame_id": "map\nbase"}, ["frame_id", "not a ROS frame name"]),
    ({"frame_id": "\u202eworld"}, ["frame_id", "not a ROS frame name"]),
    ({"frame_id": "1st"}, ["frame_id", "none starting with a digit"]),
    ({"frame_id": "a__b"}, ["frame_id", "no __"]),
    ({"frame_id": "world/"}, ["frame_id", "not a ROS frame name"]),
    ({"frame_id": "w" * 10 ** 6}, ["frame_id", "1,000,000 characters", "at most 256"]),
    ({"scene": "s" * 100_000}, ["scene", "at most 4,096"]),
    ({"record_dir": "r" * 5000}, ["record_dir", "at most 4,096"]),
    ({"model": "3d"}, ["model", "full, slab, 2d"]),
    ({"compression": "gzip"}, ["compression", "'gzip'", "zstd, lz4, none"]),
    ({"stamps": "wall"}, ["stamps", "'wall'", "simulated, epoch"]),
    ({"model": "2d"}, ["model", "obstacles[0] (obstruction) does not span the tank's width"]),
    ({"record_dir": str(REPO / "setup.py" / "bags")}, ["record_dir", "lies under", "which is a file"]),
])
def test_a_bad_value_gets_a_reason_naming_the_field_and_the_allowed_values(changes, words):
    reason = check(_values(**changes), changed=changes)
    assert reason is not None
    for word in words:
        assert word in reason, (word, reason)


def test_a_long_value_is_quoted_by_a_short_prefix_and_ros_frame_names_pass():
    for name, value in (("kernel", "k" * 100_000), ("boundary", "b" * 100_000),
                        ("particle_fields", ["vx", "f" * 100_000]), ("frame_id", "w/" * 100)):
        reason = check(_values(**{name: value}), changed={name: value})
        assert reason.startswith(f"{name}: ") and len(reason) < 400, reason[:400]
    for frame in ("world", "map", "robot1/odom", "_private/base_link"):
        assert check(_values(frame_id=frame), changed={"frame_id": frame}) is None, frame


def test_a_combination_is_checked_as_a_whole():
    assert check(_values(scene="collapse_2d", dx=0.0025)) is None
    assert check(_values(viscosity="laminar", sps=True)) is None
    scene, config = run_settings(_values(viscosity="laminar", sps=True))
    assert config.numerics["viscosity"] == "sps"
    _, config = run_settings(_values(publish_particles=False))
    assert config.output.particle_every == 0
    _, config = run_settings(_values(scene="dambreak2_010", dx=0.05, model="slab", wall_planes=True))
    assert (config.reduction.model, config.reduction.wall_planes) == ("slab", True)


def test_shipped_parameter_files_cover_every_scene_and_describe_runs():
    files = {p.stem: p for p in (REPO / "config/params").glob("*.yaml")}
    assert set(files) == set(builtin_names())
    default = yaml.safe_load((REPO / "config/sim_node.yaml").read_text())["sim_node"]["ros__parameters"]
    assert default == DEFAULTS  # the default file lists every parameter at its declared default
    for name, path in files.items():
        values = yaml.safe_load(path.read_text())["sim_node"]["ros__parameters"]
        assert set(values) <= set(DEFAULTS), path
        assert values["scene"] == name
        assert check(_values(**values)) is None, path


def test_every_live_parameter_reaches_the_session_as_its_settings():
    """node_params.LIVE_SETTINGS is the one list of what applies live: each LIVE parameter comes to
    settings in it, with the values the run would be built with."""
    for p in PARAMS:
        if p.applies == node_params.LIVE:
            assert node_params.live_settings(_values(), [p.name]), p.name
    assert node_params.live_settings(_values(cfl=0.2), ["cfl"]) == {"cfl": 0.2}
    assert node_params.live_settings(_values(viscosity="laminar", sps=True), ["sps"]) == {"viscosity": "sps"}
    settings = node_params.live_settings(_values(output_rate=50.0, publish_particles=False), ["publish_particles"])
    assert settings == {"end_time": run_settings(_values())[1].output.end_time, "output_rate": 50.0,
                        "particle_rate": 0.0}  # the outputs go as one
    assert node_params.live_settings(_values(output_rate=50.0), ["output_rate"])["particle_rate"] == 50.0


def test_a_scene_that_reset_would_refuse_is_refused_when_set(tmp_path):
    """A 1e300 m tank was accepted as the scene parameter and stayed pending until ~/reset refused
    it (issue 58): its particles are priced when it is set."""
    path = tmp_path / "vast.yaml"
    path.write_text("name: vast\ndim: 2\ntank: [1.0e+300, 1.0]\n"
                    "fluid:\n  - {name: sea, lo: [0, 0], hi: [1.0e+300, 0.5]}\n")
    reason = check(_values(scene=str(path)), changed={"scene": str(path)})
    assert reason is not None and reason.startswith("dx: ") and "particles" in reason, reason


def test_the_clock_parameters_refuse_bad_values_naming_the_field():
    for clock in ("follow", "lockstep", "none"):
        assert check(_values(clock=clock)) is None
    assert check(_values(clock="maybe"), ["clock"]).startswith(
        "clock: 'maybe' is not one of publish, follow, lockstep, none")
    assert check(_values(max_lag=-1.0), ["max_lag"]).startswith("max_lag: -1.0 is outside [0, 1000]")
    assert check(_values(wrench_rate=-1.0), ["wrench_rate"]).startswith("wrench_rate: -1.0 is outside [0, 10000]")
    assert check(_values(wrench_rate=float("nan")), ["wrench_rate"]).startswith("wrench_rate: nan is outside")
    # the master clock's time is the simulated time: epoch stamps would be another clock
    for clock in ("follow", "lockstep"):
        assert check(_values(clock=clock, stamps="epoch")).startswith(f"clock: {clock} takes the master clock's time")
