"""The packed particle rows (gpusph_ros.measure.cloud): the solver's state in scene order, as
float32, whatever the solver's precision, order of arrays or field choice."""
import numpy as np
import pytest

from gpusph_ros.measure.cloud import FIELDS, CloudPacker
from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene, parse_scene
from gpusph_ros.sph import Solver
from gpusph_ros.sph.state import FLUID

pytestmark = pytest.mark.unit


@pytest.fixture(scope="module", params=["float32", "float64"])
def solver(request):
    model = build(load_scene("dambreak1_thesis"), dx=0.06, precision=request.param)
    s = Solver(model.config, model.particles)
    s.advance(0.02)  # the arrays have been re-sorted into cell order since the fill
    return s


def test_rows_are_the_snapshot_in_scene_order_as_float32(solver):
    rows = CloudPacker(solver).pack()
    snap = solver.snapshot()
    # kind: 0 fluid, 1 a wall, 2 + k body k
    kind = np.where(snap["ptype"] == FLUID, 0, np.where(snap["body"] >= 0, 2 + snap["body"], 1))
    spacing = np.full(solver.n, solver.config.dx)
    expected = np.column_stack([snap["pos"], snap["vel"], snap["rho"], snap["pressure"], kind,
                                spacing]).astype(np.float32)
    assert rows.dtype == np.float32 and rows.shape == (solver.n, 3 + len(FIELDS))
    assert np.array_equal(rows, expected)


def test_a_field_subset_in_the_order_asked(solver):
    rows = CloudPacker(solver, ["pressure", "vz"]).pack()
    snap = solver.snapshot()
    assert np.array_equal(rows[:, 3], snap["pressure"].astype(np.float32))
    assert np.array_equal(rows[:, 4], snap["vel"][:, 2].astype(np.float32))
    assert CloudPacker(solver, []).pack().shape == (solver.n, 3)


def test_an_unknown_field_is_refused_with_the_choices(solver):
    with pytest.raises(ValueError, match="'speed' is not one of vx, vy, vz, density, pressure, kind"):
        CloudPacker(solver, ["speed"])


def test_the_spacing_field_tells_a_zones_particles_from_the_scenes():
    """A zone's active particles carry its spacing, the rest the scene's dx; the passive particles
    are left out of the cloud (sph.levels)."""
    scene = parse_scene({"name": "tank", "dim": 2, "tank": [0.6, 0.32],
                         "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.6, 0.2]}],
                         "refine": [{"name": "middle", "lo": [0.2, 0.0], "hi": [0.4, 0.32], "ratio": 0.5}]})
    model = build(scene, dx=0.02)
    solver = model.solver()
    rows = CloudPacker(solver, ["kind", "spacing"]).pack()
    x, spacing = rows[:, 0].astype(np.float64), rows[:, 4]
    assert set(np.unique(spacing)) == {np.float32(0.01), np.float32(0.02)}
    fine_fluid = (rows[:, 3] == 0) & (spacing == np.float32(0.01))
    assert fine_fluid.sum() > 100 and np.all((x[fine_fluid] > 0.2) & (x[fine_fluid] < 0.4))
    coarse_fluid = (rows[:, 3] == 0) & (spacing == np.float32(0.02))
    assert coarse_fluid.sum() > 100 and not np.any((x[coarse_fluid] > 0.2) & (x[coarse_fluid] < 0.4))
