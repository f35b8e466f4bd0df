"""Box geometry to particles: lattice fill, walls of boundary particles or planes, tanks.

Conventions: the vertical axis is the last one of the dimension (y in 2D, z in 3D); the tank
floor is at 0 on that axis; a tank is open at the top. Fluid particles sit at the cell centres
of a lattice of spacing at most dx, squeezed by less than one cell per box so that each fluid box
is filled exactly: the first layer lies half a spacing from a wall and the top layer half a spacing
below the stated surface. Boundary particles lie in layers dx apart from dx/2 outside each wall face
and follow the fluid's lattice along it.
"""
from __future__ import annotations

import numpy as np

from ..sph import boundaries
from ..sph.config import Plane, SolverConfig
from ..sph.eos import hydrostatic_density
from ..sph.particles import Particles
from ..sph.state import BOUNDARY, FLUID

PLANES = boundaries.planes.MODEL.name
WALL_KINDS = ("particles", PLANES)  # a wall of the scene: particles of the run's boundary model, or a plane


def lattice(lo, hi, dx: float, dim: int) -> np.ndarray:
    """Cell centres of a lattice of spacing dx filling the box [lo, hi] (z = 0 in 2D)."""
    axes = []
    for ax in range(dim):
        count = int(round((hi[ax] - lo[ax]) / dx))
        axes.append(lo[ax] + (np.arange(count) + 0.5) * dx)
    grids = np.meshgrid(*axes, indexing="ij")
    pts = np.zeros((grids[0].size, 3))
    for ax in range(dim):
        pts[:, ax] = grids[ax].ravel()
    return pts


def cells(length: float, dx: float) -> int:
    """The smallest whole number of cells no wider than dx that fill ``length`` (at least one)."""
    return max(1, int(np.ceil(length / dx - 1e-9)))


def fill_box(lo, hi, dx: float, dim: int):
    """Fluid filling the box [lo, hi] exactly: along each axis the spacing is the box length over
    the smallest whole number of cells no wider than dx, so the top layer lies half a spacing
    (at most dx/2) below the stated surface (the thesis, Section 4.3, lost up to 20% of bore
    velocity to a lattice that put it elsewhere). A box thinner than dx on the vertical (last)
    axis is one layer dx/2 above its bottom. Returns the points and the particle volume, box
    volume / count."""
    counts = [cells(hi[ax] - lo[ax], dx) for ax in range(dim)]
    spacing = [(hi[ax] - lo[ax]) / counts[ax] for ax in range(dim)]
    axes = [lo[ax] + (np.arange(counts[ax]) + 0.5) * spacing[ax] for ax in range(dim)]
    up = dim - 1
    if hi[up] - lo[up] < dx:
        # a layer thinner than one spacing (a wet bed) is one layer of particles dx/2 above its
        # bottom, the distance every first layer keeps from a wall: nearer, a wall force that
        # holds rest at dx (Lennard-Jones r0) would throw it off; its mass stays the layer's
        axes[up] = np.array([lo[up] + 0.5 * dx])
    grids = np.meshgrid(*axes, indexing="ij")
    pts = np.zeros((grids[0].size, 3))
    for ax in range(dim):
        pts[:, ax] = grids[ax].ravel()
    return pts, float(np.prod(spacing))


def _wall_axis(length: float, dx: float, layers: int, walls: int):
    """Coordinates along one axis of a tank [0, length] and the spacing each stands for: inside,
    fill_box's lattice; beyond each of the ``walls`` faces (0, 1: the floor, 2: both ends),
    ``layers`` layers dx apart from dx/2 out."""
    n = cells(length, dx)
    out = (np.arange(layers) + 0.5) * dx
    coords = np.concatenate([-out[::-1]] * (walls > 0) + [(np.arange(n) + 0.5) * (length / n)]
                            + [length + out] * (walls == 2))
    return coords, np.where((coords > 0.0) & (coords < length), length / n, dx)


def wall_particles(hi, dx: float, dim: int, layers: int, periodic=(False, False, False), lid: bool = False):
    """``layers`` layers of points outside the walls of the tank [0, hi], open at the top unless
    ``lid`` (no walls across periodic axes), and the volume each stands for. Each wall's layers lie
    dx/2, 3 dx/2, ... from its own face, so the fluid's outer layer (fill_box) is dx from every wall
    whether or not the tank is a whole number of dx long; along a wall they follow the fluid's lattice. (A dx lattice
    from the origin put the far side wall of DamBreak 1's 0.67 m tank 1 dx out at dx = 2 cm and
    0.17 dx out at 3 cm, where fluid then crossed the face.)"""
    axes = [_wall_axis(hi[ax], dx, layers, 0 if periodic[ax] else len(_sides(ax, dim, lid))) for ax in range(dim)]
    grids = np.meshgrid(*[c for c, _ in axes], indexing="ij")
    sizes = np.meshgrid(*[w for _, w in axes], indexing="ij")
    pts = np.zeros((grids[0].size, 3))
    volume = np.ones(grids[0].size)
    for ax in range(dim):
        pts[:, ax] = grids[ax].ravel()
        volume *= sizes[ax].ravel()
    inside = np.ones(len(pts), dtype=bool)
    for ax in range(dim):
        inside &= (pts[:, ax] > 0.0) & (pts[:, ax] < hi[ax])
    return pts[~inside], volume[~inside]


def wall_shell(hi, dx: float, dim: int, spacing: float, periodic=(False, False, False),
               lid: bool = False) -> np.ndarray:
    """One layer of points dx/2 outside the walls of the tank [0, hi], open at the top unless
    ``lid``, ``spacing`` apart along the walls (finer than dx for Monaghan-Kajtar boundaries); none
    across periodic axes."""
    up = dim - 1
    pts = []
    for ax in range(dim):
        if periodic[ax]:
            continue
        for side in _sides(ax, dim, lid):
            axes = []
            for other in range(dim):
                if other == ax:
                    axes.append(np.array([-0.5 * dx if side == 0 else hi[ax] + 0.5 * dx]))
                elif periodic[other]:
                    # a whole number of spacings per period, so the layer tiles across the seam
                    count = max(1, int(round(hi[other] / spacing)))
                    axes.append((np.arange(count) + 0.5) * hi[other] / count)
                else:
                    top = hi[other] + (0.5 * dx if other != up or lid else 0.0)
                    axes.append(np.arange(-0.5 * dx, top + 1e-9 * dx, spacing))
            grids = np.meshgrid(*axes, indexing="ij")
            face = np.zeros((grids[0].size, 3))
            for k in range(dim):
                face[:, k] = grids[k].ravel()
            pts.append(face)
    pts = np.concatenate(pts)
    # faces meet along the edges; keep one point per position
    _, keep = np.unique(np.round(pts / (1e-6 * dx)).astype(np.int64), axis=0, return_index=True)
    return pts[np.sort(keep)]


def wall_faces(dim: int, lid: bool = False) -> tuple:
    """Names of the walls of a tank: the two ends of each horizontal axis, the floor, and with ``lid``
    the top (a tank is open at the top unless its scene says ``lid: true``)."""
    sides = ("x_min", "x_max", "floor") if dim == 2 else ("x_min", "x_max", "y_min", "y_max", "floor")
    return sides + ("lid",) * lid


def _sides(ax: int, dim: int, lid: bool) -> tuple:
    """The sides of axis ``ax`` that have a wall: both, but the vertical axis's top only with a lid."""
    return (0,) if ax == dim - 1 and not lid else (0, 1)


def _face(ax: int, side: int, dim: int) -> str:
    if ax == dim - 1:
        return "floor" if side == 0 else "lid"
    return "xy"[ax] + ("_min" if side == 0 else "_max")


def tank_planes(hi, dim: int, periodic=(False, False, False), faces=None, lid: bool = False) -> list:
    """The walls of the tank [0, hi] (open at the top unless ``lid``) named in ``faces`` (default:
    all) as planes with inward normals; none across periodic axes."""
    planes = []
    for ax in range(dim):
        if periodic[ax]:
            continue
        for side in _sides(ax, dim, lid):
            if faces is not None and _face(ax, side, dim) not in faces:
                continue
            normal = [0.0, 0.0, 0.0]
            normal[ax] = 1.0 if side == 0 else -1.0
            point = [0.0, 0.0, 0.0]
            point[ax] = 0.0 if side == 0 else hi[ax]
            planes.append(Plane(point=tuple(point), normal=tuple(normal)))
    return planes


def beyond_faces(pts, hi, dim: int, faces) -> np.ndarray:
    """True for each point that lies outside the tank [0, hi] across one of ``faces``."""
    out = np.zeros(len(pts), dtype=bool)
    for ax in range(dim):
        for side in (0, 1):
            if _face(ax, side, dim) in faces:
                out |= (pts[:, ax] < 0.0) if side == 0 else (pts[:, ax] > hi[ax])
    return out


def box_tank(cfg: SolverConfig, tank, fluid_boxes, walls="particles", headroom: float = 0.5):
    """Particles and configuration for fluid boxes at rest in a tank [0, tank].

    ``fluid_boxes`` is a list of (lo, hi) boxes; each starts hydrostatic under its own top.
    ``walls`` is "particles" (the configured boundary model), "planes", or a mapping from wall name
    (``wall_faces``) to one of those; the tank is open at the top unless the mapping names a "lid"
    (then there is no headroom, and no water leaves: health.LEFT_TANK). Horizontal axes that
    ``cfg.periodic`` marks have no walls and the domain spans exactly [0, tank] there. Returns the
    config with domain and planes filled in, and the particle set.
    """
    periodic = cfg.periodic
    dim, dx = cfg.dim, cfg.dx
    up = dim - 1
    g = cfg.g_norm
    kinds = {face: walls for face in wall_faces(dim)} if isinstance(walls, str) else dict(walls)
    lid = "lid" in kinds
    for face, kind in kinds.items():
        if kind not in WALL_KINDS:
            raise ValueError(f"walls.{face}: {kind!r} is not one of {', '.join(WALL_KINDS)}")
    plane_faces = {face for face, kind in kinds.items() if kind == PLANES}
    fluid, rho, mass = [], [], []
    for lo, hi in fluid_boxes:
        pts, volume = fill_box(lo, hi, dx, dim)
        fluid.append(pts)
        rho.append(hydrostatic_density(hi[up] - pts[:, up], cfg.rho0, cfg.eos_b, cfg.gamma, g))
        mass.append(np.full(len(pts), cfg.rho0 * volume))  # the fill's mass, rho0 x box volume
    fluid = np.concatenate(fluid)
    rho = np.concatenate(rho)
    layers = 0
    wall, wall_volume = np.zeros((0, 3)), np.zeros(0)
    if len(plane_faces) < len(kinds):
        model = boundaries.model(cfg.boundary)
        layers = model.layers(cfg.hdx)
        if model.volume:  # the fluid's lattice continued through the wall
            wall, wall_volume = wall_particles(tank, dx, dim, layers, periodic, lid)
        else:
            wall = wall_shell(tank, dx, dim, model.spacing(dx, cfg.mk_beta), periodic, lid)
            wall_volume = np.full(len(wall), dx ** dim)
        # a particle wall stops where a plane takes over
        kept = ~beyond_faces(wall, tank, dim, plane_faces)
        wall, wall_volume = wall[kept], wall_volume[kept]
    surface = max(hi[up] for _, hi in fluid_boxes)
    wall_rho = hydrostatic_density(surface - wall[:, up], cfg.rho0, cfg.eos_b, cfg.gamma, g)
    planes = tank_planes(tank, dim, periodic, plane_faces, lid)
    pad = [0.0 if periodic[ax] else (layers + 1) * dx for ax in range(3)]
    lo = [-pad[ax] if ax < dim else -1.0 for ax in range(3)]
    hi = [tank[ax] + pad[ax] if ax < dim else 1.0 for ax in range(3)]
    up_pad = (layers + 1) * dx
    lo[up] = -up_pad
    hi[up] = tank[up] * (1.0 + (0.0 if lid else headroom)) + up_pad
    # the faces fluid must not cross: walls on every non-periodic axis and the floor, and the top
    # with a lid; without one, fluid beyond a wall above its top has left the tank
    far = 1.0e30
    wall_lo = [0.0 if ax < dim and not periodic[ax] else -far for ax in range(3)]
    wall_hi = [tank[ax] if (ax < up or (ax == up and lid)) and not periodic[ax] else far for ax in range(3)]
    cfg = cfg.replace(domain_lo=tuple(lo), domain_hi=tuple(hi), planes=planes, wall_lo=tuple(wall_lo),
                      wall_hi=tuple(wall_hi), wall_top=far if lid else float(tank[up]))
    n_f, n_w = len(fluid), len(wall)
    particles = Particles(
        pos=np.concatenate([fluid, wall]),
        vel=np.zeros((n_f + n_w, 3)),
        rho=np.concatenate([rho, wall_rho]),
        mass=np.concatenate(mass + [cfg.rho0 * wall_volume]),
        ptype=np.concatenate([np.full(n_f, FLUID), np.full(n_w, BOUNDARY)]),
    )
    return cfg, particles
