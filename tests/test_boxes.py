"""Filling fluid boxes: the free surface sits at its stated height and the mass follows the fill
(the thesis, Section 4.3 and Fig. 41/46, lost bore velocity to a misplaced top layer)."""
import numpy as np
import pytest

from gpusph_ros.scenes.boxes import box_tank, fill_box
from gpusph_ros.sph import SolverConfig, boundaries

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


@pytest.mark.parametrize("dx", [0.04, 0.03, 0.02, 0.015, 0.01])
def test_every_wall_stands_dx_beyond_the_fluid_whatever_the_tank_width(dx):
    # DamBreak 1's tank is 0.67 m wide: 16.75, 22.3, 33.5, 44.7 and 67 dx at these spacings. Each
    # wall's first boundary layer lies dx/2 out from its face, the fluid's outer layer half its
    # spacing in, the layers dx apart; and the wall holds rho0 times the volume of its shell (a
    # dx lattice from the origin put the far side wall 1 dx out at 2 cm, where fluid crossed the face)
    tank = (1.6, 0.67, 0.4)
    cfg = SolverConfig(dim=3, dx=dx, depth=0.3, gravity=(0.0, 0.0, -9.81))
    column = (0.4, 0.67, 0.3)
    cfg, parts = box_tank(cfg, tank, [((0.0, 0.0, 0.0), column)])
    fluid, wall = parts.pos[parts.ptype == 0], parts.pos[parts.ptype != 0]
    layers = boundaries.model(cfg.boundary).layers(cfg.hdx)
    mid = (fluid[:, 2] > 0.1) & (fluid[:, 2] < 0.2)
    for ax, side in [(0, 0), (1, 0), (1, 1), (2, 0)]:
        face = tank[ax] * side
        sign = 1.0 if side else -1.0
        # the wall particles straight out from the fluid's middle, in the face's normal direction
        beside = np.ones(len(wall), dtype=bool)
        for other in range(3):
            if other != ax:
                beside &= (wall[:, other] > 0.0) & (wall[:, other] < tank[other])
        out = sign * (wall[beside, ax] - face)
        depths = np.unique(np.round(out[out > 0.0], 9))
        assert np.allclose(depths, (np.arange(layers) + 0.5) * dx), (ax, side, depths)
        outer = np.max(sign * (fluid[mid if ax != 2 else slice(None), ax] - face))
        spacing = column[ax] / np.ceil(column[ax] / dx - 1e-9)
        assert outer == pytest.approx(-0.5 * spacing, abs=1e-9), (ax, side)
    pad = layers * dx
    shell = (tank[0] + 2 * pad) * (tank[1] + 2 * pad) * (tank[2] + pad) - np.prod(tank)
    assert parts.mass[parts.ptype != 0].sum() == pytest.approx(cfg.rho0 * shell, rel=1e-9)
