"""Point probes: velocity, pressure and density at fixed points, interpolated with the run's own
kernel and Shepard-normalised (thesis Section 3.2; Eq. 2.4 divided by the kernel sum Eq. 2.28's
denominator):

    f(x) = sum_b f_b W(x - x_b) V_b / sum_b W(x - x_b) V_b,  V_b = m_b / rho_b, over fluid b.

The normalisation makes a uniform field come back exactly whatever the particle arrangement, so
a probe does not inherit the 1-5% bias of a plain kernel sum on a lattice at h = 1.3 dx. The
interpolation runs on the solver's device; only the probe values come to the host.
"""
import functools

import numpy as np
import warp as wp

from ..sph import eos, kernels, neighbours, state
from ..sph.state import FLUID
from .ranks import Alone


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    K = kernels.build(scalar)
    kernel_w, smoothing = K.w, K.smoothing
    N = neighbours.grid(scalar)
    Grid, separation, cell_coord, neighbour_cell = N.Grid, N.separation, N.cell_coord, N.neighbour_cell
    S = state.build(scalar)
    Params, Fields = S.Params, S.Fields
    eos_pressure = eos.build(scalar).pressure

    @wp.kernel(enable_backward=False, module="unique")
    def interpolate(p: Params, grid: Grid, start: wp.array(dtype=wp.int32), end: wp.array(dtype=wp.int32),
                    order: wp.array(dtype=wp.int32), f: Fields, points: wp.array(dtype=vec), widen: int,
                    vel: wp.array(dtype=vec), pressure: wp.array(dtype=scalar), rho: wp.array(dtype=scalar),
                    weight: wp.array(dtype=scalar)):
        """The Shepard interpolation at each point with each particle's kernel ``widen`` times as
        wide (1: the run's own), over the cells that kernel reaches. The pressure from each
        particle's density (thesis Eq. 2.12), which the step loop keeps up to date where the pressure
        array is not: a sensor reads inside the step (sensors.Transducers)."""
        k = wp.tid()
        x = points[k]
        ci = cell_coord(grid, x)
        u = vec(scalar(0.0))
        pr = scalar(0.0)
        r = scalar(0.0)
        wsum = scalar(0.0)
        wide = scalar(widen)
        wide_norm = wide * wide
        if p.dim == 3:
            wide_norm = wide_norm * wide
        reach, reach_z = grid.reach * widen, grid.reach_z * widen
        for cz in range(-reach_z, reach_z + 1):
            for cy in range(-reach, reach + 1):
                for cx in range(-reach, reach + 1):
                    cell = neighbour_cell(grid, ci, cx, cy, cz)
                    if cell < 0:
                        continue
                    for s in range(start[cell], end[cell]):
                        b = order[s]
                        if f.ptype[b] != FLUID:
                            continue
                        # each particle's own kernel (scatter form) where spacings differ
                        h, inv_h, norm, scale = smoothing(p, f.hsml[b], f.hsml[b])
                        w = kernel_w(p.kernel, norm / wide_norm, inv_h / wide,
                                     wp.length(separation(grid, x, f.pos[b])))
                        wv = w * f.mass[b] / f.rho[b]
                        u += wv * f.vel[b]
                        pr += wv * eos_pressure(f.rho[b], p.rho0, p.eos_b, p.gamma)
                        r += wv * f.rho[b]
                        wsum += wv
        weight[k] = wsum
        if wsum > scalar(0.0):
            vel[k] = u / wsum
            pressure[k] = pr / wsum
            rho[k] = r / wsum
        else:
            vel[k] = vec(scalar(0.0))
            pressure[k] = scalar(0.0)
            rho[k] = scalar(0.0)

    return interpolate


class PointProbes:
    """Probes at fixed points of one solver, each particle's kernel ``widen`` times the run's (2: a
    sensor that reads as De Courcy et al. 2024 read theirs: sensors.py). ``sample()`` returns host
    arrays. ``across``: how the ranks of a run add a reading up (ranks.py; one solver by default)."""

    def __init__(self, solver, points, widen: int = 1, across=None):
        self.solver = solver
        self.widen = int(widen)
        self.across = across or Alone(solver)
        self.host_points = pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        dev = solver.device
        self._interpolate = build(solver.scalar)
        self.points = wp.array(pts, dtype=solver.vec, device=dev)
        k = len(pts)
        self._vel = wp.zeros(k, dtype=solver.vec, device=dev)
        self._pressure = wp.zeros(k, dtype=solver.scalar, device=dev)
        self._rho = wp.zeros(k, dtype=solver.scalar, device=dev)
        self._weight = wp.zeros(k, dtype=solver.scalar, device=dev)

    def launch(self, view):
        """Interpolate on the device from ``view`` = (params, fields, neighbours) into the arrays
        ``pressure`` and ``weight`` (and the velocity and density); no host copy."""
        params, fields, nl = view
        wp.launch(self._interpolate, dim=self.points.shape[0],
                  inputs=[params, nl.grid, nl.cell_start, nl.cell_end, nl.order, fields, self.points, self.widen,
                          self._vel, self._pressure, self._rho, self._weight], device=self.solver.device)
        return self._pressure, self._weight

    def sample(self) -> dict:
        """vel (k x 3), pressure, rho, and weight = sum W V (0 where no fluid is within 2h: a dry
        probe, whose other values are then 0)."""
        self.launch(self.across.view())
        arrays = {"vel": self._vel, "pressure": self._pressure, "rho": self._rho, "weight": self._weight}
        return {k: self.across.pick(a.numpy(), self.host_points).astype(np.float64) for k, a in arrays.items()}
