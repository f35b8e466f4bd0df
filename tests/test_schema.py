"""Scene files and run configurations: every bad field gets one error naming the field, its value
and what is allowed; the built-in scenes load; overrides layer in order."""
import copy
import io

import pytest
import yaml

from gpusph_ros.scenes.schema import builtin_names, load_scene, parse_scene
from gpusph_ros.scenes.settings import resolve
from gpusph_ros.sph import ConfigError

pytestmark = pytest.mark.unit

GOOD = {
    "name": "tank", "dim": 3, "tank": [1.0, 0.5, 0.4], "depth": 0.2,
    "walls": {"floor": "particles", "x_min": "planes"},
    "fluid": [{"name": "column", "lo": [0, 0, 0], "hi": [0.3, 0.5, 0.2]}],
    "wet_bed": 0.01,
    "obstacles": [{"name": "block", "lo": [0.6, 0.2, 0.0], "hi": [0.7, 0.3, 0.4]}],
    "probes": {"u": {"type": "point", "position": [0.5, 0.25, 0.02]},
               "col": {"type": "column", "position": [0.5, 0.25]},
               "prof": {"type": "profile", "position": [0.5, 0.25], "heights": [0.01, 0.02]},
               "eta": {"type": "gauge", "position": [0.2, 0.25]}},
    "run": {"end_time": 0.5},
}


def with_change(path, value):
    data = copy.deepcopy(GOOD)
    target = data
    for key in path[:-1]:
        target = target[key]
    if value is KeyError:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return data


def test_a_fluid_box_that_fills_the_whole_tank_is_legal_and_said(tmp_path):
    """Legal (a brim-full tank) but rarely meant: the scene carries a warning that gpusph-run prints.
    A box up to the brim that leaves room along the tank (the thesis's DamBreak 1 column) is not
    warned about."""
    from contextlib import redirect_stderr

    from gpusph_ros.cli import run_main

    assert parse_scene(GOOD).warnings == []
    assert parse_scene(with_change(("fluid", 0, "hi"), [0.3, 0.5, 0.4])).warnings == []  # up to the brim only
    assert load_scene("dambreak1_thesis").warnings == []
    full = with_change(("fluid", 0), {"name": "water", "lo": [0, 0, 0], "hi": [1.0, 0.5, 0.4]})
    full["obstacles"] = []
    scene = parse_scene(full)
    assert scene.warnings and "fills the whole tank" in scene.warnings[0]
    path = tmp_path / "full.yaml"
    path.write_text(yaml.safe_dump(full))
    err = io.StringIO()
    with redirect_stderr(err):
        run_main([str(path), "--set", "dx=0.05", "--set", "output_rate=1000", "--set", "end_time=0.001",
                  "--out", str(tmp_path / "bag"),
                  "--quiet"])
    assert "gpusph-run: warning: fluid box 'water' fills the whole tank" in err.getvalue(), err.getvalue()


def test_good_scene_parses_into_three_vectors():
    scene = parse_scene(GOOD)
    assert scene.walls == {"x_min": "planes", "x_max": "particles", "y_min": "particles", "y_max": "particles",
                           "floor": "particles"}
    assert scene.probes[1].position == (0.5, 0.25, 0.0) and scene.obstacles[0].block_offsets == (0.0, 0.06)


@pytest.mark.parametrize("path, value, field, allowed", [
    (("dim",), 4, "dim", "2 or 3"),
    (("tank",), [1.0, -0.5, 0.4], "tank[1]", ">= 0"),
    (("tank",), [1.0, 0.5], "tank", "a list of 3 numbers"),
    (("gravity",), [0.0, 0.0, 9.81], "gravity", "pointing down"),
    (("gravity",), [9.0, 0.0, -5.0], "gravity", "tilted by at most 45 degrees"),
    (("gravity",), [0.0, 0.0, -1.0e30], "gravity", "a magnitude in [0.0981, 981]"),  # time stuck at 0
    (("gravity",), [0.0, 0.0, -1.0e-30], "gravity", "a magnitude in [0.0981, 981]"),
    (("depth",), 1.0e6, "depth", "<= 0.4"),  # deeper than the tank: c0 took millions of steps a second
    (("analysis",), {"case": "flume"}, "analysis.case", "one of dambreak1, dambreak2, lobovsky"),
    (("walls", "floor"), "glass", "walls.floor", "one of particles, planes"),
    (("walls", "z_max"), "planes", "walls.z_max", "the fields are x_min, x_max, y_min, y_max, floor"),
    (("fluid", 0, "hi"), [0.3, 0.5, 0.6], "fluid[0].hi", "inside the tank"),
    (("fluid", 0, "hi"), [0.0, 0.5, 0.2], "fluid[0].hi", "every component above lo"),
    (("fluid", 0, "name"), "2nd", "fluid[0].name", "starting with a letter"),
    (("fluid",), [{"name": "a", "lo": [0, 0, 0], "hi": [0.3, 0.5, 0.2]}, {"name": "b", "lo": [0, 0, 0],
                                                                         "hi": [0.3, 0.5, 0.2]}],
     "fluid[1]", "overlaps 'a'"),  # two identical boxes were accepted: 16 particles a cell
    (("headroom",), 1.0e6, "headroom", "<= 10"),
    (("probes", "col", "radius_dx"), 1.0e9, "probes.col.radius_dx", "<= 100"),
    (("description",), {"a": 1}, "description", "a text"),
    (("probes",), {f"g{k}": {"type": "gauge", "position": [0.5, 0.25]} for k in range(257)}, "probes",
     "at most 256 probes"),  # 5,000 gauges: a node answered no parameter call for 96 s
    (("probes", "prof", "heights"), [0.01] * 65, "probes.prof.heights", "at most 64"),
    (("obstacles",), [{"name": f"o{k}", "lo": [0.6, 0.0, 0.0], "hi": [0.61, 0.01, 0.1]} for k in range(33)],
     "obstacles", "at most 32"),
    (("fluid", 0, "name"), "w\u00e4sser", "fluid[0].name", "ASCII letters"),  # the node's reset failed on it
    (("fluid", 0, "name"), "a" * 65, "fluid[0].name", "at most 64"),
    (("fluid",), [], "fluid", "at least one box"),
    (("fluid", 0, "lo"), KeyError, "fluid[0].lo", "required"),
    (("wet_bed",), -0.1, "wet_bed", ">= 0"),
    (("obstacles", 0, "lo"), [0.6, 0.2, 0.1], "obstacles[0].lo", "standing on the floor"),
    (("obstacles", 0, "block_offsets"), [0.0, -1], "obstacles[0].block_offsets[1]", ">= 0"),
    (("probes", "u", "type"), "laser", "probes.u.type", "one of point, column, profile, gauge"),
    (("probes", "u", "position"), [0.5, 0.25], "probes.u.position", "a list of 3 numbers"),
    (("probes", "col", "position"), [5.0, 0.25], "probes.col.position", "inside the tank"),
    (("probes", "prof", "heights"), "low", "probes.prof.heights", "a list of heights"),
    (("probes", "u", "heights"), [0.1], "probes.u.heights", "only profile probes"),
    (("probes", "u", "reading"), "smoothed", "probes.u.reading", "only pressure_sensor probes"),
    (("probes", "p"), {"type": "pressure_sensor", "position": [1.0, 0.25, 0.1], "normal": [-1, 0, 0],
                       "reading": "averaged"}, "probes.p.reading", "one of wall, smoothed"),
    (("colour",), "blue", "colour", "the fields are name, description"),
])
def test_bad_field_is_named_with_what_is_allowed(path, value, field, allowed):
    with pytest.raises(ConfigError) as err:
        parse_scene(with_change(path, value))
    assert err.value.field == field
    assert allowed in str(err.value)


def test_every_builtin_scene_loads():
    names = builtin_names()
    assert {"dambreak1_thesis", "dambreak1_lab", "dambreak2_010", "dambreak2_015", "collapse_2d"} <= set(names)
    for name in names:
        scene = load_scene(name)
        assert scene.name == name and scene.description and scene.source


def test_scene_file_errors_name_the_file_problem(tmp_path):
    with pytest.raises(ConfigError, match="scene: 'nowhere' is not allowed; expected a built-in scene"):
        load_scene("nowhere")
    bad = tmp_path / "bad.yaml"
    bad.write_text("dim: [3\n")
    with pytest.raises(ConfigError, match="valid YAML"):
        load_scene(bad)
    good = tmp_path / "mine.yaml"
    good.write_text(yaml.safe_dump(GOOD))
    assert load_scene(good).text == good.read_text()


def test_run_settings_layer_scene_then_files_then_sets(tmp_path):
    scene = parse_scene(GOOD)
    run = resolve(scene)
    assert run.output.end_time == 0.5 and run.numerics == {}
    path = tmp_path / "run.yaml"
    path.write_text("kernel: quadratic\ndx: 0.03\nend_time: 2\n")
    run = resolve(scene, files=[path, "thesis_scenario3"], sets=["dx=0.025", "xsph=false", "particle_rate=0"])
    assert run.numerics["kernel"] == "cubic_spline"  # the later file wins over the earlier
    assert run.numerics["dx"] == 0.025 and run.numerics["xsph"] is False
    assert run.output.end_time == 2.0 and run.output.particle_every == 0


@pytest.mark.parametrize("setting, field, allowed", [
    ("kernel=gauss", "kernel", "one of quadratic, cubic_spline, wendland"),
    ("dx=fine", "dx", "a number"),
    ("shepard_every=2.5", "shepard_every", "an integer"),
    ("xsph=1", "xsph", "true or false"),
    ("gravity=[0,0,-1]", "gravity", "set by the scene"),
    ("colour=red", "colour", "the settings are"),
    ("end_time=-1", "end_time", "a time in [1e-06, 100000] s"),
    ("end_time=1e30", "end_time", "a time in [1e-06, 100000] s"),  # it ran until killed
    ("end_time=0.001", "end_time", "at least one output interval, 1 / output_rate = 0.01 s"),  # it ran no step
    ("output_rate=5e-324", "output_rate", "a rate in [0.001, 10000] Hz"),  # a denormal was accepted
    ("particle_rate=500", "particle_rate", "output_rate = 100] Hz"),
    ("particle_rate=1e-300", "particle_rate", "0 (no particle clouds) or a rate in [0.001"),
    ("cfl=2", "cfl", "[0.01, 1]"),
])
def test_bad_run_setting_is_named(setting, field, allowed):
    with pytest.raises(ConfigError) as err:
        resolve(parse_scene(GOOD), sets=[setting])
    assert err.value.field == field
    assert allowed in str(err.value)


def test_a_scene_file_changes_its_base_and_records_the_merged_scene(tmp_path):
    """``base:`` takes another scene and replaces the keys the file gives; the scene's text is the
    merged scene, so a recording replays without the base file; a loop or a missing base is
    refused naming ``base``."""
    lab, zoned = load_scene("dambreak1_lab"), load_scene("dambreak1_lab_zoned")
    assert zoned.name == "dambreak1_lab_zoned" and zoned.refine and not lab.refine
    assert (zoned.tank, zoned.fluid, zoned.obstacles, zoned.probes) == (lab.tank, lab.fluid, lab.obstacles, lab.probes)
    assert parse_scene(yaml.safe_load(zoned.text)).refine == zoned.refine
    (tmp_path / "base.yaml").write_text(yaml.safe_dump(GOOD))
    (tmp_path / "deeper.yaml").write_text("base: base.yaml\ndepth: 0.1\n")
    deeper = load_scene(tmp_path / "deeper.yaml")
    assert (deeper.name, deeper.depth, deeper.tank) == ("deeper", 0.1, load_scene(tmp_path / "base.yaml").tank)
    (tmp_path / "a.yaml").write_text("base: b.yaml\n")
    (tmp_path / "b.yaml").write_text("base: a.yaml\n")
    (tmp_path / "orphan.yaml").write_text("base: nowhere.yaml\n")
    for name in ("a.yaml", "orphan.yaml"):
        with pytest.raises(ConfigError) as err:
            load_scene(tmp_path / name)
        assert err.value.field == "base"
