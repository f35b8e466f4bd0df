"""The frames of what the node publishes, after REP 103 (x forward, y left, z up) and REP 105 (one
world-fixed frame, ``frame_id``, ``world`` by default).

A 3D scene computes with z up and is published as it is. A 2D scene computes in x (along) and y
(up); it is published in the world's x-z plane through the fixed rotation (x, y, z) -> (x, -z, y)
about x, so that z is up in every message, cloud and marker, and a torque about the 2D scene's z
axis reads about -y. Each body has its own frame, ``<frame_id>/<body>``: the world's axes moved to
the body's reference point (the centre of its box), which its wrench is given about.
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
