"""Every measurement a scene asks for, taken together at an output step: point, profile and gauge
probes (one interpolation launch for all their points; a gauge reading the top particle, one
launch for all of them), the obstacles' faces (one wall-pressure launch, sensors.WallPressure),
depth-averaged columns, the wrench on each obstacle, its pressure-block force and the load of the
wall pressure over its faces. The pressure sensors and the wrenches are read at every step and
report the mean over the steps since the last output (transducers.py, forces.py). Computed on the
solver's device; only the results come to the host.

With refinement zones each measurement samples at the spacing of the finest level where it stands
(a gauge's line, a sensor's face and a body's faces every fraction of that spacing, a column's
radius in it, the wall pressure read at its h: sensors.WallPressure); the pressure blocks keep the
scene's dx, the thesis's definition of them."""
import numpy as np

from ..sph.bodies import quaternion_matrix
from ..sph.levels import finest_in, spacing_at
from .blocks import PressureBlockForce
from .columns import ColumnMeans
from .forces import BodyWrench
from .probes import PointProbes
from .ranks import Alone
from .sensors import WallPressure, face_load, face_load_points, face_points
from .surface import TopLevels, elevation, floor_under, gauge_points
from .transducers import Transducers


class Measurements:
    """The measurements of ``model`` (a ``scenes.build.Model``) on ``solver``; ``across``: how the
    ranks of a run add them up (ranks.py; one solver by default)."""

    def __init__(self, solver, model, across=None):
        scene, cfg = model.scene, solver.config
        self.across = across = across or Alone(solver)
        dim, up = cfg.dim, cfg.dim - 1

        def vertical_line(position):  # (lo, hi) of the tank's vertical line through a horizontal point
            lo = np.zeros(3)
            lo[:up] = position[:up]
            hi = lo.copy()
            hi[up] = scene.tank[up]
            return lo, hi

        def line_spacing(position):
            return finest_in(*vertical_line(position), cfg.zones, cfg.dx)
        self.scene, self.solver = scene, solver
        points, self._slices, self._floors = [], {}, {}
        # the obstacles' faces, read by WallPressure at each output; the sensors, read at each step
        # (transducers.py) by the wall model or as the converged reference reads its own (smoothed)
        wall, wall_normals = [], []
        sensors = {"wall": [], "smoothed": []}
        tops = []  # the gauges that read the top particle
        for probe in scene.probes:
            if probe.type == "point":
                pts = np.asarray([probe.position])
            elif probe.type == "profile":
                pts = np.repeat(np.asarray([probe.position]), len(probe.heights), axis=0)
                pts[:, up] = probe.heights
            elif probe.type == "gauge" and probe.reading == "top":
                tops.append(probe)
                continue
            elif probe.type == "gauge":
                pts = gauge_points(probe.position, scene.tank[up], line_spacing(probe.position), dim)
                self._floors[probe.name] = (floor_under(probe.position, scene.obstacles, dim),
                                            2.0 * cfg.hdx * line_spacing(probe.position))
            elif probe.type == "pressure_sensor":
                spacing = spacing_at(probe.position, cfg.zones, cfg.dx)[0]
                pts = face_points(probe.position, probe.normal, probe.diameter, spacing, dim, scene.tank)
                sensors[probe.reading].append((probe.name, pts, [probe.normal] * len(pts), probe.sampling, probe.clip,
                                               probe.response))
                continue
            else:
                continue
            self._slices[probe.name] = (len(points), len(points) + len(pts), pts)
            points.extend(pts)
        # each obstacle: its wrench, its pressure blocks, and its faces for the load from the wall
        # pressure (sensors.py)
        # a moving body's wrench is about where its reference point stands at the sample, in its own
        # axes, and its faces and blocks, fixed in space, are not measured
        self._wrenches, self._blocks, self._faces, self._moving, self._fast = {}, {}, {}, {}, {}
        for obstacle in scene.obstacles:
            centre = np.asarray(obstacle.centre(dim))
            self._wrenches[obstacle.name] = BodyWrench(solver, model.bodies[obstacle.name], centre, across)
            if obstacle.motion is not None:
                self._moving[obstacle.name] = (model.bodies[obstacle.name], centre)
                continue
            self._blocks[obstacle.name] = PressureBlockForce(solver, obstacle.lo, obstacle.hi, obstacle.block_offsets,
                                                             across)
            spacing = finest_in(obstacle.lo, obstacle.hi, cfg.zones, cfg.dx)
            pts, normals, areas = face_load_points(obstacle.lo, obstacle.hi, spacing, dim, scene.tank)
            self._faces[obstacle.name] = (len(wall), pts, normals, areas, centre)
            wall.extend(pts)
            wall_normals.extend(normals)
        self._points = PointProbes(solver, points, across=across) if points else None
        self._wall = WallPressure(solver, wall, wall_normals, across) if wall else None
        self._transducers = [Transducers(solver, found, reading == "smoothed", across)
                             for reading, found in sensors.items() if found]
        self._tops = TopLevels(solver, tops, [line_spacing(p.position) for p in tops], across) if tops else None
        columns = [p for p in scene.probes if p.type == "column"]
        self._column_names = [p.name for p in columns]
        self._columns = (ColumnMeans(solver, [p.position for p in columns],
                                     [p.radius_dx * line_spacing(p.position) for p in columns], across)
                         if columns else None)

    def restart(self):
        """Forget what the measurements that average over steps have summed (a restored state)."""
        for wrench in (*self._wrenches.values(), *self._fast.values(), *self._transducers):
            wrench.restart()

    def start_fast(self):
        """Each body's wrench summed a second time, from now on, for the bodies' messages between
        outputs (runner: wrench_rate): apart from the outputs' sums, so that each reports the mean
        over its own interval. Once; the sums go on after, at one reduction per body and step."""
        if not self._fast:
            self._fast = {name: BodyWrench(self.solver, wrench.body_id, wrench.centre, self.across)
                          for name, wrench in self._wrenches.items()}

    def fast_sample(self) -> dict:
        """{"wrenches", "poses"} as ``sample`` has them, the wrench the mean over the steps since the
        last fast sample (``start_fast``)."""
        return self._bodies(self._fast)

    def _bodies(self, sums: dict) -> dict:
        """{"wrenches": {name: (force, torque)} of ``sums`` (BodyWrench by name), "poses": {name:
        a moving body's pose}}: a moving body's wrench turned into its own axes, about where its
        reference point stands now."""
        wrenches = {name: wrench.sample() for name, wrench in sums.items()}
        out = {"wrenches": wrenches, "poses": {}}
        if self._moving:
            poses = self.solver.body_poses()
            for name, (body, centre) in self._moving.items():
                pose = out["poses"][name] = {**poses[body], "rotation": quaternion_matrix(poses[body]["quaternion"])}
                force, torque = wrenches[name]
                turn = pose["rotation"].T
                about = torque - np.cross(pose["position"] - centre, force)
                wrenches[name] = (turn @ force, turn @ about)
        return out

    def sample(self) -> dict:
        """{"points": {name: {vel, pressure, rho}}, "profiles": {name: {heights, vel}},
        "gauges": {name: elevation}, "sensors": {name: wall pressure}, "columns": {name: {vel, count}},
        "wrenches": {name: (force, torque)}, "pressure_loads": {name: (force, torque) from the wall
        pressure}, "blocks": {name: {offset: (fx, upstream, downstream)}}, "poses": {name: a moving
        body's pose (Solver.body_poses) and its rotation matrix, "rotation"}}. A moving body's wrench
        is in its own axes about its reference point."""
        out = {"points": {}, "profiles": {}, "gauges": {}, "sensors": {}, "columns": {}, "wrenches": {},
               "pressure_loads": {}, "blocks": {}, "poses": {}}
        self.across.view()  # on ranks, together: the view's lists built where any rank's are stale
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
                else:
                    out["gauges"][probe.name] = elevation(pts[:, up], values["weight"][a:b], *self._floors[probe.name])
        if self._tops is not None:
            out["gauges"].update(self._tops.sample())
        if self._wall is not None:
            p_wall = self._wall.sample()
            for name, (a, pts, normals, areas, centre) in self._faces.items():
                out["pressure_loads"][name] = face_load(p_wall[a:a + len(pts)], pts, normals, areas, centre)
        for transducers in self._transducers:
            out["sensors"].update(transducers.sample())
        if self._columns is not None:
            values = self._columns.sample()
            for k, name in enumerate(self._column_names):
                out["columns"][name] = {"vel": values["vel"][k], "count": int(values["count"][k])}
        out.update(self._bodies(self._wrenches))
        for name, blocks in self._blocks.items():
            out["blocks"][name] = blocks.sample()
        return out
