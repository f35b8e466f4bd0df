"""The stability study (gpusph_ros.study.stability): the bisection brackets a known limit, a
combination's settings reach the solver, and a real probe tells a sound speed too low for the
2D column collapse (density out of bounds) from the thesis's 10 sqrt(g H)."""
import math

import pytest

from gpusph_ros.study import stability as st

pytestmark = pytest.mark.study


@pytest.mark.parametrize("limit", [0.137, 0.55, 0.99])
def test_search_brackets_the_largest_stable_value(limit):
    calls = []

    def fails(x):
        calls.append(x)
        return "density_bounds" if x > limit else ""

    found, failure, runs = st.search(fails, 0.1, 1.0, "lo", iterations=6)
    assert runs == len(calls) == 8
    assert failure == "density_bounds"
    assert found <= limit < found * 10 ** (1 / 2 ** 6) * (1 + 1e-12)  # within one bisection step (log scale)


def test_search_for_the_smallest_stable_value_and_the_ends():
    found, failure, runs = st.search(lambda x: "clumping" if x < 4.2 else "", 2.0, 20.0, "hi", iterations=5)
    assert found >= 4.2 and found / 4.2 < 10 ** (1 / 32) + 1e-12 and failure == "clumping"
    assert st.search(lambda x: "", 2.0, 20.0, "hi", 5) == (2.0, "", 1)  # stable everywhere: the far end
    assert st.search(lambda x: "non_finite", 0.1, 1.0, "lo", 5) == (None, "non_finite", 2)  # never stable


def test_combinations_and_their_settings():
    combos = st.combinations()
    assert len(combos) == 3 * 3 * 6 * 3 * 2 * 2 == 648  # kernels, viscosities, walls, densities, shifting, XSPH
    planes = st.Combination("wendland", "sps", "planes", "shepard", xsph="on").settings()
    assert planes == {"kernel": "wendland", "viscosity": "sps", "density_diffusion": "none", "shepard_every": 40,
                      "shifting": False, "xsph": True, "wall_planes": True}
    assert st.Combination("quadratic", "laminar", "dynamic", "delta").settings()["boundary"] == "dynamic"


def test_a_real_probe_finds_a_sound_speed_too_low():
    settings = {**st.Combination("cubic_spline", "artificial", "dynamic", "delta").settings(),
                "dx": 0.05715 / 10, "end_time": 0.1, "output_rate": 10.0, "particle_rate": 0.0}
    assert st.trial("collapse_2d", {**settings, "c0_coef": 2.0}) == "density_bounds"
    assert st.trial("collapse_2d", {**settings, "c0_coef": 10.0}) == ""


def test_table_and_map(tmp_path):
    rows = [{"kernel": "wendland", "viscosity": "artificial", "boundary": "dynamic", "density": "delta", "cfl_max": 0.6,
             "cfl_failure": "density_bounds", "c0_coef_min": 3.1, "c0_failure": "wall_penetration", "runs": 12,
             "wall_s": 5.0},
            {"kernel": "quadratic", "viscosity": "sps", "boundary": "planes", "density": "none", "cfl_max": None,
             "cfl_failure": "non_finite", "c0_coef_min": None, "c0_failure": "non_finite", "runs": 4, "wall_s": 1.0}]
    st.write(rows, tmp_path / "stability.csv")
    assert st.read(tmp_path / "stability.csv")[0]["cfl_max"] == 0.6
    md, png = st.report(tmp_path)
    text = md.read_text()
    # rows of a table from before the shifting and XSPH dimensions read as both off
    assert "| wendland | artificial | dynamic | delta | off | off | 0.6 | density_bounds | 3.1 | wall_penetration |" \
        in text
    assert "| quadratic | sps | planes | none | off | off | fails | non_finite | fails | non_finite |" in text
    assert png.stat().st_size > 10_000
    assert math.isfinite(rows[0]["cfl_max"])
