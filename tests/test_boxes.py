"""Filling fluid boxes: the free surface sits at its stated height and the mass follows the fill
(the thesis, Section 4.3 and Fig. 41/46, lost bore velocity to a misplaced top layer)."""
import numpy as np
import pytest

from gpusph_ros.scenes.boxes import box_tank, fill_box
from gpusph_ros.sph import SolverConfig

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("dx", [0.006, 0.0075, 0.01, 0.0125, 0.015, 0.02, 0.03])
@pytest.mark.parametrize("depth", [0.10, 0.15, 0.4])
def test_top_layer_within_half_dx_of_the_surface_and_mass_matches(dx, depth):
    lo, hi = (0.0, 0.0, 0.0), (0.3, 0.1, depth)
    pts, volume = fill_box(lo, hi, dx, 3)
    layers = np.unique(np.round(pts[:, 2], 12))
    spacing = np.diff(layers)
    top = layers[-1]
    assert 0.0 < depth - top <= 0.5 * dx + 1e-12
    assert np.allclose(spacing, 2 * (depth - top))  # the surface is half a spacing above the top layer
    assert len(pts) * volume == pytest.approx(0.3 * 0.1 * depth, rel=1e-12)  # mass = rho0 x volume
    assert (spacing <= dx + 1e-12).all() and (spacing > 0.8 * dx).all()


def test_box_tank_gives_each_box_the_mass_of_its_volume():
    cfg = SolverConfig(dim=3, dx=0.015, depth=0.4, gravity=(0.0, 0.0, -9.81))
    boxes = [((0.0, 0.0, 0.0), (0.4, 0.67, 0.4)), ((0.4, 0.0, 0.0), (1.6, 0.67, 0.01))]
    cfg, parts = box_tank(cfg, (1.6, 0.67, 0.4), boxes)
    fluid = parts.ptype == 0
    volume = 0.4 * 0.67 * 0.4 + 1.2 * 0.67 * 0.01
    assert parts.mass[fluid].sum() == pytest.approx(1000.0 * volume, rel=0.01)
    column = fluid & (parts.pos[:, 0] < 0.4)
    assert 0.4 - parts.pos[column, 2].max() <= 0.5 * cfg.dx
