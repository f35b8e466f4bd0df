"""What a model will hold, known before anything is allocated: an upper bound on its particles and
the memory they take, checked against ``max_particles`` and the free memory of the device and the
host, so that a spacing a thousand times too fine is refused with the numbers instead of
exhausting the machine.

Memory per particle (measured with ``Solver.device_bytes`` on DamBreak 1 and the 2D collapse, and
checked by the tests): 54 scalars of state, half-step, candidate and scratch arrays plus 56 bytes of
integers, and what the neighbour search holds (``config.cell_walks``): with lists, the list, 4 bytes
x ``default_max_neighbours`` (248 in 3D, 72 in 2D at h = 1.3 dx: the most a run's lists may widen
to; the solver measures its own, narrower at the start, sph/neighbours.py), its count and the sorted
copies its build reads (4 scalars, 8 bytes); without, the kinds, h and needs as of the last sort
(1 scalar, 8 bytes). Building the particles on the host takes about HOST_BYTES a particle more.
Refinement zones are counted exactly as they are split, each level before it is made
(``check_count``, from refine.split), with the wider lists a refined run holds.
"""
import math
from pathlib import Path

from ..sph import boundaries
from ..sph.config import ConfigError, SolverConfig
from ..sph.kernels import coarse_stride
from ..sph.neighbours import default_max_neighbours
from .boxes import cells

HOST_BYTES = 200  # numpy arrays of the particle set and the lattice fills, per particle
_SCALARS, _INTEGER_BYTES = 54, 56
_LIST_SCALARS, _LIST_INTEGER_BYTES = 4, 8  # the sorted positions and h, the sorted kinds and the count
_WALK_SCALARS, _WALK_INTEGER_BYTES = 1, 8  # h, the kinds and the needs as of the sort
_STRESS = 6  # of the scalars: the SPS stress, held only under viscosity sps
_WALL_NORMAL = 3  # beyond them: the walls' face normals, held only under wall_flux normal
_LEVEL_BYTES = 20  # with zones: the levels' spawn and free-slot bookkeeping (sph/levels.py)
USABLE = 0.9  # of the free memory a run may plan to take
# the most particles whose arrays Warp can shape: the cell sort's keys hold 2 n int32 entries, and a
# shape is 32-bit (the neighbour lists are n x width, sph/neighbours.lists_array)
MAX_INDEXED = (2 ** 31 - 1) // 2


def particle_bound(scene, cfg: SolverConfig, fluid_boxes) -> int:
    """At least as many particles as ``scenes.build`` makes of ``scene`` at ``cfg.dx``, and exactly as
    many where the walls have a volume (dynamic, mdbc, adami) and the obstacles are blocks of it:
    ``fluid_boxes`` filled, particle walls (the boundary model's layers of its spacing) and the
    obstacles' blocks."""
    dim, dx = scene.dim, cfg.dx
    n = sum(math.prod(cells(hi[ax] - lo[ax], dx) for ax in range(dim)) for lo, hi in fluid_boxes)
    n += sum(math.prod(cells(o.hi[ax] - o.lo[ax], dx) for ax in range(dim)) for o in scene.obstacles)
    faces = [face for face, kind in scene.walls.items() if kind == "particles"]
    if not faces:
        return n
    model = boundaries.model(cfg.boundary)
    up = dim - 1
    axis = {face: up if face in ("floor", "lid") else "xy".index(face[0]) for face in faces}
    if model.volume:
        # exactly boxes.wall_particles: the fluid's lattice continued ``layers`` deep beyond each
        # particle face, less the tank's inside
        layers = model.layers(cfg.hdx)
        inside = [cells(scene.tank[ax], dx) for ax in range(dim)]
        sides = [sum(1 for face in faces if axis[face] == ax and not scene.periodic[ax]) for ax in range(dim)]
        return n + math.prod(inside[ax] + layers * sides[ax] for ax in range(dim)) - math.prod(inside)
    spacing = model.spacing(dx, cfg.mk_beta)
    layers = model.layers(cfg.hdx) + 1  # the shell sits half a spacing out
    outer = [cells(scene.tank[ax], spacing) + (0 if scene.periodic[ax] else 2 * layers) for ax in range(up)]
    outer.append(cells(scene.tank[up], spacing) + layers * (2 if "lid" in scene.walls else 1))
    for face in faces:  # each face's slab of wall particles, edges counted twice
        ax = axis[face]
        if not scene.periodic[ax]:
            n += layers * math.prod(outer[other] for other in range(dim) if other != ax)
    return n


def device_bytes(n: int, cfg: SolverConfig, refined: bool = False) -> int:
    """The device memory a solver of ``n`` particles takes (an estimate within a few percent);
    ``refined``: with refinement zones, whose lists are wider and whose levels keep books."""
    scalar = 8 if cfg.precision == "float64" else 4
    finest = 0.5 if refined else 1.0
    integers = _INTEGER_BYTES + (_LEVEL_BYTES if refined else 0)
    substeps = coarse_stride(cfg, refined)
    scalars = _SCALARS - (0 if cfg.viscosity == "sps" else _STRESS) + (_WALL_NORMAL if cfg.wall_flux == "normal" else 0)
    if cfg.cell_walks:
        return n * ((scalars + _WALK_SCALARS) * scalar + integers + _WALK_INTEGER_BYTES)
    lists = 4 * default_max_neighbours(cfg.dim, cfg.hdx, finest, substeps)
    return n * (lists + (scalars + _LIST_SCALARS) * scalar + integers + _LIST_INTEGER_BYTES)


def host_free_bytes() -> int:
    """Available memory of this machine (Linux: MemAvailable), or a very large number elsewhere."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 1 << 62


def device_free_bytes(device: str) -> int:
    import warp as wp

    d = wp.get_device(device)
    return host_free_bytes() if d.is_cpu else int(d.free_memory)


def _gib(b: float) -> str:
    return f"{b / 2 ** 30:.3g} GiB"


def check(scene, cfg: SolverConfig, fluid_boxes):
    """ConfigError on dx when the model would pass ``max_particles`` or the free memory."""
    n = particle_bound(scene, cfg, fluid_boxes)
    return check_count(n, cfg, "dx", cfg.dx, f"dx = {cfg.dx:g} m needs up to", "a coarser spacing")


def check_count(n: int, cfg: SolverConfig, field: str, value, needs: str, remedy: str, refined: bool = False):
    """ConfigError on ``field`` (its ``value``: "``remedy``: ``needs`` n particles, ...") when ``n``
    particles would pass ``max_particles``, the free memory or the arrays' 32-bit shapes; (n, device
    bytes) otherwise."""
    need, why = shortfall(n, cfg, refined)
    if why:
        raise ConfigError(field, value, f"{remedy}: {needs} {n:.3g} particles, {_gib(need)} on {cfg.device}{why}")
    return n, need


def shortfall(n: int, cfg: SolverConfig, refined: bool = False, free_dev: "int | None" = None) -> tuple:
    """(device bytes of ``n`` particles, "" or why they do not fit: ``max_particles``, the device's free
    memory (``free_dev``, else asked of the device), the host's, or a 32-bit array shape)."""
    need = device_bytes(n, cfg, refined)
    cpu = cfg.device == "cpu"
    host = n * HOST_BYTES + (need if cpu else 0)
    if free_dev is None and not cpu:
        free_dev = device_free_bytes(cfg.device)
    free_host = host_free_bytes()
    if n > cfg.max_particles:
        return need, f"; max_particles is {cfg.max_particles:,}"
    if not cpu and need > USABLE * free_dev:
        return need, f"; {cfg.device} has {_gib(free_dev)} free"
    if host > USABLE * free_host:
        return need, f" and {_gib(host)} of host memory in all; this machine has {_gib(free_host)} free"
    if n > MAX_INDEXED:
        return need, f"; the cell sort's arrays (2 n entries) pass Warp's 32-bit array shape at {MAX_INDEXED:,}"
    return need, ""
