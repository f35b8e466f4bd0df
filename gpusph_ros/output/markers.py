"""What a viewer draws beside the cloud: the scene's geometry (``visualization_msgs/MarkerArray``,
latched), each body's force as an arrow at the body, and the body frames for tf2.

All in the published axes (z up, ``frames``). An arrow is as long as the body's largest side for
a force equal to the weight of the water the body would displace (rho0 |g| times its volume, its
area in 2D): the scale of a body's loads, the same in 2D (N/m) and 3D (N).
"""
import numpy as np
from geometry_msgs.msg import Point
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from . import frames
from .messages import stamp

TANK, OBSTACLE, PROBE, LABEL, ARROW = ((0.6, 0.6, 0.6, 1.0), (0.55, 0.35, 0.2, 0.6), (1.0, 0.85, 0.0, 1.0),
                                       (1.0, 1.0, 1.0, 1.0), (1.0, 0.1, 0.1, 1.0))
THIN = 0.005  # [m] the thickness a 2D scene's boxes and lines are drawn with


def _marker(t, frame_id, ns, ident, kind, colour) -> Marker:
    m = Marker(ns=ns, id=ident, type=kind, action=Marker.ADD, frame_locked=False)
    m.header.stamp, m.header.frame_id = stamp(t), frame_id
    m.pose.orientation.w = 1.0
    m.color = ColorRGBA(r=colour[0], g=colour[1], b=colour[2], a=colour[3])
    return m


def _point(dim, values) -> Point:
    x, y, z = frames.published(dim, values)
    return Point(x=x, y=y, z=z)


def _box_edges(dim, lo, hi) -> list:
    """The 12 edges of the box [lo, hi] (4 in 2D) as pairs of points, for a LINE_LIST."""
    corners = [(a, b, c) for a in (lo[0], hi[0]) for b in (lo[1], hi[1]) for c in (lo[2], hi[2])]
    edges = [(p, q) for i, p in enumerate(corners) for q in corners[i + 1:]
             if sum(u != v for u, v in zip(p, q)) == 1]
    return [_point(dim, c) for edge in edges for c in edge]


def _label(t, frame_id, ident, dim, where, text, size) -> Marker:
    m = _marker(t, frame_id, "labels", ident, Marker.TEXT_VIEW_FACING, LABEL)
    m.pose.position = _point(dim, where)
    m.scale.z, m.text = size, text
    return m


def _solid(t, frame_id, ident, obstacle, dim, where) -> Marker:
    """An obstacle as RViz draws it: a cube (a wedge too, as its box), a sphere, or a cylinder
    turned from the marker's z onto its axis (a 2D disc's is the scene's z, published as y)."""
    kind = {"sphere": Marker.SPHERE, "cylinder": Marker.CYLINDER}.get(obstacle.shape, Marker.CUBE)
    m = _marker(t, frame_id, "obstacles", ident, kind, OBSTACLE)
    m.pose.position = _point(dim, where)
    extent = [max(abs(v), THIN) for v in frames.published(dim, np.subtract(obstacle.hi, obstacle.lo))]
    if kind == Marker.CYLINDER:
        axis = np.asarray(frames.published(dim, np.eye(3)[obstacle.axis]))
        along = int(np.argmax(np.abs(axis)))
        across = [extent[a] for a in range(3) if a != along]
        extent = [across[0], across[1], extent[along] if dim == 3 else THIN]
        turn = np.cross([0.0, 0.0, 1.0], axis)  # about z x a by the angle between them
        if np.linalg.norm(turn) > 0.0:
            half = 0.5 * np.arccos(np.clip(axis[2], -1.0, 1.0))
            x, y, z = np.sin(half) * turn / np.linalg.norm(turn)
            m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z = float(x), float(y), float(z)
            m.pose.orientation.w = float(np.cos(half))
    m.scale.x, m.scale.y, m.scale.z = extent
    return m


def geometry(scene, dx: float, frame_id: str, t: float = 0.0) -> MarkerArray:
    """The tank's edges, the obstacles as solids (``_solid``), each probe as a marker where it measures (a point,
    a sensor's face, a column's cylinder, a profile's points, a gauge's vertical line), and their
    names, in ``frame_id`` (scene in world coordinates: a model's, whose origin is applied)."""
    dim, out = scene.dim, []
    lo = np.asarray(scene.origin, dtype=float)
    hi = lo + np.asarray(scene.tank, dtype=float)
    tank = _marker(t, frame_id, "tank", 0, Marker.LINE_LIST, TANK)
    tank.points, tank.scale.x = _box_edges(dim, lo, hi), THIN
    out.append(tank)
    size = max(scene.tank) / 40  # the height of the labels
    for k, o in enumerate(scene.obstacles):
        # a moving body is drawn in its own frame, which /tf moves and turns with it
        frame, where = frame_id, np.asarray(o.centre(dim))
        if o.motion is not None:
            frame, where = frames.body_frame(frame_id, o.name), where - np.asarray(o.motion.centre)
        out.append(_solid(t, frame, k, o, dim, where))
        above = np.eye(3)[dim - 1] * (o.hi[dim - 1] - o.lo[dim - 1])
        out.append(_label(t, frame, k, dim, where + above, o.name, size))
    up = dim - 1
    for k, p in enumerate(scene.probes):
        m = _marker(t, frame_id, "probes", k, Marker.SPHERE_LIST, PROBE)
        where = list(p.position)
        if p.type == "gauge":  # the vertical it finds the surface on
            m.type = Marker.LINE_LIST
            bottom, top = list(where), list(where)
            bottom[up], top[up] = lo[up], hi[up]
            m.points, m.scale.x = [_point(dim, bottom), _point(dim, top)], THIN
        elif p.type == "column":
            m.type = Marker.CYLINDER if dim == 3 else Marker.CUBE
            radius = p.radius_dx * dx
            centre = list(where)
            centre[up] = (lo[up] + hi[up]) / 2
            m.pose.position = _point(dim, centre)
            m.scale.x, m.scale.y, m.scale.z = 2 * radius, 2 * radius if dim == 3 else THIN, hi[up] - lo[up]
            m.color.a = 0.3
        elif p.type == "profile":
            heights = [list(where[:up]) + [lo[up] + h] + list(where[up + 1:]) for h in p.heights]
            m.points = [_point(dim, h) for h in heights]
            m.scale.x = m.scale.y = m.scale.z = 2 * dx
        else:  # a point probe, or a pressure sensor (its face's diameter)
            m.points = [_point(dim, where)]
            m.scale.x = m.scale.y = m.scale.z = p.diameter or 2 * dx
        out.append(m)
        out.append(_label(t, frame_id, len(scene.obstacles) + k, dim, np.add(where, np.eye(3)[up] * size), p.name,
                          size))
    return MarkerArray(markers=out)


def force_scale(obstacle, dim: int, rho0: float, gravity) -> float:
    """[m/N] (m per N/m in 2D) the arrow length of a unit force on ``obstacle``."""
    side = np.subtract(obstacle.hi, obstacle.lo)[:dim]
    return float(np.max(side) / (rho0 * np.linalg.norm(gravity) * np.prod(side)))


def force_arrows(t: float, wrenches: dict, scene, scales: dict, frame_id: str) -> MarkerArray:
    """One arrow per body from its centre along the net force on its particles (``wrenches``:
    name -> (force, torque), scene axes; ``scales``: name -> ``force_scale``)."""
    out = []
    for k, o in enumerate(scene.obstacles):
        if o.name not in wrenches:
            continue
        m = _marker(t, frame_id, "forces", k, Marker.ARROW, ARROW)
        start = np.asarray(o.centre(scene.dim))
        end = start + scales[o.name] * np.asarray(wrenches[o.name][0])
        m.points = [_point(scene.dim, start), _point(scene.dim, end)]
        shaft = 0.05 * float(np.max(np.subtract(o.hi, o.lo)[:scene.dim]))
        m.scale.x, m.scale.y, m.scale.z = shaft, 2 * shaft, 3 * shaft
        out.append(m)
    return MarkerArray(markers=out)


def body_transforms(scene, frame_id: str, t: float = 0.0, poses: "dict | None" = None):
    """The body frames (``frames.body_frame``) as a tf2_msgs/TFMessage, or None where tf2_msgs is
    not installed (PyPI has no wheel of it; every ROS 2 install has it) or no body is listed:
    without ``poses`` the fixed bodies' for /tf_static, each at its box's centre; with them ({name:
    a measurement sample's pose, with its rotation matrix}) the moving bodies' for /tf, each where
    it stands and turned as it is."""
    try:
        from geometry_msgs.msg import TransformStamped
        from tf2_msgs.msg import TFMessage
    except ImportError:
        return None
    out = []
    for o in scene.obstacles:
        if (poses is None) != (o.motion is None):
            continue
        tf = TransformStamped(child_frame_id=frames.body_frame(frame_id, o.name))
        tf.header.stamp, tf.header.frame_id = stamp(t), frame_id
        where, turned = o.centre(scene.dim), (0.0, 0.0, 0.0, 1.0)
        if poses is not None:
            where = poses[o.name]["position"]
            turned = frames.published_rotation(scene.dim, poses[o.name]["rotation"])
        x, y, z = frames.published(scene.dim, where)
        tf.transform.translation.x, tf.transform.translation.y, tf.transform.translation.z = x, y, z
        r = tf.transform.rotation
        r.x, r.y, r.z, r.w = turned
        out.append(tf)
    return TFMessage(transforms=out) if out else None
