"""Configuration validation: every bad field names itself, its value and what is allowed."""
import pytest

from gpusph_ros.sph import ConfigError, Plane, SolverConfig

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("field, value, allowed", [
    ("kernel", "gauss", "quadratic, cubic_spline, wendland"),
    ("viscosity", "none", "artificial, laminar, sps"),
    ("boundary", "walls", "lennard_jones, monaghan_kajtar, dynamic"),
    ("density_diffusion", "shepard", "none, delta"),
    ("precision", "float16", "float32, float64"),
    ("dim", 4, "2 or 3"),
    ("cfl", 1.5, "[0.01, 1]"),
    ("cfl", 1.0e-12, "[0.01, 1]"),
    ("dt_fixed", 1.0e-12, "0 (adaptive) or a step >= 1e-06 s"),
    ("max_particles", 0, "a whole number >= 1"),
    ("dx", -0.01, "[0.0001, 10]"),
    ("hdx", 0.0, "> 0"),
    ("shepard_every", -1, ">= 0"),
    ("cpu_threads", 1.5, ">= 0"),
    ("gravity", (0.0, 0.0), "3 finite numbers"),
    ("dt_fixed", float("nan"), ">= 0"),
    ("visco_bound_factor", -0.5, "-1 (the wall model's own) or a number in [0, 10]"),
    ("visco_bound_factor", 11.0, "[-1, 10]"),
])
def test_bad_field_is_named_with_allowed_values(field, value, allowed):
    with pytest.raises(ConfigError) as err:
        SolverConfig(**{field: value}).validate()
    assert err.value.field == field
    assert repr(value) in str(err.value)
    assert allowed in str(err.value)


def test_defaults_are_valid_and_c0_follows_depth():
    cfg = SolverConfig(depth=0.4, c0_coef=10.0).validate()
    assert cfg.sound_speed == pytest.approx(10.0 * (9.81 * 0.4) ** 0.5)
    assert cfg.replace(c0=30.0).sound_speed == 30.0
    assert cfg.eos_b == pytest.approx(cfg.sound_speed ** 2 * 1000.0 / 7.0)
    assert cfg.h == pytest.approx(1.3 * cfg.dx)


def test_the_wall_friction_is_the_wall_models_own_unless_set():
    """visco_bound_factor -1 (the default) takes the wall model's: the particle walls that push keep
    DualSPHysics' 1, the extrapolated-pressure wall none; a value set is taken as it is."""
    assert [SolverConfig(boundary=b).wall_friction for b in ("dynamic", "mdbc", "adami")] == [1.0, 1.0, 0.0]
    assert SolverConfig(boundary="adami", visco_bound_factor=0.5).wall_friction == 0.5
    assert SolverConfig(boundary="dynamic", visco_bound_factor=0.0).wall_friction == 0.0


def test_domain_periodic_and_planes_are_checked():
    with pytest.raises(ConfigError, match="domain_hi"):
        SolverConfig(domain_lo=(0, 0, 0), domain_hi=(1, 0, 1)).validate()
    with pytest.raises(ConfigError, match="periodic"):
        SolverConfig(dx=0.02, domain_hi=(0.1, 1, 1), periodic=(True, False, False)).validate()
    with pytest.raises(ConfigError, match=r"planes\[0\]"):
        SolverConfig(planes=[Plane(point=(0, 0, 0), normal=(0, 0, 0))]).validate()
    with pytest.raises(ConfigError, match="gravity"):
        SolverConfig(dim=2, gravity=(0, 0, -9.81)).validate()


def test_on_and_off_read_as_yaml_booleans_are_the_words():
    """``--set step_graph=off`` reads as YAML 1.1's false: a name setting takes it as "off" (and "on"),
    and its choices still decide (``kernel=yes`` names kernel and its choices)."""
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve

    scene = load_scene("collapse_2d")
    assert resolve(scene, sets=["step_graph=off"]).solver.step_graph == "off"
    assert resolve(scene, sets=["step_graph=on"]).solver.step_graph == "on"
    with pytest.raises(ConfigError, match="kernel: 'on' is not allowed; expected one of quadratic, cubic_spline"):
        resolve(scene, sets=["kernel=yes"])
