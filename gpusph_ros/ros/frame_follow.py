"""Driven bodies that follow a TF frame (a scene's ``motion: {type: driven, frame: <frame>}``): the
frame's pose in the node's world frame, from what ``/tf`` and ``/tf_static`` carry, is the body's
pose command, as a ``cmd_pose`` would be (drive.py holds it to the scene's limits).

tf2's buffer has no wheel on PyPI, so this keeps the newest transform of each child frame and walks
a frame's parents up to the world frame, composing them (a robot's world -> base -> arm -> paddle).
What it gives up against tf2: no interpolation in time; the pose is the newest of each link, stamped
with the oldest stamp of the chain's moving links (tf2's "latest common time"), or with none (now)
where every link is static.

What /tf carries is bounded: a frame id empty or longer than a scene's may name is not kept, at
most MAX_LINKS links are (the least recently updated off every followed chain go first: 200,000
frames held 92 MiB), and a chain is walked MAX_CHAIN links at most (one of 10,000 cost 110 ms a
message).
"""
import numpy as np

from ..output import frames
from ..scenes.schema import MAX_FRAME_ID
from ..sph.bodies import quaternion_matrix

MAX_LINKS = 4096  # a robot's tree has tens to hundreds of frames
MAX_CHAIN = 64  # links from a followed frame up to the world


def frame_in(links: dict, frame: str, world: str):
    """(position, rotation matrix, stamp or None) of ``frame`` in ``world``, composing ``links``
    ({child: (parent, translation, quaternion x y z w, stamp, static)}), or the reason it cannot."""
    position, rotation, stamps, seen, at = np.zeros(3), np.eye(3), [], set(), frame
    while at != world:
        if at in seen:
            return f"the transforms from {frame!r} loop at {at!r}"
        if len(seen) >= MAX_CHAIN:
            return f"the transforms from {frame!r} to {world!r} are more than {MAX_CHAIN} links deep"
        seen.add(at)
        if at not in links:
            return f"no transform yet connects {frame!r} to {world!r} ({at!r} has no parent)"
        parent, translation, quaternion, stamp, static = links[at]
        turn = quaternion_matrix(quaternion)
        position = turn @ position + translation
        rotation = turn @ rotation
        if not static:
            stamps.append(stamp)
        at = parent
    return position, rotation, min(stamps) if stamps else None


class FrameFollower:
    """The pose commands of the driven bodies that follow frames (``bodies``: {body: frame}) in the
    world frame ``world``, from TF messages' transforms; the node's own body frames
    (``<world>/<body>``, which it publishes on /tf) are never taken as links."""

    def __init__(self, bodies: dict, world: str):
        self.bodies = dict(bodies)
        self.world = world
        self.links = {}

    def take(self, transforms, static: bool = False) -> list:
        """The transforms of one TF message (geometry_msgs/TransformStamped each) kept; for each body
        whose frame's chain they touch, (body, (position, rotation, stamp)) or (body, reason), the
        position and rotation in the published axes, the stamp in seconds of the message clock. A
        transform with a non-finite or non-unit rotation is not kept (a reason for each body it
        would move)."""
        touched, bad = set(), {}
        for tf in transforms:
            child, parent = tf.child_frame_id.lstrip("/"), tf.header.frame_id.lstrip("/")
            if child.startswith(self.world + "/") or not (0 < len(child) <= MAX_FRAME_ID and
                                                          0 < len(parent) <= MAX_FRAME_ID):
                continue
            t, r = tf.transform.translation, tf.transform.rotation
            translation, quaternion = np.array([t.x, t.y, t.z], dtype=float), np.array([r.x, r.y, r.z, r.w], float)
            if not (np.all(np.isfinite(translation)) and np.all(np.isfinite(quaternion))
                    and abs(np.linalg.norm(quaternion) - 1.0) <= 1.0e-3):
                bad[child] = f"the transform of {child!r} is not finite with a unit rotation"
                continue
            stamp = tf.header.stamp.sec + tf.header.stamp.nanosec * 1.0e-9
            self.links.pop(child, None)  # to the end: the links stand in the order they were last set
            self.links[child] = (parent, translation, quaternion / np.linalg.norm(quaternion), stamp, static)
            touched.add(child)
        if len(self.links) > MAX_LINKS:
            self._prune()
        out = []
        for body, frame in self.bodies.items():
            chain = self._chain(frame)
            if bad.keys() & chain:
                out.append((body, next(bad[c] for c in chain if c in bad)))
            elif touched & chain:
                out.append((body, frame_in(self.links, frame, self.world)))
        return out

    def _prune(self):
        """Down to MAX_LINKS links: the least recently set that no followed frame's chain holds go."""
        kept = set().union(*(self._chain(frame) for frame in self.bodies.values()))
        for child in [c for c in self.links if c not in kept][:len(self.links) - MAX_LINKS]:
            del self.links[child]

    def _chain(self, frame: str) -> set:
        """The frames from ``frame`` up its known parents (the links a change of which moves it), at
        most MAX_CHAIN."""
        chain, at = set(), frame
        while at not in chain and at != self.world and len(chain) <= MAX_CHAIN:
            chain.add(at)
            if at not in self.links:
                break
            at = self.links[at][0]
        return chain


def command(run, body: str, result) -> tuple:
    """Body ``body``'s pose command to ``run`` (runner.Run) from a ``FrameFollower.take`` result:
    (taken, what was done or why not), stamped as a cmd_pose is (Run.stamp_time)."""
    if isinstance(result, str):
        return False, result
    position, rotation, stamp = result
    dim = run.model.config.dim
    return run.command(body, "pose", run.stamp_time(stamp), frames.scene_vector(dim, position),
                       frames.scene_rotation(dim, rotation))
