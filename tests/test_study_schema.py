"""Study files (gpusph_ros.study.schema): the shipped thesis studies hold the thesis's cases, and
a bad study is refused naming the field (or the case) and what is allowed."""
import pytest
import yaml

from gpusph_ros.sph import ConfigError
from gpusph_ros.study.schema import load_study, study_names

pytestmark = pytest.mark.unit


def test_the_thesis_studies_hold_the_thesis_cases():
    names = {"thesis_dambreak1", "thesis_dambreak2", "thesis_dambreak1_cpu", "thesis_dambreak2_cpu"}
    assert names <= set(study_names())
    db1 = load_study("thesis_dambreak1")
    cases = db1.cases()
    assert len(cases) == 54 and len({c.name for c in cases}) == 54  # 18 spacings x 3 scenarios (Tables 2, 6-24)
    assert {c.grid["dx"] for c in cases} == {0.0035, 0.004, 0.005, 0.006, 0.007, 0.008, 0.009, 0.01, 0.011, 0.012,
                                              0.013, 0.014, 0.015, 0.016, 0.017, 0.018, 0.019, 0.02}
    one = next(c for c in cases if c.scenario == "scenario1" and c.grid["dx"] == 0.0035)
    assert one.name == "dambreak1_thesis-scenario1-dx=0.0035"
    assert one.settings["kernel"] == "quadratic" and one.settings["viscosity"] == "sps" and one.settings["dx"] == 0.0035
    db2 = load_study("thesis_dambreak2")
    assert len(db2.cases()) == 30  # 5 spacings x 2 depths x 3 scenarios (Tables 4, 25-36)
    assert {c.scene for c in db2.cases()} == {"dambreak2_010", "dambreak2_015"}


def _study(tmp_path, **changes):
    data = {"scenes": ["collapse_2d"], "scenarios": {"base": {}}, "grid": {"dx": [0.01]}, "metrics": ["peak_velocity"],
            **changes}
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize("changes, field, words", [
    ({"scenes": []}, "scenes", "a list of scene names"),
    ({"metrics": ["speed"]}, "metrics", "peak_velocity"),
    ({"grid": {"dx": 0.01}}, "grid.dx", "non-empty list"),
    ({"scenarios": {"base": "no_such_run_config"}}, "run_config", "thesis_scenario1"),
    ({"grid": {"kernel": ["gauss"]}}, "case collapse_2d-base-kernel=gauss: kernel", "cubic_spline"),
    ({"workers": -1}, "workers", ">= 0"),
    ({"colour": "blue"}, "colour", "the fields are"),
])
def test_a_bad_study_names_the_field(tmp_path, changes, field, words):
    with pytest.raises(ConfigError) as err:
        load_study(_study(tmp_path, **changes))
    assert err.value.field == field and words in str(err.value)
