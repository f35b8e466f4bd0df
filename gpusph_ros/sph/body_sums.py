"""What the moving bodies' particles add up to each step: a floating body's force and torque from the
fluid, and the moving bodies' work on the fluid (bodies.py integrates the one and health.py checks
the other).

A floating body's force and torque (bodies.py's F = sum m_i acc_i, T = sum rho_i x m_i acc_i about
its centre of mass) are summed in the order of its particles' ids in the run, whatever slots or
ranks hold them. Each particle writes its two terms into its own row of a table (``wrench_terms``:
its row is its place among the run's floating-body particles, counted in id order), and the table
is summed in an order fixed by its length (``wrench_sums``, sums.py). On MPI ranks each rank writes
the rows of the particles it owns and leaves the others zero, and the ranks' tables are added before
the sum (sph/exchange.py): a row's one term plus zeros is that term exactly, so every rank sums the
table one rank sums, and a floating body moves bit for bit as on one rank (tests/test_ranks.py).

The moving bodies' work is a sum over their particles too, each rank's over the particles it owns
(``work_on_fluid``), added across ranks before it joins the run's total (Solver.each_total).
"""
import functools
from types import SimpleNamespace

import warp as wp

from . import bodies, sums
from .state import BOUNDARY, DT


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    moving = bodies.build(scalar).moving

    @wp.kernel(enable_backward=False, module="unique")
    def wrench_terms(poses: wp.array(dtype=bodies.Pose), ptype: wp.array(dtype=wp.int32),
                     body: wp.array(dtype=wp.int32), ids: wp.array(dtype=wp.int32), rows: wp.array(dtype=wp.int32),
                     ranked: int, owned: wp.array(dtype=wp.int32), pos: wp.array(dtype=vec),
                     mass: wp.array(dtype=scalar), acc: wp.array(dtype=vec), terms: wp.array2d(dtype=wp.vec3d)):
        """Each floating-body particle's force m_i acc_i (the force pass's reaction) and its torque
        about its body's centre of mass into its row of ``terms`` (``rows``, by the caller's index:
        -1 for a particle of no floating body); ``ranked``: only the particles this rank owns."""
        i = wp.tid()
        r = rows[ids[i]]
        if r < 0 or ptype[i] != BOUNDARY or (ranked != 0 and owned[i] == 0):
            return
        a = acc[i]
        f = wp.vec3d(wp.float64(a[0]), wp.float64(a[1]), wp.float64(a[2])) * wp.float64(mass[i])
        x = pos[i]
        arm = wp.vec3d(wp.float64(x[0]), wp.float64(x[1]), wp.float64(x[2])) - poses[body[i]].x
        terms[r, 0] = f
        terms[r, 1] = wp.cross(arm, f)

    @wp.kernel(enable_backward=False, module="unique")
    def wrench_sums(row_body: wp.array(dtype=wp.int32), terms: wp.array2d(dtype=wp.vec3d),
                    part: wp.array2d(dtype=wp.vec3d), lead: int, step: int, members: int, chunk: int, stride: int):
        """Block k of ``terms``' rows (sums.py), each row's force and torque added into its body's
        slots part[k, 2 b] and part[k, 2 b + 1] (``row_body``: each row's body)."""
        k = wp.tid() * stride + chunk
        n = terms.shape[0]
        for s in range(part.shape[1]):
            part[k, s] = wp.vec3d(wp.float64(0.0))
        for j in range(members):
            r = sums.member(k, j, lead, step)
            if r < n:
                b = row_body[r]
                part[k, 2 * b] = part[k, 2 * b] + terms[r, 0]
                part[k, 2 * b + 1] = part[k, 2 * b + 1] + terms[r, 1]

    @wp.kernel(enable_backward=False, module="unique")
    def work_on_fluid(laws: wp.array(dtype=bodies.Law), clock: wp.array(dtype=wp.float64), stride: int,
                      ptype: wp.array(dtype=wp.int32), body: wp.array(dtype=wp.int32), ranked: int,
                      owned: wp.array(dtype=wp.int32), mass: wp.array(dtype=scalar), acc: wp.array(dtype=vec),
                      vel: wp.array(dtype=vec), part: wp.array2d(dtype=wp.float64), lead: int, step: int,
                      members: int, chunk: int, launch_stride: int):
        """Block k's share (part[k, 0], sums.py) of the work of one step (``stride`` steps dt:
        multirate's coarse step) of the moving bodies on the fluid: stride dt sum_w -m_w a_w . v_w
        over their particles, a_w the fluid's force on w over m_w and v_w their velocity at the
        step's midpoint (the corrector's rates): the energy the fluid may gain (health.census_check).
        ``ranked``: only the particles this rank owns."""
        k = wp.tid() * launch_stride + chunk
        n = ptype.shape[0]
        work = wp.float64(0.0)
        for j in range(members):
            i = sums.member(k, j, lead, step)
            if i < n:
                if moving(laws, ptype, body, i) and (ranked == 0 or owned[i] != 0):
                    work = work - wp.float64(mass[i] * wp.dot(acc[i], vel[i]))
        part[k, 0] = wp.float64(stride) * clock[DT] * work

    @wp.kernel(enable_backward=False, module="unique")
    def add_into(value: wp.array(dtype=wp.float64), total: wp.array(dtype=wp.float64), slot: int):
        """total[slot] += value[0]: a step's work into the run's."""
        total[slot] = total[slot] + value[0]

    return SimpleNamespace(wrench_terms=wrench_terms, wrench_sums=wrench_sums, work_on_fluid=work_on_fluid,
                           add_into=add_into)
