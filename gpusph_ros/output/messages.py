"""Solver output to ROS messages: particle clouds, wrenches, probe values, /clock.

Topic names are the node's (``/sim_node/...`` by default; the headless runner records under the
same names, so one analysis reads both). Stamps are simulated time. Points and vectors are in the
published axes (z up, ``frames``); a body's wrench is in its own frame, about its centre.
"""
import array

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import PointStamped, PoseStamped, Vector3Stamped, WrenchStamped
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import FluidPressure, PointCloud2, PointField

from . import frames


def stamp(t: float, origin_ns: int = 0) -> Time:
    """Simulated time [s] as builtin_interfaces/Time, counted from ``origin_ns`` [ns]."""
    ns = origin_ns + int(round(t * 1e9))
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def _stamps(msg):
    """The stamps a message carries: its header's, a clock's, or those of the items it lists."""
    if hasattr(msg, "header"):
        return [msg.header]
    if hasattr(msg, "clock"):
        return [msg]
    items = getattr(msg, "markers", None) or getattr(msg, "transforms", None) or []
    return [item.header for item in items]


def restamp(msg, t: float, origin_ns: int):
    """``msg`` (built at simulated time ``t``) with every stamp counted from ``origin_ns`` instead
    of 0: the outputs of a run stamped with the wall clock of its start."""
    for holder in _stamps(msg):
        if hasattr(holder, "clock"):
            holder.clock = stamp(t, origin_ns)
        else:
            holder.stamp = stamp(t, origin_ns)
    return msg


def clock(t: float) -> Clock:
    return Clock(clock=stamp(t))


class CloudBuilder:
    """PointCloud2 messages from packed float32 rows (``measure.cloud.CloudPacker``): the field
    layout is made once, the data is one copy of the rows' bytes."""

    def __init__(self, fields, frame_id: str = "world"):
        self.fields = tuple(fields)
        self.frame_id = frame_id
        self._layout = [PointField(name=name, offset=4 * k, datatype=PointField.FLOAT32, count=1)
                        for k, name in enumerate(self.fields)]

    def build(self, t: float, rows: np.ndarray) -> PointCloud2:
        n, step = rows.shape[0], rows.shape[1] * 4
        data = array.array("B")
        data.frombytes(rows.data.cast("B"))
        msg = PointCloud2(height=1, width=n, fields=self._layout, is_bigendian=False, point_step=step,
                          row_step=step * n, is_dense=True)
        msg.header.stamp = stamp(t)
        msg.header.frame_id = self.frame_id
        msg.data = data
        return msg


def cloud_arrays(msg) -> dict:
    """The fields of a PointCloud2 of float32 fields as numpy arrays (for readers and tests)."""
    names = [f.name for f in msg.fields]
    values = np.frombuffer(bytes(msg.data), dtype="<f4").reshape(msg.width * msg.height, len(names))
    return {name: values[:, k] for k, name in enumerate(names)}


def _header(msg, t, frame_id):
    msg.header.stamp = stamp(t)
    msg.header.frame_id = frame_id
    return msg


def _vec(target, values):
    target.x, target.y, target.z = (float(v) for v in values)


def wrench(t, force, torque, frame_id="world") -> WrenchStamped:
    msg = _header(WrenchStamped(), t, frame_id)
    _vec(msg.wrench.force, force)
    _vec(msg.wrench.torque, torque)
    return msg


def vector(t, values, frame_id="world") -> Vector3Stamped:
    msg = _header(Vector3Stamped(), t, frame_id)
    _vec(msg.vector, values)
    return msg


def point(t, values, frame_id="world") -> PointStamped:
    msg = _header(PointStamped(), t, frame_id)
    _vec(msg.point, values)
    return msg


def body_motion(t, pose: dict, dim: int, frame_id: str, child: str) -> tuple:
    """A moving body's pose (PoseStamped in the world frame) and odometry (Odometry: the pose, and
    the twist in the body's own frame, ``child``), in the published axes, from a pose of a
    measurement sample (``measure.suite``: position, rotation matrix, velocity, omega)."""
    rotation = pose["rotation"]
    position = frames.published(dim, pose["position"])
    q = frames.published_rotation(dim, rotation)
    stamped = _header(PoseStamped(), t, frame_id)
    odometry = _header(Odometry(), t, frame_id)
    odometry.child_frame_id = child
    for target in (stamped.pose, odometry.pose.pose):
        _vec(target.position, position)
        target.orientation.x, target.orientation.y, target.orientation.z, target.orientation.w = q
    _vec(odometry.twist.twist.linear, frames.published(dim, rotation.T @ pose["velocity"]))
    _vec(odometry.twist.twist.angular, frames.published(dim, rotation.T @ pose["omega"]))
    return stamped, odometry


def pressure(t, value, frame_id="world") -> FluidPressure:
    msg = _header(FluidPressure(), t, frame_id)
    msg.fluid_pressure = float(value)
    return msg


def block_topic(offset: float) -> str:
    """Topic suffix of the pressure-block force at ``offset`` [m] from the faces: d060mm."""
    return f"d{int(round(offset * 1000)):03d}mm"


def measurement_messages(t: float, sample: dict, scene, namespace: str = "/sim_node", frame_id: str = "world"):
    """(topic, message) pairs for one measurement sample (``measure.suite.Measurements``):
    velocity at point probes (Vector3Stamped) and their pressure (FluidPressure), a wall pressure
    sensor's reading (FluidPressure), depth-averaged
    velocity (Vector3Stamped), profile points (Vector3Stamped per height, h0, h1, ...), surface
    elevation (PointStamped at the gauge, z = elevation), the wrench on each body in its frame
    (the net force on its particles, and the load of the wall pressure over its faces), each
    body's pressure-block force (WrenchStamped, force.x only), and a moving body's pose and odometry
    (body_motion)."""
    out = []
    probes = f"{namespace}/probes"

    def turned(values):
        return frames.published(scene.dim, values)

    for name, values in sample["points"].items():
        out.append((f"{probes}/{name}", vector(t, turned(values["vel"]), frame_id)))
        out.append((f"{probes}/{name}/pressure", pressure(t, values["pressure"], frame_id)))
    for name, value in sample.get("sensors", {}).items():
        out.append((f"{probes}/{name}", pressure(t, value, frame_id)))
    for name, values in sample["columns"].items():
        out.append((f"{probes}/{name}", vector(t, turned(values["vel"]), frame_id)))
    for name, values in sample["profiles"].items():
        for k, vel in enumerate(values["vel"]):
            out.append((f"{probes}/{name}/h{k}", vector(t, turned(vel), frame_id)))
    up = scene.dim - 1
    positions = {p.name: p.position for p in scene.probes}
    for name, level in sample["gauges"].items():
        where = list(positions[name])
        where[up] = level
        out.append((f"{probes}/{name}", point(t, turned(where), frame_id)))
    out += body_messages(t, sample, scene.dim, namespace, frame_id)
    for name, (force, torque) in sample.get("pressure_loads", {}).items():
        out.append((f"{namespace}/bodies/{name}/pressure_load",
                    wrench(t, turned(force), turned(torque), frames.body_frame(frame_id, name))))
    for name, by_offset in sample["blocks"].items():
        for offset, (fx, _, _) in by_offset.items():
            out.append((f"{namespace}/bodies/{name}/pressure_blocks/{block_topic(offset)}",
                        wrench(t, (fx, 0.0, 0.0), (0.0, 0.0, 0.0), frames.body_frame(frame_id, name))))
    return out


FAST = "_fast"  # the suffix of the bodies' topics at wrench_rate (runner.Run.fast_messages)


def body_messages(t: float, sample: dict, dim: int, namespace: str = "/sim_node", frame_id: str = "world",
                  suffix: str = "") -> list:
    """(topic, message) pairs of each body's wrench (``bodies/<name>/wrench<suffix>``, in its frame)
    and a moving body's pose and odometry (``pose<suffix>``, ``odom<suffix>``: body_motion) from a
    sample's "wrenches" and "poses" (``measure.suite.Measurements``)."""
    out = []
    for name, (force, torque) in sample["wrenches"].items():
        out.append((f"{namespace}/bodies/{name}/wrench{suffix}",
                    wrench(t, frames.published(dim, force), frames.published(dim, torque),
                           frames.body_frame(frame_id, name))))
    for name, pose in sample.get("poses", {}).items():
        stamped, odometry = body_motion(t, pose, dim, frame_id, frames.body_frame(frame_id, name))
        out.append((f"{namespace}/bodies/{name}/pose{suffix}", stamped))
        out.append((f"{namespace}/bodies/{name}/odom{suffix}", odometry))
    return out
