"""The particle state of an output as rows of float32, packed on the solver's device.

One row per particle in scene order (the order the scene built them: fluid first, then boundary;
the solver keeps its arrays sorted into cells), excluded particles left out, columns x, y, z and
then the chosen fields. Positions and velocities are turned by the rotation the publisher gives (a
2D scene's vertical y onto z, ``output.frames``); ``kind`` says what a particle is (fluid, wall, body),
``spacing`` its particle spacing [m] (the scene's dx, or a refinement zone's: what a viewer colours
levels by, and (spacing)^dim its volume). One
kernel writes the rows into a device buffer, which on a GPU is copied into one reusable host buffer;
on the CPU the device buffer is the host buffer. No per-particle Python, no float64 round trip: the
copy off the device is the only pass over the data before serialisation.
"""
import functools

import numpy as np
import warp as wp

from ..sph.state import FLUID

FIELDS = ("vx", "vy", "vz", "density", "pressure", "kind", "spacing")  # what may follow x, y, z
FLUID_KIND, WALL_KIND, FIRST_BODY_KIND = 0, 1, 2  # kind: fluid, a fixed wall, then body k as 2 + k


@functools.lru_cache(maxsize=None)
def build(scalar):
    vec = wp.types.vector(3, scalar)
    mat = wp.types.matrix((3, 3), scalar)

    @wp.func
    def kind_of(ptype: int, body: int):
        kind = FLUID_KIND
        if ptype != FLUID:
            kind = WALL_KIND
            if body >= 0:
                kind = FIRST_BODY_KIND + body
        return wp.float32(kind)

    @wp.func
    def column(code: int, v: vec, rho: scalar, p: scalar, kind: wp.float32, spacing: wp.float32):
        # codes index FIELDS: 0-2 velocity components, 3 density, 4 pressure, 5 kind, 6 spacing
        value = wp.float32(p)
        if code < 3:
            value = wp.float32(v[code])
        elif code == 3:
            value = wp.float32(rho)
        elif code == 5:
            value = kind
        elif code == 6:
            value = spacing
        return value

    @wp.kernel(enable_backward=False, module="unique")
    def pack(ids: wp.array(dtype=wp.int32), pos: wp.array(dtype=vec), vel: wp.array(dtype=vec),
             rho: wp.array(dtype=scalar), pressure: wp.array(dtype=scalar), ptype: wp.array(dtype=wp.int32),
             body: wp.array(dtype=wp.int32), hsml: wp.array(dtype=scalar), h: scalar, dx: wp.float32, turn: mat,
             codes: wp.array(dtype=wp.int32), out: wp.array2d(dtype=wp.float32), chunk: int, stride: int):
        i = wp.tid() * stride + chunk
        row = ids[i]
        # + 0 turns the -0.0 that a turn's negative zero entries make of a 2D scene's z into 0.0
        x = turn * pos[i] + vec()
        for a in range(3):
            out[row, a] = wp.float32(x[a])
        v = turn * vel[i]
        # the levels' ratio h_i / h is a power of two, exact in any precision: the float32 spacing is
        # the one a float64 product would round to, with no float64 arithmetic in a float32 build
        spacing = dx * wp.float32(hsml[i] / h)
        for k in range(codes.shape[0]):
            out[row, 3 + k] = column(codes[k], v, rho[i], pressure[i], kind_of(ptype[i], body[i]), spacing)

    return pack


class CloudPacker:
    """Packs ``solver``'s particles with ``fields`` (a sequence from FIELDS); ``turn``: the 3x3
    rotation from the solver's axes to the published ones (identity by default). ``kind`` is
    FLUID_KIND, WALL_KIND, or FIRST_BODY_KIND + the particle's body id."""

    def __init__(self, solver, fields=FIELDS, turn=None):
        for name in fields:
            if name not in FIELDS:
                raise ValueError(f"particle_fields: {name!r} is not one of {', '.join(FIELDS)}")
        self.solver = solver
        self.fields = ("x", "y", "z") + tuple(fields)
        dev = solver.device
        self._pack = build(solver.scalar)
        self._codes = wp.array(np.array([FIELDS.index(name) for name in fields], dtype=np.int32), dtype=wp.int32,
                               device=dev)
        self._turn = wp.types.matrix((3, 3), solver.scalar)(*np.eye(3).ravel() if turn is None else
                                                          np.asarray(turn, dtype=float).ravel())
        shape = (solver.n, len(self.fields))
        self._rows = wp.zeros(shape, dtype=wp.float32, device=dev)
        self._host = self._rows if dev.is_cpu else wp.zeros(shape, dtype=wp.float32, device="cpu", pinned=True)

    def pack(self, every: bool = False) -> np.ndarray:
        """The rows, (n, 3 + fields) float32: a view of the reusable host buffer, valid until
        the next call. Excluded particles (sph.health) and a refinement level's passive particles
        and vacant slots (sph.levels) are left out, the others keep their order; ``every``: none
        left out, one row a particle id (a rank's, which keeps its own: sph/exchange.py)."""
        s = self.solver
        s.update_pressure()
        # on every core of a CPU (the solver's launcher): a memory-bound scatter of 32 B a particle
        s.launch(self._pack, s.n, [s.ids, s.pos, s.vel, s.rho, s.pressure, s.ptype, s.body, s.hsml,
                                     s.config.h, s.config.dx, self._turn, self._codes, self._rows])
        if self._host is not self._rows:
            wp.copy(self._host, self._rows)  # into pinned memory: asynchronous until the sync below
        wp.synchronize_device(s.device)
        rows = self._host.numpy()
        if every or not (s.excluded_particles or s.left_tank_particles or s.config.zones):
            return rows
        return rows[s.kept()]
