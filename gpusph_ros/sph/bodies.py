"""Bodies that move (issue 45): a body's boundary particles on a prescribed path, or a floating body
moved by the fluid, gravity and its own inertia.

Each moving body has a reference point c0 where the scene puts it at t = 0 (a prescribed body's
centre of rotation, a floating body's centre of mass) and a pose at time t: the point's position X
and the body's rotation q (a unit quaternion, the identity at t = 0). A particle of the body that
stood at r0 stands at, and moves with (rho = x - X, its arm):

    x = X + R(q) (r0 - c0)
    v = V + omega x rho
    a = A + alpha x rho + omega x (omega x rho)

Prescribed motion (DualSPHysics' ``MotionSinusoidal`` / ``MotionRectSinusoidal``): a translation d(t)
and a rotation by theta(t) about a fixed unit axis n through c0, X = c0 + d, each starting where the
scene put the body:

- ``sinusoid``: d = A [sin(omega t + phi) - sin(phi)] and theta = Theta [sin(omega t + phi) -
  sin(phi)], omega = 2 pi / period: a piston (A along the flume) or a flap (Theta about its hinge);
  phi = -90 degrees starts it at rest; with a ``ramp``, both times (1 - cos(pi t / ramp)) / 2 until
  then (a wavemaker's start: the scene's ``piston`` and ``flap`` are such sinusoids, their stroke
  from linear wavemaker theory, theory/wavemaker.py);
- ``translate``: d = A (t - start) from ``start`` on: a constant velocity A (a wedge's entry into
  still water at constant speed);
- ``move``: d = D [s - sin(2 pi s) / (2 pi)], s = (t - start) / duration clamped to [0, 1]: the
  displacement D over the duration, starting and ending at rest with a continuous acceleration
  (the velocity 1 - cos(2 pi s) times D / duration), no rotation;
- ``series`` (DualSPHysics' ``mvfile`` and ``mvrotfile``): d and theta given at times t_0 < t_1 <
  ..., both 0 at t_0, between them a clamped cubic spline of each (``series_table``: its velocity 0
  at t_0 and at the last time, its acceleration continuous between), which the wall's (g - a_w)
  term needs and straight lines between the samples would make a train of impulses; before t_0 the
  body stands where the scene put it, after the last time at the last sample, at rest.

A driven body follows segments its driver sets at each output (drive.py: commands from ROS, held
to the scene's limits): from its pose and velocities at the segment's start t0, constant linear and
angular accelerations, so that its velocity is continuous across outputs; until first driven it
stands where the scene put it.

A floating body (DualSPHysics' floatings, GPUSPH's floating bodies) integrates Newton's and Euler's
laws for a rigid body in the solver's own predictor-corrector, from the force and torque the fluid
exerts on its particles (the reaction the force pass leaves on each, F = sum m_i acc_i, T = sum
rho_i x m_i acc_i about X), gravity, and an external force and torque its driver may set (a tether,
a thruster: drive.py):

    V' = F / M + g,  X' = V,  L' = T,  omega = I_w^-1 L,  I_w = R I_body R^T,  q' = (omega / 2) q

with the angular momentum L in the world frame as the state: the gyroscopic term omega x I omega of
Euler's equations in the body frame (which DualSPHysics drops) is then exact, and a free body keeps
L to round-off. Each stage is the fluid's: the predictor advances by dt / 2 with the rates and
velocities at t, the corrector by dt from t with those at t + dt / 2 (the rotation by the angle
omega dt about omega, as a quaternion). Constrained degrees of freedom have their force and torque
zeroed (and their angular velocity: a 2D body turns about z only). Until its ``release`` time a
floating body is held where it stands. It meets the tank's walls (``wall_contact``): a corner of its
box past a wall's face moves it back and takes its velocity into the wall away, a plastic contact
without friction (DualSPHysics hands contacts to Project Chrono; this is the least that keeps a body
that sinks or drifts inside the tank). It meets a fixed obstacle's box the same way
(``solid_contact``: its corner deepest in pushed out through the nearest face), and another floating
body (``body_contacts``): the two pushed apart in inverse proportion to their masses and their
velocities along the push made one, which keeps their momentum. A round body (a sphere, a 2D disc)
meets others as its ball, a 3D cylinder as its box's corners. The pushes act at the centres: the
contact turns nothing, and an edge meeting an edge (no corner inside) is not seen.

The solver sets the bodies' poses at each stage of a step (the step's start, the half step, the
candidate: ``body_poses``) and each body's particles on them (``move_walls``), with their velocity
and acceleration, which the extrapolated-pressure wall's (g - a_w) term reads (boundaries/adami.py);
the fluid sees the wall's velocity through the pair terms as it sees a fixed wall's zero. What the
bodies' particles add up to (a floating body's force and torque, the moving bodies' work on the
fluid) is body_sums.py's. A scene without a moving body launches none of this and steps bit for
bit as before.
"""
import functools
import math
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import warp as wp

from . import health
from .state import BOUNDARY, DT, T

FIXED, SINUSOID, MOVE, FLOATING, DRIVEN, TRANSLATE, SERIES = 0, 1, 2, 3, 4, 5, 6
# the scene's ``motion.type`` (piston, flap: a sinusoid)
LAWS = ("translate", "sinusoid", "move", "series", "driven", "piston", "flap")
LAW_ID = {"translate": TRANSLATE, "sinusoid": SINUSOID, "move": MOVE, "driven": DRIVEN, "series": SERIES}
CHANNELS = 4  # a series' d_x, d_y, d_z and theta
SERIES_COLUMNS = 1 + 4 * CHANNELS  # a row of series_table: t_k, then each channel's cubic on [t_k, t_k+1]


@dataclass(frozen=True)
class Motion:
    """One body's prescribed motion (the module's docstring): SI units, angles in radians."""

    law: str = "sinusoid"
    centre: tuple = (0.0, 0.0, 0.0)  # [m] c0, the rotation's centre at t = 0
    amplitude: tuple = (0.0, 0.0, 0.0)  # [m] sinusoid: A; move: the displacement D
    period: float = 0.0  # [s] sinusoid
    phase: float = 0.0  # [rad] sinusoid's phi
    angle: float = 0.0  # [rad] sinusoid's Theta
    axis: tuple = (0.0, 0.0, 1.0)  # the rotation's axis (normalised here)
    start: float = 0.0  # [s] move
    duration: float = 0.0  # [s] move
    ramp: float = 0.0  # [s] sinusoid: its amplitude grows from 0 over this time (1 - cos); 0: none
    # driven: the limits its commands are held to (drive.py), [m/s], [m/s^2], [rad/s], [rad/s^2], and
    # the time [s] a command is held before the body is brought to rest
    max_speed: float = 0.0
    max_acceleration: float = 0.0
    max_angular_speed: float = 0.0
    max_angular_acceleration: float = 0.0
    timeout: float = 0.0
    frame: str = ""  # driven: a TF frame whose pose in the world frame commands it (the node's), or none
    # series: rows (t, d_x, d_y, d_z, theta) [s, m, rad], d and theta 0 in the first
    series: tuple = ()

    def peak_speed(self, reach: float) -> float:
        """The largest speed [m/s] of a particle at most ``reach`` [m] from the centre: what the
        scene's check holds under c0 / 10."""
        if self.law == "translate":
            return float(np.linalg.norm(self.amplitude))
        if self.law == "driven":
            return self.max_speed + self.max_angular_speed * reach
        if self.law == "move":
            return 2.0 * float(np.linalg.norm(self.amplitude)) / self.duration
        if self.law == "series":
            _, rate = series_samples(self.series)
            return float((np.linalg.norm(rate[:, :3], axis=1) + np.abs(rate[:, 3]) * reach).max())
        omega = 2.0 * math.pi / self.period
        return omega * (float(np.linalg.norm(self.amplitude)) + abs(self.angle) * reach)

    def reach(self):
        """((lo, hi) of the displacement d along each axis over all time, the largest |theta|
        [rad]), or None where the law sets no bound (translate, driven)."""
        if self.law == "series":
            value_at, _ = series_samples(self.series)
            return (list(zip(value_at[:, :3].min(axis=0), value_at[:, :3].max(axis=0))),
                    float(np.abs(value_at[:, 3]).max()))
        if self.law == "move":
            return [(min(0.0, c), max(0.0, c)) for c in self.amplitude], 0.0
        if self.law == "sinusoid":  # sin(omega t + phi) - sin(phi) spans [-1 - sin(phi), 1 - sin(phi)]
            span = (-1.0 - math.sin(self.phase), 1.0 - math.sin(self.phase))
            return ([(min(a * s for s in span), max(a * s for s in span)) for a in self.amplitude],
                    abs(self.angle) * (1.0 + abs(math.sin(self.phase))))
        return None

    def sweep(self, lo, hi):
        """(lo, hi) 3-vectors of a box that holds the box [lo, hi] wherever the law takes it (a
        rotation by theta moves a point r from the centre by at most r |theta|), or None (reach)."""
        reach = self.reach()
        if reach is None:
            return None
        shift, angle = reach
        lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
        turn = min(angle, 2.0) * farthest_corner(lo, hi, self.centre)
        return lo + np.array([s[0] for s in shift]) - turn, hi + np.array([s[1] for s in shift]) + turn


def farthest_corner(lo, hi, centre) -> float:
    """How far the farthest corner of the box [lo, hi] (3-vectors) stands from ``centre`` [m]: the
    arm of a body's particle farthest from its centre of rotation."""
    corners = np.array(np.meshgrid(*zip(lo, hi))).reshape(3, -1).T
    return float(np.linalg.norm(corners - np.asarray(centre), axis=1).max())


@dataclass(frozen=True)
class Floating:
    """A floating rigid body (the module's docstring): its mass [kg, kg/m in 2D], centre of mass at
    t = 0 [m], inertia about it in the body's frame (3 x 3, [kg m^2]), which translations and
    rotations are free (per world axis), and when it is let go [s]."""

    mass: float
    centre: tuple
    inertia: tuple
    translate: tuple = (True, True, True)
    rotate: tuple = (True, True, True)
    release: float = 0.0
    velocity: tuple = (0.0, 0.0, 0.0)  # [m/s] at t = 0 (once released)
    omega: tuple = (0.0, 0.0, 0.0)  # [rad/s] at t = 0
    # its box's corners less the centre of mass at t = 0 [m]: what meets the tank's walls, or for a
    # round body (radius > 0) the box's centre: a sphere, or a cylinder of that radius about the unit
    # ``round_axis`` (body frame) ``half_length`` either side of it
    corner_lo: tuple = (0.0, 0.0, 0.0)
    corner_hi: tuple = (0.0, 0.0, 0.0)
    radius: float = 0.0
    round_axis: tuple = (0.0, 0.0, 0.0)
    half_length: float = 0.0
    # the largest external force [N; N/m in 2D] and torque [N m] a client may put on it (cmd_wrench):
    # by default its weight, and its weight at its farthest corner (schema._floating)
    max_force: float = 0.0
    max_torque: float = 0.0


def clamped_spline(t, y) -> np.ndarray:
    """The cubic spline through (t_k, y_k) with y' = 0 at both ends, C2 between (de Boor, A
    Practical Guide to Splines, ch. 4): (k - 1, 4) coefficients (a, b, c, d) of a + b s + c s^2 + d
    s^3, s = t - t_k, on each interval."""
    t, y = np.asarray(t, dtype=np.float64), np.asarray(y, dtype=np.float64)
    h = np.diff(t)
    n = len(t)
    # the second derivatives' system: h_(k-1) m_(k-1) + 2 (h_(k-1) + h_k) m_k + h_k m_(k+1) = 6 (slope_k - slope_(k-1)),
    # the clamped ends 2 h_0 m_0 + h_0 m_1 = 6 slope_0 and h m_(n-2) + 2 h m_(n-1) = -6 slope_(n-2)
    slope = np.diff(y) / h
    diag, upper, lower, rhs = np.zeros(n), np.zeros(n - 1), np.zeros(n - 1), np.zeros(n)
    diag[0], upper[0], rhs[0] = 2.0 * h[0], h[0], 6.0 * slope[0]
    diag[-1], lower[-1], rhs[-1] = 2.0 * h[-1], h[-1], -6.0 * slope[-1]
    diag[1:-1] = 2.0 * (h[:-1] + h[1:])
    upper[1:], lower[:-1] = h[1:], h[:-1]
    rhs[1:-1] = 6.0 * np.diff(slope)
    for k in range(1, n):  # Thomas' elimination: a tridiagonal, diagonally dominant system
        w = lower[k - 1] / diag[k - 1]
        diag[k] -= w * upper[k - 1]
        rhs[k] -= w * rhs[k - 1]
    m = np.zeros(n)
    m[-1] = rhs[-1] / diag[-1]
    for k in range(n - 2, -1, -1):
        m[k] = (rhs[k] - upper[k] * m[k + 1]) / diag[k]
    b = slope - h * (2.0 * m[:-1] + m[1:]) / 6.0
    b[0] = 0.0  # the clamped start, exactly: its round-off read -2.8e-17 m/s on one CPU, a body not at rest
    return np.column_stack([y[:-1], b, m[:-1] / 2.0, (m[1:] - m[:-1]) / (6.0 * h)])


def series_table(motions: list) -> np.ndarray:
    """The series laws' rows, body after body (Law.first, Law.count): t_k and each channel's
    clamped_spline coefficients on [t_k, t_k+1]; the last row of a body its last sample, held. At
    least one row."""
    rows = [np.zeros((1, SERIES_COLUMNS))]
    for m in motions:
        if isinstance(m, Motion) and m.law == "series":
            data = np.asarray(m.series, dtype=np.float64)
            block = np.zeros((len(data), SERIES_COLUMNS))
            block[:, 0] = data[:, 0]
            for c in range(CHANNELS):
                block[:-1, 1 + 4 * c:5 + 4 * c] = clamped_spline(data[:, 0], data[:, 1 + c])
                block[-1, 1 + 4 * c] = data[-1, 1 + c]
            rows.append(block)
    return np.concatenate(rows[1:] or rows)


@functools.lru_cache(maxsize=8)
def series_samples(series, per_interval: int = 8):
    """(d and theta, their rates) of a series' spline at ``per_interval`` points of each interval
    and its ends, (k, 4) each, read-only: where the spline reaches and how fast, which its samples
    alone do not say (a cubic overshoots them). Kept for the scene's reach and the build's speed
    check, which ask for the same series."""
    table = series_table([Motion(law="series", series=series)])
    tau = np.diff(table[:, 0])[:, None] * np.linspace(0.0, 1.0, per_interval, endpoint=False)[None, :]
    coef = table[:-1, 1:].reshape(-1, 1, CHANNELS, 4)  # interval, sample, channel, power
    tau = tau[:, :, None]
    value = coef[..., 0] + tau * (coef[..., 1] + tau * (coef[..., 2] + tau * coef[..., 3]))
    rate = coef[..., 1] + tau * (2.0 * coef[..., 2] + 3.0 * tau * coef[..., 3])
    out = (np.concatenate([value.reshape(-1, CHANNELS), table[-1:, 1::4]]),
           np.concatenate([rate.reshape(-1, CHANNELS), np.zeros((1, CHANNELS))]))
    for a in out:
        a.setflags(write=False)
    return out


def quaternion_matrix(q) -> np.ndarray:
    """The rotation matrix of the unit quaternion q = (x, y, z, w) (Warp's order)."""
    x, y, z, w = (float(c) for c in q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


# A body's law, a floating body's state and a body's pose, in float64 whatever the fluid's precision:
# one struct of each for every build, since Warp keys a kernel by its name and module, and a second
# build's struct (float64 after float32) was refused by the first build's kernels ("argument 'laws'
# expects an array with dtype=<Struct ...>"), so a reset could not change the precision of a scene
# with a body.
@wp.struct
class Law:
    kind: int  # FIXED, SINUSOID, MOVE or FLOATING
    centre: wp.vec3d  # c0
    amplitude: wp.vec3d
    omega: wp.float64
    phase: wp.float64
    angle: wp.float64
    axis: wp.vec3d
    start: wp.float64
    duration: wp.float64
    ramp: wp.float64
    mass: wp.float64  # floating: M, the body frame's inertia, the free axes, the release time
    inertia: wp.mat33d
    inv_inertia: wp.mat33d
    translate: wp.vec3d  # 1 where free, 0 where held
    rotate: wp.vec3d
    release: wp.float64
    corner_lo: wp.vec3d  # floating: its box's corners less c0
    corner_hi: wp.vec3d
    radius: wp.float64  # floating and round: its radius, axis (body frame) and half length
    round_axis: wp.vec3d
    half_length: wp.float64
    ext_force: wp.vec3d  # floating: an external force and torque about its centre of mass (world)
    ext_torque: wp.vec3d
    first: int  # series: its rows in the series table
    count: int
    t0: wp.float64  # driven: the segment's start, pose, velocities and constant accelerations
    x0: wp.vec3d
    q0: wp.quatd
    v0: wp.vec3d
    w0: wp.vec3d
    lin_acc: wp.vec3d
    ang_acc: wp.vec3d

@wp.struct
class Rigid:
    """A floating body's state: centre of mass, its velocity, rotation, angular momentum (world),
    and the sum of the contacts' pushes at its stage (zero when it touched nothing)."""

    x: wp.vec3d
    v: wp.vec3d
    q: wp.quatd
    ang: wp.vec3d
    touch: wp.vec3d

@wp.struct
class Pose:
    """Where a body stands at one stage and how it moves: X, q, V, omega, A, alpha."""

    x: wp.vec3d
    q: wp.quatd
    v: wp.vec3d
    w: wp.vec3d
    a: wp.vec3d
    alpha: wp.vec3d


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    healthy = health.build(scalar).healthy

    @wp.func
    def profile(law: Law, t: wp.float64) -> wp.vec3d:
        """(f, f', f'') of a prescribed law's time profile at t: d = f A and theta = f Theta."""
        if law.kind == SINUSOID:
            s = wp.sin(law.omega * t + law.phase)
            c = wp.cos(law.omega * t + law.phase)
            f = wp.vec3d(s - wp.sin(law.phase), law.omega * c, -law.omega * law.omega * s)
            if t >= law.ramp:
                return f
            # times the ramp r = (1 - cos(pi t / ramp)) / 2: (r f)' = r' f + r f', (r f)'' = r'' f + 2 r' f' + r f''
            a = wp.float64(math.pi) / law.ramp
            r = wp.float64(0.5) * (wp.float64(1.0) - wp.cos(a * t))
            dr = wp.float64(0.5) * a * wp.sin(a * t)
            ddr = wp.float64(0.5) * a * a * wp.cos(a * t)
            return wp.vec3d(r * f[0], dr * f[0] + r * f[1], ddr * f[0] + wp.float64(2.0) * dr * f[1] + r * f[2])
        if law.kind == TRANSLATE:  # at the velocity A from start on
            return wp.vec3d(wp.max(t - law.start, wp.float64(0.0)), wp.where(t > law.start, wp.float64(1.0),
                                                                               wp.float64(0.0)), wp.float64(0.0))
        if law.kind == MOVE:
            u = (t - law.start) / law.duration
            if u <= wp.float64(0.0):
                return wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
            if u >= wp.float64(1.0):
                return wp.vec3d(wp.float64(1.0), wp.float64(0.0), wp.float64(0.0))
            two_pi = wp.float64(2.0 * math.pi)
            return wp.vec3d(u - wp.sin(two_pi * u) / two_pi, (wp.float64(1.0) - wp.cos(two_pi * u)) / law.duration,
                            two_pi * wp.sin(two_pi * u) / (law.duration * law.duration))
        return wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))

    @wp.func
    def world_inertia_inv(law: Law, q: wp.quatd) -> wp.mat33d:
        """I_w^-1 = R I_body^-1 R^T."""
        r = wp.quat_to_matrix(q)
        return r * law.inv_inertia * wp.transpose(r)

    @wp.func
    def angular_velocity(law: Law, body: Rigid) -> wp.vec3d:
        """omega = I_w^-1 L, zero about the held axes."""
        return wp.cw_mul(world_inertia_inv(law, body.q) * body.ang, law.rotate)

    @wp.func
    def turned(q: wp.quatd, w: wp.vec3d, dt: wp.float64) -> wp.quatd:
        """q turned by the angle |w| dt about w (world frame), normalised."""
        angle = wp.length(w) * dt
        if angle <= wp.float64(0.0):
            return q
        return wp.normalize(wp.quat_from_axis_angle(wp.normalize(w), angle) * q)

    @wp.func
    def prescribed_pose(law: Law, t: wp.float64) -> Pose:
        f = profile(law, t)
        pose = Pose()
        pose.x = law.centre + law.amplitude * f[0]
        pose.q = wp.quat_from_axis_angle(law.axis, law.angle * f[0])
        pose.v = law.amplitude * f[1]
        pose.w = law.axis * (law.angle * f[1])
        pose.a = law.amplitude * f[2]
        pose.alpha = law.axis * (law.angle * f[2])
        return pose

    @wp.func
    def series_pose(law: Law, table: wp.array2d(dtype=wp.float64), t: wp.float64) -> Pose:
        """A series body on its splines (series_table): the interval holding t found by bisection;
        before the first time its first row, after the last its last, at rest."""
        lo = law.first
        hi = law.first + law.count - 1
        tau = wp.float64(0.0)
        moving = wp.float64(1.0)  # 0 before the first time: standing, its spline's start curvature unfelt
        if t <= table[lo, 0]:
            hi = lo
            if t < table[lo, 0]:
                moving = wp.float64(0.0)
        elif t >= table[hi, 0]:
            lo = hi
        else:
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if table[mid, 0] <= t:
                    lo = mid
                else:
                    hi = mid
            tau = t - table[lo, 0]
        value = wp.vec4d()
        rate = wp.vec4d()
        accel = wp.vec4d()
        for c in range(CHANNELS):
            a = table[lo, 1 + 4 * c]
            b = table[lo, 2 + 4 * c]
            cc = table[lo, 3 + 4 * c]
            d = table[lo, 4 + 4 * c]
            value[c] = a + tau * (b + tau * (cc + tau * d))
            rate[c] = b + tau * (wp.float64(2.0) * cc + wp.float64(3.0) * tau * d)
            accel[c] = moving * (wp.float64(2.0) * cc + wp.float64(6.0) * tau * d)
        pose = Pose()
        pose.x = law.centre + wp.vec3d(value[0], value[1], value[2])
        pose.q = wp.quat_from_axis_angle(law.axis, value[3])
        pose.v = wp.vec3d(rate[0], rate[1], rate[2])
        pose.w = law.axis * rate[3]
        pose.a = wp.vec3d(accel[0], accel[1], accel[2])
        pose.alpha = law.axis * accel[3]
        return pose

    @wp.func
    def driven_pose(law: Law, t: wp.float64) -> Pose:
        """A driven body on its segment (drive.py): constant accelerations from its pose and
        velocities at t0, the rotation by the integrated angular velocity's vector."""
        tau = wp.max(t - law.t0, wp.float64(0.0))
        pose = Pose()
        pose.x = law.x0 + law.v0 * tau + law.lin_acc * (wp.float64(0.5) * tau * tau)
        pose.v = law.v0 + law.lin_acc * tau
        pose.a = law.lin_acc
        pose.w = law.w0 + law.ang_acc * tau
        pose.alpha = law.ang_acc
        pose.q = turned(law.q0, law.w0 + law.ang_acc * (wp.float64(0.5) * tau), tau)
        return pose

    @wp.func
    def box_point(law: Law, body: Rigid, k: int) -> wp.vec3d:
        """Point k (0-26) of a body's box, in the world: its corners, the middles of its edges and
        faces, and its centre (each coordinate low, middle or high), so that two boxes meeting face
        to face, whose corners lie on each other's faces, still find a point inside."""
        mid = wp.float64(0.5) * (law.corner_lo + law.corner_hi)
        point = wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
        for ax in range(3):
            c = (k // wp.where(ax == 0, 1, wp.where(ax == 1, 3, 9))) % 3  # k's base-3 digit ax
            point[ax] = wp.where(c == 0, law.corner_lo[ax], wp.where(c == 1, mid[ax], law.corner_hi[ax]))
        return body.x + wp.quat_rotate(body.q, point)

    @wp.func
    def corner_of(law: Law, body: Rigid, k: int) -> wp.vec3d:
        """Corner k (0-7) of a body's box, in the world: the box point whose digits are all low or
        high."""
        return box_point(law, body, 2 * (k % 2) + 6 * ((k // 2) % 2) + 18 * (k // 4))

    @wp.func
    def box_centre(law: Law, body: Rigid) -> wp.vec3d:
        """The centre of a body's box, in the world (a round body's centre): its middle box point."""
        return box_point(law, body, 13)

    @wp.func
    def wall_contact(law: Law, body: Rigid, wall_lo: wp.vec3d, wall_hi: wp.vec3d) -> Rigid:
        """The body kept inside the tank's walls [wall_lo, wall_hi]: where a corner of its box (the
        surface of a round body) has passed a wall's face it is moved back along that axis and its
        velocity into the wall is taken away (a plastic contact without friction; its rotation is
        left as it is)."""
        low = wp.vec3d(wp.float64(1.0e300), wp.float64(1.0e300), wp.float64(1.0e300))
        high = -low
        if law.radius > wp.float64(0.0):
            # a cylinder's reach along a world axis e: |a.e| L/2 + R sqrt(1 - (a.e)^2) (a sphere: R)
            centre = box_centre(law, body)
            a = wp.quat_rotate(body.q, law.round_axis)
            for ax in range(3):
                reach = wp.abs(a[ax]) * law.half_length + law.radius * wp.sqrt(
                    wp.max(wp.float64(1.0) - a[ax] * a[ax], wp.float64(0.0)))
                low[ax] = centre[ax] - reach
                high[ax] = centre[ax] + reach
        else:
            for k in range(8):
                p = corner_of(law, body, k)
                low = wp.min(low, p)
                high = wp.max(high, p)
        shift = wp.max(wall_lo - low, wp.vec3d(wp.float64(0.0))) - wp.max(high - wall_hi, wp.vec3d(wp.float64(0.0)))
        v = body.v
        for ax in range(3):
            if (shift[ax] > wp.float64(0.0) and v[ax] < wp.float64(0.0)) or \
                    (shift[ax] < wp.float64(0.0) and v[ax] > wp.float64(0.0)):
                v[ax] = wp.float64(0.0)
        body.x = body.x + shift
        body.v = v
        body.touch = body.touch + shift
        return body

    @wp.func
    def ball(law: Law) -> bool:
        """Whether a body meets others as a ball: a sphere, or a disc in 2D (its radius about the
        centre of its box); a 3D cylinder meets them with its box's corners."""
        return law.radius > wp.float64(0.0) and law.half_length == wp.float64(0.0)

    @wp.func
    def box_push(p: wp.vec3d, radius: wp.float64, centre: wp.vec3d, q: wp.quatd, half: wp.vec3d) -> wp.vec3d:
        """How far a point (a ball of ``radius`` about it, 0 for a corner) must move to leave the box
        of ``half`` extents about ``centre`` turned by q (an axis with no extent, a 2D scene's z,
        bounds nothing): along the face nearest to it, or away from the box's nearest point."""
        local = wp.quat_rotate_inv(q, p - centre)
        near = local
        inside = True
        for ax in range(3):
            if half[ax] > wp.float64(0.0):
                near[ax] = wp.clamp(local[ax], -half[ax], half[ax])
                if wp.abs(local[ax]) >= half[ax]:
                    inside = False
        push = wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
        if inside:  # out through the nearest face, the ball's radius beyond it
            depth = wp.float64(1.0e300)
            for ax in range(3):
                if half[ax] > wp.float64(0.0) and half[ax] - wp.abs(local[ax]) < depth:
                    depth = half[ax] - wp.abs(local[ax])
                    push = wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
                    side = wp.where(local[ax] < wp.float64(0.0), -wp.float64(1.0), wp.float64(1.0))
                    push[ax] = side * (depth + radius)
        else:
            gap = local - near
            d = wp.length(gap)
            if d < radius and d > wp.float64(0.0):
                push = gap * ((radius - d) / d)
        return wp.quat_rotate(q, push)

    @wp.func
    def ball_push(p: wp.vec3d, radius: wp.float64, centre: wp.vec3d, other: wp.float64) -> wp.vec3d:
        """How far a point (a ball of ``radius``) must move to leave a ball of radius ``other`` about
        ``centre``."""
        gap = p - centre
        d = wp.length(gap)
        if d >= radius + other or d == wp.float64(0.0):
            return wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
        return gap * ((radius + other - d) / d)

    @wp.func
    def deepest(law: Law, body: Rigid, centre: wp.vec3d, q: wp.quatd, half: wp.vec3d,
                other: wp.float64) -> wp.vec3d:
        """The largest push that takes a body out of a box (``other`` 0) or a ball of radius
        ``other`` (about ``centre``): its ball's, or that of the point of its box (``box_point``)
        deepest in."""
        best = wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
        if ball(law):
            p = box_centre(law, body)
            if other > wp.float64(0.0):
                return ball_push(p, law.radius, centre, other)
            return box_push(p, law.radius, centre, q, half)
        for k in range(27):
            push = wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
            if other > wp.float64(0.0):
                push = ball_push(box_point(law, body, k), wp.float64(0.0), centre, other)
            else:
                push = box_push(box_point(law, body, k), wp.float64(0.0), centre, q, half)
            if wp.length(push) > wp.length(best):
                best = push
        return best

    @wp.func
    def stop_along(v: wp.vec3d, push: wp.vec3d) -> wp.vec3d:
        """v less its part against ``push`` (a plastic, frictionless contact); v when push is 0."""
        if wp.length(push) == wp.float64(0.0):
            return v
        n = wp.normalize(push)
        into = wp.dot(v, n)
        if into < wp.float64(0.0):
            return v - into * n
        return v

    @wp.func
    def solid_contact(law: Law, body: Rigid, lo: wp.vec3d, hi: wp.vec3d) -> Rigid:
        """The body kept out of a fixed obstacle's box [lo, hi]: moved out by its deepest corner's
        (its ball's) push, its velocity into the obstacle taken away."""
        half = wp.float64(0.5) * (hi - lo)
        push = deepest(law, body, wp.float64(0.5) * (lo + hi), wp.quatd(wp.float64(0.0), wp.float64(0.0),
                                                                        wp.float64(0.0), wp.float64(1.0)),
                       half, wp.float64(0.0))
        if wp.length(push) > wp.float64(0.0):
            body.x = body.x + push
            body.v = stop_along(body.v, push)
            body.touch = body.touch + push
        return body

    @wp.kernel(enable_backward=False, module="unique")
    def body_contacts(laws: wp.array(dtype=Law), factor: wp.float64, out: wp.array(dtype=Rigid),
                      poses: wp.array(dtype=Pose)):
        """Floating bodies kept out of each other (one thread, body pairs in turn): where a point of
        one's box (its ball) is inside the other's box (ball), the two are moved apart along the push
        in inverse proportion to their masses and their velocities along it made one, as a plastic,
        frictionless contact between their centres keeps their momentum; the poses follow. At the
        candidate only (factor 1): the corrector recomputes the velocities from the step's start, and
        would drop an exchange made at the half step."""
        if factor < wp.float64(1.0):
            return
        n = laws.shape[0]
        for a in range(n):
            for b in range(a + 1, n):
                la = laws[a]
                lb = laws[b]
                if la.kind != FLOATING or lb.kind != FLOATING:
                    continue
                ra = out[a]
                rb = out[b]
                # a's features in b's shape, and b's in a's (reversed)
                centre_b = box_centre(lb, rb)
                centre_a = box_centre(la, ra)
                push = deepest(la, ra, centre_b, rb.q, wp.float64(0.5) * (lb.corner_hi - lb.corner_lo),
                               wp.where(ball(lb), lb.radius, wp.float64(0.0)))
                back = deepest(lb, rb, centre_a, ra.q, wp.float64(0.5) * (la.corner_hi - la.corner_lo),
                               wp.where(ball(la), la.radius, wp.float64(0.0)))
                if wp.length(back) > wp.length(push):
                    push = -back
                if wp.length(push) == wp.float64(0.0):
                    continue
                total = la.mass + lb.mass
                ra.x = ra.x + push * (lb.mass / total)
                rb.x = rb.x - push * (la.mass / total)
                nrm = wp.normalize(push)
                closing = wp.dot(ra.v - rb.v, nrm)
                if closing < wp.float64(0.0):
                    ra.v = ra.v - nrm * (closing * lb.mass / total)
                    rb.v = rb.v + nrm * (closing * la.mass / total)
                out[a] = ra
                out[b] = rb
                pa = poses[a]
                pb = poses[b]
                pa.x = ra.x
                pa.v = ra.v
                pb.x = rb.x
                pb.v = rb.v
                poses[a] = pa
                poses[b] = pb

    @wp.kernel(enable_backward=False, module="unique")
    def body_poses(laws: wp.array(dtype=Law), series: wp.array2d(dtype=wp.float64),
                   clock: wp.array(dtype=wp.float64), factor: wp.float64, gravity: wp.vec3d, wall_lo: wp.vec3d,
                   wall_hi: wp.vec3d, solid_lo: wp.array(dtype=wp.vec3d),
                   solid_hi: wp.array(dtype=wp.vec3d), n_solids: int, base: wp.array(dtype=Rigid),
                   rates_at: wp.array(dtype=Rigid), sums: wp.array(dtype=wp.vec3d), out: wp.array(dtype=Rigid),
                   poses: wp.array(dtype=Pose)):
        """Each body's pose at t + factor dt: a prescribed body's from its law (a series' from its
        rows of ``series``, series_table); a floating body's state advanced from ``base`` by factor
        dt with the velocities of ``rates_at`` and the last force evaluation's force and torque
        (sums[2 b], sums[2 b + 1]) into ``out`` (factor 0: base itself), its acceleration from those."""
        b = wp.tid()
        law = laws[b]
        t = clock[T] + factor * clock[DT]
        if law.kind == SINUSOID or law.kind == MOVE or law.kind == TRANSLATE:
            poses[b] = prescribed_pose(law, t)
            return
        if law.kind == SERIES:
            poses[b] = series_pose(law, series, t)
            return
        if law.kind == DRIVEN:
            poses[b] = driven_pose(law, t)
            return
        if law.kind != FLOATING:
            return
        body = base[b]
        force = wp.cw_mul(sums[2 * b] + gravity * law.mass + law.ext_force, law.translate)
        torque = wp.cw_mul(sums[2 * b + 1] + law.ext_torque, law.rotate)
        if t <= law.release:  # held until released: it stands where it is, at rest
            force = wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
            torque = force
        if factor > wp.float64(0.0) and t > law.release:
            dt = factor * clock[DT]
            at = rates_at[b]
            body.x = body.x + at.v * dt
            # a contact at the stage whose rates these are holds the velocity out of it too: the
            # corrector moves the body with the half step's velocity, which a contact stopped, and
            # would otherwise let the velocity into a floor it rests on grow unseen
            body.v = stop_along(body.v + force * (dt / law.mass), at.touch)
            body.touch = wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))
            body.q = turned(body.q, angular_velocity(law, at), dt)
            body.ang = body.ang + torque * dt
            for k in range(n_solids):
                body = solid_contact(law, body, solid_lo[k], solid_hi[k])
            body = wall_contact(law, body, wall_lo, wall_hi)
        out[b] = body
        w = angular_velocity(law, body)
        pose = Pose()
        pose.x = body.x
        pose.q = body.q
        pose.v = body.v
        pose.w = w
        pose.a = force / law.mass
        # Euler's equations in the world frame: I_w alpha = T - omega x L
        pose.alpha = wp.cw_mul(world_inertia_inv(law, body.q) * (torque - wp.cross(w, body.ang)), law.rotate)
        poses[b] = pose

    @wp.func
    def moving(laws: wp.array(dtype=Law), ptype: wp.array(dtype=wp.int32), body: wp.array(dtype=wp.int32),
               i: int) -> bool:
        """Whether particle i belongs to a body that moves."""
        b = body[i]
        if b < 0 or ptype[i] != BOUNDARY:
            return False
        return laws[b].kind != FIXED

    @wp.kernel(enable_backward=False, module="unique")
    def move_walls(laws: wp.array(dtype=Law), poses: wp.array(dtype=Pose), ptype: wp.array(dtype=wp.int32),
                   body: wp.array(dtype=wp.int32), ids: wp.array(dtype=wp.int32), rest: wp.array(dtype=wp.vec3d),
                   pos: wp.array(dtype=vec), vel: wp.array(dtype=vec), acc: wp.array(dtype=vec)):
        """Each moving body's particles on its pose (the module's docstring), with their velocity and
        acceleration; ``rest`` is in the caller's order."""
        i = wp.tid()
        b = body[i]
        if not moving(laws, ptype, body, i):
            return
        pose = poses[b]
        arm = wp.quat_rotate(pose.q, rest[ids[i]] - laws[b].centre)
        x = pose.x + arm
        u = pose.v + wp.cross(pose.w, arm)
        a = pose.a + wp.cross(pose.alpha, arm) + wp.cross(pose.w, wp.cross(pose.w, arm))
        pos[i] = vec(scalar(x[0]), scalar(x[1]), scalar(x[2]))
        vel[i] = vec(scalar(u[0]), scalar(u[1]), scalar(u[2]))
        acc[i] = vec(scalar(a[0]), scalar(a[1]), scalar(a[2]))

    @wp.kernel(enable_backward=False, module="unique")
    def body_bounds(laws: wp.array(dtype=Law), candidate: wp.array(dtype=Rigid), lo: wp.vec3d, hi: wp.vec3d,
                    fail: wp.array(dtype=wp.int32)):
        """Flags body_outside with the lowest id of a floating body whose centre left the domain [lo,
        hi] in the candidate: no wall stops one above an open tank, and a push can carry it there."""
        b = wp.tid()
        law = laws[b]
        if law.kind != FLOATING:
            return
        centre = box_centre(law, candidate[b])
        for ax in range(3):
            if centre[ax] < lo[ax] or centre[ax] > hi[ax]:
                wp.atomic_min(fail, health.BODY_OUTSIDE, b)

    @wp.kernel(enable_backward=False, module="unique")
    def commit_rigid(fail: wp.array(dtype=wp.int32), candidate: wp.array(dtype=Rigid), state: wp.array(dtype=Rigid)):
        """The candidate's floating bodies become the state, if the step is healthy."""
        b = wp.tid()
        if healthy(fail):
            state[b] = candidate[b]

    def law_list(motions: list) -> list:
        """The Law of each of ``motions`` by body id (None: fixed), at least one."""
        table, first = [], 0
        for m in motions or [None]:
            law = Law()
            law.kind = FIXED
            law.axis, law.rotate, law.translate = wp.vec3d(0.0, 0.0, 1.0), wp.vec3d(0.0), wp.vec3d(0.0)
            law.mass = 1.0
            law.release = -1.0
            law.q0 = wp.quatd(0.0, 0.0, 0.0, 1.0)
            if isinstance(m, Motion):
                axis = np.asarray(m.axis, dtype=np.float64)
                law.kind = LAW_ID[m.law]
                law.centre, law.amplitude = wp.vec3d(*m.centre), wp.vec3d(*m.amplitude)
                law.omega = 2.0 * math.pi / m.period if m.law == "sinusoid" else 0.0
                law.phase, law.angle = m.phase, m.angle
                law.axis = wp.vec3d(*(axis / np.linalg.norm(axis)))
                law.start, law.duration, law.ramp = m.start, m.duration, m.ramp
                law.x0 = law.centre  # a driven body stands where the scene put it until driven
                if m.law == "series":
                    law.first, law.count = first, len(m.series)
                    first += len(m.series)
            elif isinstance(m, Floating):
                inertia = np.asarray(m.inertia, dtype=np.float64)
                # a 2D body's only inertia is about z: the others are set to 1 and their axes held
                inverse = np.diag([1.0 / d if d > 0.0 else 0.0 for d in np.diag(inertia)]) \
                    if np.allclose(inertia, np.diag(np.diag(inertia))) else np.linalg.inv(inertia)
                law.kind = FLOATING
                law.centre = wp.vec3d(*m.centre)
                law.mass, law.release = m.mass, m.release
                law.inertia, law.inv_inertia = wp.mat33d(*inertia.ravel()), wp.mat33d(*inverse.ravel())
                law.corner_lo, law.corner_hi = wp.vec3d(*m.corner_lo), wp.vec3d(*m.corner_hi)
                law.radius, law.round_axis, law.half_length = m.radius, wp.vec3d(*m.round_axis), m.half_length
                law.translate = wp.vec3d(*(1.0 if f else 0.0 for f in m.translate))
                law.rotate = wp.vec3d(*(1.0 if f else 0.0 for f in m.rotate))
            table.append(law)
        return table

    def external(law, force, torque):
        """``law`` (a floating body's Law) with an external force and torque (world, about its
        centre of mass)."""
        law.ext_force, law.ext_torque = wp.vec3d(*force), wp.vec3d(*torque)
        return law

    def segment(law, t0: float, position, quaternion, velocity, omega, acceleration, angular_acceleration):
        """``law`` (a Law) on the segment from t0 (driven_pose), all in the scene's axes."""
        law.t0 = t0
        law.x0, law.q0 = wp.vec3d(*position), wp.quatd(*quaternion)
        law.v0, law.w0 = wp.vec3d(*velocity), wp.vec3d(*omega)
        law.lin_acc, law.ang_acc = wp.vec3d(*acceleration), wp.vec3d(*angular_acceleration)
        return law

    def rigid_states(motions: list, device) -> wp.array:
        """Each body's floating state at t = 0: at its centre, at rest, unturned."""
        table = []
        for m in motions or [None]:
            body = Rigid()
            body.x = wp.vec3d(*(m.centre if m is not None else (0.0, 0.0, 0.0)))
            body.v, body.ang, body.q = wp.vec3d(0.0), wp.vec3d(0.0), wp.quatd(0.0, 0.0, 0.0, 1.0)
            body.touch = wp.vec3d(0.0)
            if isinstance(m, Floating):
                body.v = wp.vec3d(*m.velocity)
                body.ang = wp.vec3d(*(np.asarray(m.inertia, dtype=np.float64) @ np.asarray(m.omega, dtype=np.float64)))
            table.append(body)
        return wp.array(table, dtype=Rigid, device=device)

    return SimpleNamespace(Law=Law, Rigid=Rigid, Pose=Pose, body_poses=body_poses, body_contacts=body_contacts,
                           move_walls=move_walls, moving=moving, body_bounds=body_bounds,
                           commit_rigid=commit_rigid,
                           law_list=law_list, segment=segment, external=external,
                           rigid_states=rigid_states)
