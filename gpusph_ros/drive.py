"""Bodies driven by commands (issue 45, item 4): what a driven body (a scene's ``motion: {type:
driven}``) does with the poses and twists a client sends, held to the scene's limits, and the
segment the solver follows to the next output (sph/bodies.py: ``driven_pose``; Solver.drive).

A command is a pose (position, unit quaternion x, y, z, w: where the body's reference point is to
be and how it is to be turned from where the scene put it) or a twist (linear and angular
velocity), in the scene's axes, stamped with simulated time. One is refused, with the reason and
nothing changed, when a number is not finite, the quaternion's norm is not 1 within 1e-3, its stamp
is later than the simulated time now (a command from the future), older than the timeout (stale on
arrival) or older than the last command taken (out of order). A twist past the limits is clamped to
them, and the reply says so.

At each output the driver turns the last command into the segment to the next output: the velocity
it wants (a pose's: the gap to it over one output interval; a twist's: the twist), within
``max_speed`` and ``max_angular_speed``, reached with at most ``max_acceleration`` and
``max_angular_acceleration`` from the velocity the body has, so that the body's velocity is
continuous, and no faster than it can stop within the gap to a pose (a trapezoid of speed). A pose
jump becomes a path at those limits, never a teleport into the fluid; a body follows a smooth
stream of poses about one output behind. A command older than the timeout is held
no longer: the body is brought to rest within the limits. Where the body is to go is kept where its
box stays in the tank (its translation: a rotation's sweep is not checked); a 2D body turns about z
only.

A floating body may also be pushed: ``WrenchHold`` keeps the external force and torque a client
sets (world axes, about its centre of mass), under the same refusals, for a timeout, clamped to
the body's ``max_force`` and ``max_torque`` (its weight by default), and the reply says so.
"""
import math
import threading

import numpy as np

QUATERNION_TOLERANCE = 1.0e-3


def _limit(v: np.ndarray, largest: float) -> np.ndarray:
    """v, shortened to at most ``largest`` long. Its length is taken over its largest component: a
    twist of 1e154 m/s on each axis overflowed the plain norm to inf, and became no velocity."""
    top = float(np.max(np.abs(v), initial=0.0))
    norm = top * float(np.linalg.norm(v / top)) if top > 0.0 else 0.0
    return v * (largest / norm) if norm > largest else v


def refusal(kind: str, stamp: float, now: float, timeout: float, last: float, *values) -> str:
    """Why a command of ``kind`` stamped ``stamp`` at simulated time ``now`` is refused, or "": a
    number not finite, a stamp later than now, older than the timeout, or older than ``last``, the
    stamp of the last command taken (the module's docstring)."""
    if not (all(np.all(np.isfinite(v)) for v in values) and math.isfinite(stamp)):
        return f"{kind}: a number is not finite"
    if stamp > now + 1.0e-9:
        return f"{kind}: stamped {stamp:.4f} s, later than the simulated time {now:.4f} s"
    if stamp < now - timeout:
        return f"{kind}: stamped {stamp:.4f} s, older than the timeout {timeout:g} s at {now:.4f} s"
    if stamp < last:
        return f"{kind}: stamped {stamp:.4f} s, before the last command taken ({last:.4f} s)"
    return ""


def _stopping_speed(gap: np.ndarray, velocity: np.ndarray, acceleration: float, interval: float) -> float:
    """The largest speed towards ``gap`` at the end of an interval over which the velocity changes
    at a constant rate from ``velocity``, from which the body still stops within what is left of the
    gap at ``acceleration``: v_end^2 <= 2 a (g - (v + v_end) dt / 2), solved for v_end (0 when even
    that is too late)."""
    g = float(np.linalg.norm(gap))
    if g == 0.0:
        return 0.0
    v = float(np.dot(velocity, gap)) / g
    half = acceleration * interval / 2.0
    room = half * half + 2.0 * acceleration * g - acceleration * v * interval
    return max(0.0, math.sqrt(room) - half) if room > 0.0 else 0.0


def _quat_mul(a, b) -> np.ndarray:
    """The Hamilton product a b of quaternions (x, y, z, w)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz])


def rotation_vector(target, now) -> np.ndarray:
    """The rotation (axis times angle, world frame, the shorter way) that turns ``now`` into
    ``target`` (quaternions x, y, z, w)."""
    q = _quat_mul(target, np.array([-now[0], -now[1], -now[2], now[3]]))
    if q[3] < 0.0:
        q = -q
    s = float(np.linalg.norm(q[:3]))
    return np.zeros(3) if s < 1.0e-15 else q[:3] / s * 2.0 * math.atan2(s, q[3])


class BodyDriver:
    """The commands of one driven body and the segments they give (the module's docstring)."""

    def __init__(self, motion, dim: int, lo, hi, tank):
        self.motion, self.dim = motion, dim
        centre = np.asarray(motion.centre, dtype=float)
        # where the reference point may go: the box inside the tank (the vertical axis: above the floor)
        self._low = centre - np.asarray(lo, dtype=float)
        self._high = np.asarray(tank, dtype=float)[:3] - (np.asarray(hi, dtype=float) - centre)
        self._high[dim - 1:] = np.inf
        if dim == 2:
            self._low[2], self._high[2] = 0.0, 0.0
        self._lock = threading.Lock()
        self._command = None  # (kind, stamp, a, b)
        self._last_stamp = -math.inf

    def command(self, kind: str, stamp: float, now: float, a, b) -> tuple:
        """Take a ``pose`` (a = position, b = quaternion) or a ``twist`` (a = linear, b = angular)
        stamped ``stamp`` at simulated time ``now``: (taken, what was done or why not)."""
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        m = self.motion
        if kind not in ("pose", "twist"):
            return False, f"command: {kind!r} is not one of pose, twist"
        why = refusal(kind, stamp, now, m.timeout, self._last_stamp, a, b)
        if why:
            return False, why
        note = "taken"
        if kind == "pose":
            if abs(float(np.linalg.norm(b)) - 1.0) > QUATERNION_TOLERANCE:
                return False, f"pose: the quaternion's norm is {np.linalg.norm(b):.6g}, not 1"
            b = b / np.linalg.norm(b)
        else:
            linear, angular = _limit(a, m.max_speed), _limit(self._planar(b), m.max_angular_speed)
            if not (np.allclose(linear, a) and np.allclose(angular, b)):
                note = (f"taken, clamped to max_speed {m.max_speed:g} m/s and max_angular_speed "
                        f"{m.max_angular_speed:g} rad/s")
            a, b = linear, angular
        with self._lock:
            self._command = (kind, stamp, a, b)
            self._last_stamp = stamp
        return True, note

    def _planar(self, w: np.ndarray) -> np.ndarray:
        """An angular vector the body may turn by: about z only in 2D."""
        return np.array([0.0, 0.0, w[2]]) if self.dim == 2 else w

    def segment(self, now: float, interval: float, pose: dict) -> dict:
        """The segment from ``now`` to the next output, ``interval`` later, from the body's
        ``pose`` (Solver.body_poses): Solver.drive's keyword arguments."""
        m = self.motion
        with self._lock:
            command = self._command
        x, v, w = (np.asarray(pose[k], dtype=float) for k in ("position", "velocity", "omega"))
        want_v, want_w = np.zeros(3), np.zeros(3)
        if command is not None and now - command[1] <= m.timeout:
            kind, _, a, b = command
            goal = a if kind == "pose" else x + a * interval
            gap = np.clip(goal, self._low, self._high) - x
            want_v = gap / interval
            if kind == "pose":
                turn = self._planar(rotation_vector(b, pose["quaternion"]))
                # no faster than it can stop within the gap: a step is a trapezoid of speed, not an overshoot
                want_v = _limit(want_v, _stopping_speed(gap, v, m.max_acceleration, interval))
                want_w = _limit(turn / interval, _stopping_speed(turn, w, m.max_angular_acceleration, interval))
            else:
                want_w = b
        want_v, want_w = _limit(want_v, m.max_speed), _limit(want_w, m.max_angular_speed)
        acceleration = _limit((want_v - v) / interval, m.max_acceleration)
        angular_acceleration = _limit((want_w - w) / interval, m.max_angular_acceleration)
        return {"t0": now, "position": x, "quaternion": np.asarray(pose["quaternion"], dtype=float), "velocity": v,
                "omega": w, "acceleration": acceleration, "angular_acceleration": angular_acceleration}


class WrenchHold:
    """The external force and torque on one floating body (a tether, a thruster), world axes about its
    centre of mass, as its last ``cmd_wrench`` set them: refused as a command is (not finite, from
    the future, older than the timeout or than the last taken), clamped to ``max_force`` and
    ``max_torque``, held for ``timeout`` seconds of simulated time after its stamp, then none."""

    def __init__(self, timeout: float, max_force: float, max_torque: float):
        self.timeout, self.max_force, self.max_torque = timeout, max_force, max_torque
        self._lock = threading.Lock()
        self._wrench = None  # (stamp, force, torque)

    def command(self, stamp: float, now: float, force, torque) -> tuple:
        """(taken, what was done or why not)."""
        force, torque = np.asarray(force, dtype=float), np.asarray(torque, dtype=float)
        with self._lock:
            last = self._wrench[0] if self._wrench is not None else -math.inf
            why = refusal("wrench", stamp, now, self.timeout, last, force, torque)
            if why:
                return False, why
            held = (_limit(force, self.max_force), _limit(torque, self.max_torque))
            self._wrench = (stamp, *held)
        clamped = [f"{name} clamped to {largest:g} {unit} (the body's max_{name})"
                   for name, unit, given, kept, largest in (("force", "N", force, held[0], self.max_force),
                                                             ("torque", "N m", torque, held[1], self.max_torque))
                   if not np.array_equal(given, kept)]
        return True, "; ".join(["taken", *clamped])

    def wrench(self, now: float) -> tuple:
        """(force, torque) to apply from ``now``: the last one taken while it is fresh, else none."""
        with self._lock:
            held = self._wrench
        if held is None or now - held[0] > self.timeout:
            return np.zeros(3), np.zeros(3)
        return held[1], held[2]
