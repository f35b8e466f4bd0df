"""Prescribed rigid motion of a body's boundary particles (issue 45: bodies that move).

A body's motion is a translation d(t) and a rotation by the angle theta(t) about a fixed unit axis n
through the point c (the centre, where the body stands at t = 0). A particle of the body that stood
at r0 at t = 0 stands at, and moves with (Rodrigues' rotation R; rho = x - c - d, its arm from
the moved centre):

    x = c + d + R(n, theta) (r0 - c)
    v = d' + theta' n x rho
    a = d'' + theta'' n x rho + theta'^2 n x (n x rho)

as DualSPHysics' and GPUSPH's moving bodies do (DualSPHysics' ``MotionSinusoidal`` /
``MotionRectSinusoidal``: a sinusoid of the displacement and of the angle). Two laws, each starting
where the scene put the body:

- ``sinusoid``: d = A [sin(omega t + phi) - sin(phi)] and theta = Theta [sin(omega t + phi) -
  sin(phi)], omega = 2 pi / period: a piston (A along the flume) or a flap (Theta about its hinge);
  phi = -90 degrees starts it at rest;
- ``move``: d = D [s - sin(2 pi s) / (2 pi)], s = (t - start) / duration clamped to [0, 1]: the
  displacement D over the duration, starting and ending at rest with a continuous acceleration
  (the velocity 1 - cos(2 pi s) times D / duration), no rotation.

The solver sets the body's particles on their path at each stage of a step (the step's start, the
predictor's half step, the corrector's end: ``move_walls``), and stores their acceleration, which
the extrapolated-pressure wall's (g - a_w) term reads (boundaries/adami.py). The fluid sees the
wall's velocity through the pair terms as it sees a fixed wall's zero. A fixed body takes none of
this: a scene without motion launches nothing more and steps bit for bit as before.
"""

import functools
import math
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import warp as wp

from .state import BOUNDARY, DT, T

FIXED, SINUSOID, MOVE = 0, 1, 2
LAWS = ("sinusoid", "move")  # the scene's ``motion.type``
LAW_ID = {"sinusoid": SINUSOID, "move": MOVE}


@dataclass(frozen=True)
class Motion:
    """One body's prescribed motion (the module's docstring): SI units, angles in radians."""

    law: str = "sinusoid"
    centre: tuple = (0.0, 0.0, 0.0)  # [m] the rotation's centre at t = 0
    amplitude: tuple = (0.0, 0.0, 0.0)  # [m] sinusoid: A; move: the displacement D
    period: float = 0.0  # [s] sinusoid
    phase: float = 0.0  # [rad] sinusoid's phi
    angle: float = 0.0  # [rad] sinusoid's Theta
    axis: tuple = (0.0, 0.0, 1.0)  # the rotation's axis (normalised here)
    start: float = 0.0  # [s] move
    duration: float = 0.0  # [s] move

    def peak_speed(self, reach: float) -> float:
        """The largest speed [m/s] of a particle at most ``reach`` [m] from the centre: the time
        step's and the neighbour lists' bound, and what the scene's check holds under c0 / 10."""
        if self.law == "move":
            return 2.0 * float(np.linalg.norm(self.amplitude)) / self.duration
        omega = 2.0 * math.pi / self.period
        return omega * (float(np.linalg.norm(self.amplitude)) + abs(self.angle) * reach)


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.struct
    class Law:
        kind: int  # FIXED, SINUSOID or MOVE
        centre: wp.vec3d
        amplitude: wp.vec3d
        omega: wp.float64
        phase: wp.float64
        angle: wp.float64
        axis: wp.vec3d
        start: wp.float64
        duration: wp.float64

    @wp.func
    def profile(law: Law, t: wp.float64) -> wp.vec3d:
        """(f, f', f'') of the law's time profile at t: d = f A and theta = f Theta."""
        if law.kind == SINUSOID:
            s = wp.sin(law.omega * t + law.phase)
            c = wp.cos(law.omega * t + law.phase)
            return wp.vec3d(s - wp.sin(law.phase), law.omega * c, -law.omega * law.omega * s)
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
    def rotate(n: wp.vec3d, theta: wp.float64, r: wp.vec3d) -> wp.vec3d:
        """Rodrigues: r rotated by theta about the unit axis n."""
        c = wp.cos(theta)
        return r * c + wp.cross(n, r) * wp.sin(theta) + n * (wp.dot(n, r) * (wp.float64(1.0) - c))

    @wp.kernel(enable_backward=False, module="unique")
    def move_walls(laws: wp.array(dtype=Law), clock: wp.array(dtype=wp.float64), factor: wp.float64,
                   ptype: wp.array(dtype=wp.int32), body: wp.array(dtype=wp.int32), ids: wp.array(dtype=wp.int32),
                   rest: wp.array(dtype=wp.vec3d), pos: wp.array(dtype=vec), vel: wp.array(dtype=vec),
                   acc: wp.array(dtype=vec)):
        """Each moving body's particles where its law puts them at t + factor dt, with their
        velocity and acceleration (the module's docstring); ``rest`` is in the caller's order."""
        i = wp.tid()
        b = body[i]
        if b < 0 or ptype[i] != BOUNDARY:
            return
        law = laws[b]
        if law.kind == FIXED:
            return
        f = profile(law, clock[T] + factor * clock[DT])
        theta = law.angle * f[0]
        d = law.amplitude * f[0]
        arm = rotate(law.axis, theta, rest[ids[i]] - law.centre)
        spin = law.angle * f[1]
        a = law.amplitude * f[2] + wp.cross(law.axis, arm) * (law.angle * f[2]) \
            + wp.cross(law.axis, wp.cross(law.axis, arm)) * (spin * spin)
        x = law.centre + d + arm
        u = law.amplitude * f[1] + wp.cross(law.axis, arm) * spin
        pos[i] = vec(scalar(x[0]), scalar(x[1]), scalar(x[2]))
        vel[i] = vec(scalar(u[0]), scalar(u[1]), scalar(u[2]))
        acc[i] = vec(scalar(a[0]), scalar(a[1]), scalar(a[2]))

    @wp.kernel(enable_backward=False, module="unique")
    def work_on_fluid(laws: wp.array(dtype=Law), clock: wp.array(dtype=wp.float64), ptype: wp.array(dtype=wp.int32),
                      body: wp.array(dtype=wp.int32), mass: wp.array(dtype=scalar), acc: wp.array(dtype=vec),
                      vel: wp.array(dtype=vec), total: wp.array(dtype=wp.float64), slot: int):
        """total[slot] += the work of one step of the moving bodies on the fluid: dt sum_w -m_w a_w .
        v_w over their particles, a_w the fluid's force on w over m_w and v_w their velocity at the
        step's midpoint (the corrector's rates): the energy the fluid may gain (health.census_check)."""
        i = wp.tid()
        b = body[i]
        if b < 0 or ptype[i] != BOUNDARY:
            return
        if laws[b].kind == FIXED:
            return
        wp.atomic_add(total, slot, -clock[DT] * wp.float64(mass[i] * wp.dot(acc[i], vel[i])))

    def laws(motions: list, device) -> wp.array:
        """The device table of ``motions`` by body id (None: fixed), at least one entry."""
        table = []
        for m in motions or [None]:
            law = Law()
            law.kind = FIXED if m is None else LAW_ID[m.law]
            if m is not None:
                axis = np.asarray(m.axis, dtype=np.float64)
                law.centre, law.amplitude = wp.vec3d(*m.centre), wp.vec3d(*m.amplitude)
                law.omega = 2.0 * math.pi / m.period if m.law == "sinusoid" else 0.0
                law.phase, law.angle = m.phase, m.angle
                law.axis = wp.vec3d(*(axis / np.linalg.norm(axis)))
                law.start, law.duration = m.start, m.duration
            table.append(law)
        return wp.array(table, dtype=Law, device=device)

    return SimpleNamespace(Law=Law, move_walls=move_walls, work_on_fluid=work_on_fluid, laws=laws)
