"""Force and torque that the fluid exerts on a body made of boundary particles.

The force is the net reaction of every fluid neighbour on the body's particles, which is what
GPUSPH and DualSPHysics report: the solver's force pass leaves on each body particle
acc = -sum_fluid (m_j / m_i) a_(j <- i), so F = sum_i m_i acc_i. The torque is taken about a
given centre, T = sum_i (x_i - c) x m_i acc_i. Both come from the last force evaluation (the half
step of the last step) and are summed on the solver's device.
"""
import functools

import numpy as np
import warp as wp


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)

    @wp.kernel(enable_backward=False, module="unique")
    def sum_wrench(body_id: int, centre: vec, body: wp.array(dtype=wp.int32), pos: wp.array(dtype=vec),
                   mass: wp.array(dtype=scalar), acc: wp.array(dtype=vec), out: wp.array(dtype=vec)):
        i = wp.tid()
        if body[i] == body_id:
            f = mass[i] * acc[i]
            wp.atomic_add(out, 0, f)
            wp.atomic_add(out, 1, wp.cross(pos[i] - centre, f))

    return sum_wrench


class BodyWrench:
    """The wrench on body ``body_id`` about ``centre`` [m]. In 2D runs forces are per unit depth."""

    def __init__(self, solver, body_id: int, centre=(0.0, 0.0, 0.0)):
        self.solver = solver
        self.body_id = int(body_id)
        self.centre = solver.vec(*[float(c) for c in centre])
        self._sum = build(solver.scalar)
        self._out = wp.zeros(2, dtype=solver.vec, device=solver.device)

    def sample(self):
        """(force, torque) as host 3-vectors [N, N m]."""
        s = self.solver
        self._out.zero_()
        # one launch: CPU atomics are not atomic across the threads of a split launch
        wp.launch(self._sum, dim=s.n, inputs=[self.body_id, self.centre, s.body, s.pos, s.mass, s.acc, self._out],
                  device=s.device)
        out = self._out.numpy().astype(np.float64)
        return out[0], out[1]
