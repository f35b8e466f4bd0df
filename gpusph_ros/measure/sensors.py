"""Wall pressure sensors: what a transducer on a wall or body face reads.

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
at 3 mm on a wall sampled 4.5 mm across); a dry point reads 0 (atmospheric). The reading is the
mean over the face's points.
"""
import math

import numpy as np

OFFSET_H = 1.5  # [h] the interpolation points' distance in front of the face


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


def sensor_points(probe, h: float, dx: float, dim: int, tank) -> np.ndarray:
    """Where the sensor's pressure is interpolated: its face moved OFFSET_H h into the fluid."""
    return face_points(probe.position, probe.normal, probe.diameter, dx, dim, tank) \
        + OFFSET_H * h * np.asarray(probe.normal, dtype=np.float64)


def wall_pressure(pressure, weight, normal, h: float, rho0: float, gravity) -> float:
    """The face's mean pressure from the interpolated ``pressure`` (and kernel ``weight``, 0 where
    dry) at its sensor_points."""
    drop = rho0 * float(np.dot(gravity, normal)) * OFFSET_H * h  # p_wall = p - rho0 (g.n) delta
    wet = np.asarray(weight) > 0.0
    return float(np.mean(np.where(wet, np.asarray(pressure) - drop, 0.0)))
