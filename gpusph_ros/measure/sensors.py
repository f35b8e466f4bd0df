"""Wall pressure: what a transducer on a wall or body face reads, and the load on a body from the
pressure over its faces.

A transducer averages the pressure over its face. Under walls of boundary particles the fluid
next to a wall is half-supported and the wall particles' own pressure is noise (dynamic boundary
particles answer every approaching fluid particle), so a point at the wall reads neither.
DualSPHysics' pressure-probe examples with dynamic boundaries put their probes 1.5 h in front of
the wall for that reason; so do we: the sensor's face (a segment across the normal in 2D, a disc
in 3D, sampled every dx/2) is moved ``OFFSET_H`` h along the inward normal n, the pressure is
interpolated there (probes.py: Shepard-normalised, so the fluid's kernel deficit near the free
surface and the wall does not bias it), and brought back to the face with the normal pressure
gradient a rigid wall imposes. Euler's equation along n at a wall whose fluid cannot move through
it (u.n = 0, so the fluid's normal acceleration is the wall's, zero) leaves

    dp/dn = rho (g . n),   p_wall = p(x + delta n) - rho0 (g . n) delta,   delta = OFFSET_H h,

exact for hydrostatics (a floor sensor's 1.5 h of water added back; nothing on a side wall) and
first order in delta during an impact. Points of the face outside the tank are dropped (a sensor
at 3 mm on a wall sampled 4.5 mm across); a dry point reads 0 (atmospheric). A sensor reads the
mean over its face's points.

A box body's load from the wall pressure (``face_load_points``, ``face_load``): each face the fluid
can reach (not one lying on a tank wall or the floor) tiled in cells dx/2 across, the wall pressure
at each cell's centre as above, F = -sum p n dA and T = sum (x - c) x (-p n dA) about the centre c;
in 2D per unit depth. This is what a load cell behind a rigid face reads of the pressure, without
the boundary particles' own noise that the net force on them carries (forces.py).

Under mDBC (sph/boundaries/mdbc.py) the wall's own pressure is usable and no offset is needed: each face point
reads the boundary's pressure, mDBC's first-order extrapolation of the fluid from the ghost node of
the first boundary layer (dx/2 in front of the face) evaluated at the face (``WallPressure``),
times the wet share of the support at the face (``interpolate.wet_share``, as below): on DamBreak 1
at 3 cm the load's peak read 111.7 N without it against the particles' 27.8 N, 24.1 N with it.
Under the extrapolated-pressure wall (sph/boundaries/adami.py) each face point reads the wall's own
condition, Adami et al. (2012) Eq. 27, at the point itself: the Shepard mean of the fluid's pressure
carried to the face with rho (g . r), times the wet share of the support (the fluid's kernel sum
over the room the walls leave, at most 1: a Shepard mean fills a dry part of the support with the
fluid present), before the wall particles' clamp at ambient (on the impinging
jet at ten particles across the stagnation point reads -6.8% averaged over every step, where the
fluid 1.5 h out brought back to the face read -13%: docs/results/wall_pressure.md).

A sensor's ``reading: smoothed`` reads as De Courcy et al. (2024) read the converged 2D reference
(data/decourcy_2024_dambreak_2d_converged, its README) and as TrixiParticles' validation does: at
each point of the face itself the fluid's Shepard pressure with a kernel of twice the run's smoothing
length (``SMOOTHED_WIDEN``; it reaches 4 h into the fluid), negative pressures clipped to zero, 0
where dry (``smoothed_face_pressure``). It reads any wall treatment the same way.
"""
import math

import numpy as np
import warp as wp

from ..sph import boundaries, levels
from .probes import PointProbes
from .ranks import Alone

OFFSET_H = 1.5  # [h] the interpolation points' distance in front of the face
SMOOTHED_WIDEN = 2  # a smoothed reading's kernel, in the run's smoothing lengths (De Courcy et al. 2024)


def face_points(position, normal, diameter: float, dx: float, dim: int, tank) -> np.ndarray:
    """Points of the sensor face every dx/2 (the centre alone for a face narrower than that),
    inside the tank [0, tank]."""
    c, n = np.asarray(position, dtype=np.float64), np.asarray(normal, dtype=np.float64)
    radius = 0.5 * diameter
    steps = int(math.floor(radius / (0.5 * dx)))
    offsets = np.arange(-steps, steps + 1) * 0.5 * dx
    if dim == 2:
        t = np.array([-n[1], n[0], 0.0])
        pts = c + offsets[:, None] * t
    else:
        a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        t1 = np.cross(n, a)
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(n, t1)
        s1, s2 = np.meshgrid(offsets, offsets, indexing="ij")
        inside = s1 ** 2 + s2 ** 2 <= radius ** 2 + 1e-12
        pts = c + s1[inside][:, None] * t1 + s2[inside][:, None] * t2
    lo, hi = -1e-9, np.asarray(tank, dtype=np.float64) + 1e-9
    keep = np.all((pts[:, :dim] >= lo) & (pts[:, :dim] <= hi[:dim]), axis=1)
    return pts[keep] if keep.any() else c[None, :]


def face_pressure(pressure, weight, drop) -> np.ndarray:
    """The pressure on the face at each point from the ``pressure`` and kernel ``weight`` read for it
    (0 where dry) less ``drop`` (wall_drop: the offset's hydrostatic part where the fluid was read in
    front of the face, else 0)."""
    return np.where(np.asarray(weight) > 0.0, np.asarray(pressure) - np.asarray(drop), 0.0)


def wall_drop(normals, h, rho0: float, gravity) -> np.ndarray:
    """rho0 (g . n) delta at each point, delta = OFFSET_H h: p_wall = p(x + delta n) - that."""
    return rho0 * (np.asarray(normals, dtype=np.float64) @ np.asarray(gravity, dtype=np.float64)) * OFFSET_H * h


def smoothed_face_pressure(values: dict) -> np.ndarray:
    """The smoothed reading at each face point from PointProbes(..., widen=SMOOTHED_WIDEN) at the
    points themselves: the pressure clipped at zero, 0 where no fluid is near."""
    return np.where(np.asarray(values["weight"]) > 0.0, np.maximum(np.asarray(values["pressure"]), 0.0), 0.0)


class WallPressure:
    """The pressure on wall faces at fixed points (n x 3) with their inward normals (n x 3), in the
    way right for the solver's boundary model (see the module docstring); ``sample()`` returns the
    pressure at each point, 0 where dry. Each point reads at the spacing and smoothing length of
    the level that is the flow where it stands (``spacing``: a refinement zone's inside it).
    ``across``: how the ranks of a run add a reading up (ranks.py)."""

    def __init__(self, solver, points, normals, across=None):
        cfg = solver.config
        self.solver = solver
        self.across = across or Alone(solver)
        self.points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        self.normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
        self.spacing = levels.spacing_at(self.points, cfg.zones, cfg.dx)
        h = cfg.hdx * self.spacing  # as the solver makes its particles' (Solver: hdx x spacing)
        self._kernel = boundaries.model(cfg.boundary).face_pressure(solver.scalar)
        if self._kernel is not None:  # the wall's own pressure is usable
            dev, n = solver.device, len(self.points)
            self._pts = wp.array(self.points, dtype=solver.vec, device=dev)
            self._nrm = wp.array(self.normals, dtype=solver.vec, device=dev)
            self._spacing = wp.array(self.spacing, dtype=solver.scalar, device=dev)
            self._pressure = wp.zeros(n, dtype=solver.scalar, device=dev)
            self._weight = wp.zeros(n, dtype=solver.scalar, device=dev)
            self._probes = None
            self.drop = np.zeros(n)
        else:
            self._probes = PointProbes(solver, self.points + OFFSET_H * h[:, None] * self.normals)
            self.drop = wall_drop(self.normals, h, cfg.rho0, cfg.gravity)

    def launch(self, view):
        """Read every point on the device from ``view`` = (params, fields, neighbours): (pressure,
        weight) device arrays, the pressure before ``drop`` is taken off (face_pressure)."""
        if self._probes is not None:
            return self._probes.launch(view)
        params, fields, nl = view
        wp.launch(self._kernel, dim=len(self.points),
                  inputs=[params, nl.grid, nl.cell_start, nl.cell_end, nl.order, fields, self._pts, self._nrm,
                          self._spacing, self._pressure, self._weight], device=self.solver.device)
        return self._pressure, self._weight

    def sample(self) -> np.ndarray:
        pressure, weight = self.launch(self.across.view())
        pick = self.across.pick
        return face_pressure(pick(pressure.numpy(), self.points).astype(np.float64), pick(weight.numpy(), self.points),
                             self.drop)


def face_load_points(lo, hi, dx: float, dim: int, tank):
    """Cell centres (n x 3), inward normals (n x 3, out of the body into the fluid) and cell areas
    (n; lengths in 2D) tiling the faces of the box [lo, hi] the fluid can reach."""
    lo, hi, tank = (np.asarray(v, dtype=np.float64) for v in (lo, hi, tank))
    pts, normals, areas = [], [], []
    for ax in range(dim):
        for side, sign in ((lo, -1.0), (hi, 1.0)):
            if side[ax] <= 1e-9 or side[ax] >= tank[ax] - 1e-9:
                continue  # on the floor or a tank wall: no fluid behind it
            across = [a for a in range(dim) if a != ax]
            counts = [max(1, int(math.ceil((hi[a] - lo[a]) / (0.5 * dx)))) for a in across]
            axes = [lo[a] + (np.arange(c) + 0.5) * (hi[a] - lo[a]) / c for a, c in zip(across, counts)]
            grid = np.meshgrid(*axes, indexing="ij")
            face = np.zeros((grid[0].size, 3))
            face[:, ax] = side[ax]
            for a, g in zip(across, grid):
                face[:, a] = g.ravel()
            n = np.zeros(3)
            n[ax] = sign
            pts.append(face)
            normals.append(np.repeat(n[None, :], len(face), axis=0))
            areas.append(np.full(len(face), np.prod([(hi[a] - lo[a]) / c for a, c in zip(across, counts)])))
    return np.concatenate(pts), np.concatenate(normals), np.concatenate(areas)


def face_load(p_face, points, normals, areas, centre):
    """(force, torque about ``centre``) on the body from the pressure ``p_face`` on its faces."""
    df = -(np.asarray(p_face) * np.asarray(areas))[:, None] * normals
    return df.sum(axis=0), np.cross(points - np.asarray(centre), df).sum(axis=0)
