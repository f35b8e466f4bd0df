"""Every measurement a scene asks for, taken together at an output step: point, profile, gauge
and pressure-sensor probes (one interpolation launch for all their points and the obstacles' face
points), depth-averaged columns, the wrench on each obstacle, its pressure-block force and the
load of the wall pressure over its faces. Computed on the solver's device; only the results
come to the host."""
import numpy as np

from .blocks import PressureBlockForce
from .columns import ColumnMeans
from .forces import BodyWrench
from .probes import PointProbes
from .sensors import OFFSET_H, face_load, face_load_points, face_pressure, sensor_points, wall_pressure
from .surface import elevation, gauge_points


class Measurements:
    """The measurements of ``model`` (a ``scenes.build.Model``) on ``solver``."""

    def __init__(self, solver, model):
        scene, cfg = model.scene, solver.config
        dim, up = cfg.dim, cfg.dim - 1
        self.scene = scene
        points, self._slices = [], {}
        for probe in scene.probes:
            if probe.type == "point":
                pts = np.asarray([probe.position])
            elif probe.type == "profile":
                pts = np.repeat(np.asarray([probe.position]), len(probe.heights), axis=0)
                pts[:, up] = probe.heights
            elif probe.type == "gauge":
                pts = gauge_points(probe.position, scene.tank[up], cfg.dx, dim)
            elif probe.type == "pressure_sensor":
                pts = sensor_points(probe, cfg.h, cfg.dx, dim, scene.tank)
            else:
                continue
            self._slices[probe.name] = (len(points), len(points) + len(pts), pts)
            points.extend(pts)
        # each obstacle: its wrench, its pressure blocks, and its faces for the load from the wall
        # pressure (sensors.py), whose points join the probes' interpolation
        self._wrenches, self._blocks, self._faces = {}, {}, {}
        for obstacle in scene.obstacles:
            centre = 0.5 * (np.asarray(obstacle.lo) + np.asarray(obstacle.hi))
            if dim == 2:
                centre[2] = 0.0
            self._wrenches[obstacle.name] = BodyWrench(solver, model.bodies[obstacle.name], centre)
            self._blocks[obstacle.name] = PressureBlockForce(solver, obstacle.lo, obstacle.hi, obstacle.block_offsets)
            pts, normals, areas = face_load_points(obstacle.lo, obstacle.hi, cfg.dx, dim, scene.tank)
            self._faces[obstacle.name] = (len(points), pts, normals, areas, centre)
            points.extend(pts + OFFSET_H * cfg.h * normals)
        self._points = PointProbes(solver, points) if points else None
        self._wall = (cfg.h, cfg.rho0, cfg.gravity)
        columns = [p for p in scene.probes if p.type == "column"]
        self._column_names = [p.name for p in columns]
        self._columns = (ColumnMeans(solver, [p.position for p in columns], [p.radius_dx * cfg.dx for p in columns])
                         if columns else None)

    def sample(self) -> dict:
        """{"points": {name: {vel, pressure, rho}}, "profiles": {name: {heights, vel}},
        "gauges": {name: elevation}, "sensors": {name: wall pressure}, "columns": {name: {vel, count}},
        "wrenches": {name: (force, torque)}, "pressure_loads": {name: (force, torque) from the wall
        pressure}, "blocks": {name: {offset: (fx, upstream, downstream)}}}."""
        out = {"points": {}, "profiles": {}, "gauges": {}, "sensors": {}, "columns": {}, "wrenches": {},
               "pressure_loads": {}, "blocks": {}}
        up = self.scene.dim - 1
        if self._points is not None:
            values = self._points.sample()
            for probe in self.scene.probes:
                if probe.name not in self._slices:
                    continue
                a, b, pts = self._slices[probe.name]
                if probe.type == "point":
                    out["points"][probe.name] = {k: values[k][a] for k in ("vel", "pressure", "rho")}
                elif probe.type == "profile":
                    out["profiles"][probe.name] = {"heights": pts[:, up], "vel": values["vel"][a:b]}
                elif probe.type == "pressure_sensor":
                    out["sensors"][probe.name] = wall_pressure(values["pressure"][a:b], values["weight"][a:b],
                                                               probe.normal, *self._wall)
                else:
                    out["gauges"][probe.name] = elevation(pts[:, up], values["weight"][a:b])
            for name, (a, pts, normals, areas, centre) in self._faces.items():
                b = a + len(pts)
                p_face = face_pressure(values["pressure"][a:b], values["weight"][a:b], normals, *self._wall)
                out["pressure_loads"][name] = face_load(p_face, pts, normals, areas, centre)
        if self._columns is not None:
            values = self._columns.sample()
            for k, name in enumerate(self._column_names):
                out["columns"][name] = {"vel": values["vel"][k], "count": int(values["count"][k])}
        for name, wrench in self._wrenches.items():
            out["wrenches"][name] = wrench.sample()
        for name, blocks in self._blocks.items():
            out["blocks"][name] = blocks.sample()
        return out
