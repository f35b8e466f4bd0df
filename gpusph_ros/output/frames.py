"""The frames of what the node publishes, after REP 103 (x forward, y left, z up) and REP 105 (one
world-fixed frame, ``frame_id``, ``world`` by default).

A 3D scene computes with z up and is published as it is. A 2D scene computes in x (along) and y
(up); it is published in the world's x-z plane through the fixed rotation (x, y, z) -> (x, -z, y)
about x, so that z is up in every message, cloud and marker, and a torque about the 2D scene's z
axis reads about -y. Each body has its own frame, ``<frame_id>/<body>``: the world's axes moved to
the body's reference point (the centre of its box), which its wrench is given about; a moving
body's frame moves and turns with it (its pose and odometry are published), and its wrench is in
those axes about its reference point (a floating body's centre of mass).
"""
import numpy as np

AXES = "z up (REP 103); a 2D scene in the x-z plane"  # a recording's metadata says so
TURN_2D = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def turn(dim: int) -> np.ndarray:
    """The rotation from a ``dim``-dimensional scene's axes to the published ones."""
    return TURN_2D if dim == 2 else np.eye(3)


def published(dim: int, values) -> tuple:
    """A point or vector of the scene, in the published axes (0.0, never -0.0, for what is zero)."""
    return tuple(float(v) + 0.0 for v in turn(dim) @ np.asarray(values, dtype=float))


def body_frame(frame_id: str, body: str) -> str:
    """The frame of ``body``'s wrench: a child of the world frame ``frame_id``."""
    return f"{frame_id}/{body}"


def published_rotation(dim: int, rotation: np.ndarray) -> tuple:
    """A rotation of the scene (3 x 3) as the published axes see it, as a unit quaternion (x, y, z,
    w): T R T^T, T the turn of the axes (a 2D body's turn about z reads about -y)."""
    return quaternion_of(turn(dim) @ rotation @ turn(dim).T)


def scene_vector(dim: int, values, axial: bool = False) -> np.ndarray:
    """A point or vector given in the published axes, in the scene's: a 2D scene keeps its plane,
    x and y, or for an ``axial`` vector (an angular velocity) its z."""
    v = turn(dim).T @ np.asarray(values, dtype=float)
    if dim == 2:
        v = np.array([0.0, 0.0, v[2]]) if axial else np.array([v[0], v[1], 0.0])
    return v


def scene_rotation(dim: int, rotation: np.ndarray) -> np.ndarray:
    """A rotation given in the published axes (3 x 3), in the scene's, as a unit quaternion (x, y,
    z, w): T^T R T; a 2D scene keeps its turn about its z (the published -y)."""
    m = turn(dim).T @ rotation @ turn(dim)
    if dim == 2:
        angle = np.arctan2(m[1, 0], m[0, 0])
        return np.array([0.0, 0.0, np.sin(angle / 2), np.cos(angle / 2)])
    return np.asarray(quaternion_of(m))


def quaternion_of(m: np.ndarray) -> tuple:
    """The unit quaternion (x, y, z, w) of the rotation matrix m."""
    w = np.sqrt(max(0.0, 1.0 + m[0, 0] + m[1, 1] + m[2, 2])) / 2.0
    x = np.copysign(np.sqrt(max(0.0, 1.0 + m[0, 0] - m[1, 1] - m[2, 2])) / 2.0, m[2, 1] - m[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1.0 - m[0, 0] + m[1, 1] - m[2, 2])) / 2.0, m[0, 2] - m[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1.0 - m[0, 0] - m[1, 1] + m[2, 2])) / 2.0, m[1, 0] - m[0, 1])
    return tuple(float(c) + 0.0 for c in (x, y, z, w))
