"""The walls' term of the continuity equation over a flat face with the face-normal relative
velocity only (the run setting ``wall_flux: normal``; density.wall_flux, passes.wall_normal_at,
issue 68).

- Geometry: each wall particle's face normal is the unit vector towards its ghost node
  (boundaries/faces.py): up on the floor and on an obstacle's top, out of an obstacle's end face,
  diagonal at an edge, and never along a periodic axis, under either wall that uses them (an
  obstacle across a periodic axis has no face there: mDBC's ghost nodes had one).
- The 3D thin sheet (scenes.exact.thin_sheet) at 2 cm, 3 spacings deep at 1 m/s over a plate: while
  it slides, the plate's sensors at x = 0.25 and 0.40 m read rho g h, h the local depth above them,
  within 5% on average, and their published series scatter from one 10 ms output to the next by at
  most 10% of their mean. With the full relative velocity the sheet's particles passing over the
  wall's particles drive a pressure wave across the sheet at U / dx = 50 Hz and the same series
  scatter by 37% and 40% (bench/thin_sheet.py, docs/results/thin_sheet.md).
"""
import numpy as np
import pytest

from gpusph_ros.measure.suite import Measurements
from gpusph_ros.scenes.build import build_run
from gpusph_ros.scenes.exact import PLATE_END, PLATE_TOP, thin_sheet
from gpusph_ros.scenes.settings import resolve
from gpusph_ros.sph.state import BOUNDARY, FLUID

DX, DEPTH, U = 0.02, 3, 1.0


@pytest.mark.unit
def test_a_wall_particles_normal_points_at_its_ghost_node_and_never_along_a_periodic_axis():
    scene = thin_sheet(DX, DEPTH)
    for boundary in ("adami", "mdbc"):
        built = build_run(scene, resolve(scene, dx=DX, end_time=0.01, wall_flux="normal", boundary=boundary))
        solver = built.solver()
        b = solver.ptype.numpy() == BOUNDARY
        pos, n = solver.pos.numpy()[b].astype(np.float64), solver.wall_normal.numpy()[b].astype(np.float64)
        assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
        assert np.all(n[:, 1] == 0.0)  # y is periodic
        ghost = solver.ghost.numpy()[b]
        assert np.all(ghost[:, 1] == 0.0)
        plate = solver.body.numpy()[b] >= 0
        top = plate & (pos[:, 2] > PLATE_TOP - DX) & (pos[:, 0] < PLATE_END - 2 * DX)
        end = plate & (pos[:, 0] > PLATE_END - DX) & (pos[:, 2] < PLATE_TOP - 2 * DX)
        corner = plate & (pos[:, 0] > PLATE_END - DX) & (pos[:, 2] > PLATE_TOP - DX)
        assert top.any() and np.allclose(n[top], [0.0, 0.0, 1.0], atol=1e-6)
        assert end.any() and np.allclose(n[end], [1.0, 0.0, 0.0], atol=1e-6)
        assert corner.any() and np.allclose(n[corner], [0.5 ** 0.5, 0.0, 0.5 ** 0.5], atol=1e-5)
        floor = ~plate & (pos[:, 2] < 0.0) & (pos[:, 0] > PLATE_END + 2 * DX) & (pos[:, 0] < 1.0 - 2 * DX)
        assert floor.any() and np.allclose(n[floor], [0.0, 0.0, 1.0], atol=1e-6)


@pytest.mark.physics
def test_a_sheet_sliding_over_a_plate_reads_hydrostatic_pressure_without_the_walls_beat():
    scene = thin_sheet(DX, DEPTH)
    built = build_run(scene, resolve(scene, dx=DX, end_time=0.15, wall_flux="normal"))
    fluid = built.particles.ptype == FLUID
    built.particles.vel[fluid, 0] = U
    solver = built.solver()
    measurements = Measurements(solver, built)
    read = {x: [] for x in (0.25, 0.40)}
    for k in range(1, 15):
        solver.advance(0.01 * k)
        snap = solver.snapshot()
        x, z = snap["pos"][fluid, 0], snap["pos"][fluid, 2]
        sensors = measurements.sample()["sensors"]
        for x0, series in read.items():
            h = z[np.abs(x - x0) < DX].max() + 0.5 * DX - PLATE_TOP
            series.append((sensors[f"plate_{round(x0 * 100)}cm"], 1000.0 * 9.81 * h))
    for x0, series in read.items():
        p, hydrostatic = np.asarray(series[1:]).T  # from 0.02 s: the first output's mean holds the start
        assert abs(np.mean(p / hydrostatic) - 1.0) <= 0.05, x0
        assert np.sqrt(np.mean(np.diff(p) ** 2)) <= 0.10 * p.mean(), x0
