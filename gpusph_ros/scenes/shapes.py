"""The solid an obstacle is inside its box [lo, hi]: the boundary particles that line it, what it
holds (the fluid it takes the place of), and its volume, centroid and inertia (a floating body's
defaults, as a uniform solid).

- ``box``: the box itself (``block_particles``: a lattice filling it exactly).
- ``wedge``: apex down at the middle of the box's floor, its sides rising at the deadrise beta to
  the box's top (a prism along y in 3D).
- ``cylinder``: the circle inscribed in the box's section across ``axis`` (2D: a disc, the box a
  square; 3D: the axis x, y or z, the box square across it).
- ``sphere`` (3D): the sphere inscribed in a cubic box.
- ``points``: the particles given (a hull from another tool, as GPUSPH's and DualSPHysics' points
  files), a spacing apart; its box is its extent, what it displaces of the fluid and what meets
  walls and bodies; its solid is unknown (a floating one is given its mass, centre and inertia).

Round shapes are lined with rings (shells on a sphere) of particles a spacing apart, from half a
spacing inside the surface inward, so that the surface the fluid sees is round, not a lattice's
staircase; each particle stands for dx^dim.
"""
import math
from dataclasses import dataclass

import numpy as np

from .boxes import cells, fill_box

SHAPES = ("box", "wedge", "cylinder", "sphere", "points")
ROUND = ("cylinder", "sphere")
AXES = ("x", "y", "z")
SPACING_SAMPLE = 4096  # points whose nearest neighbours give a points body's spacing


@dataclass(frozen=True)
class Solid:
    """A uniform solid's volume [m^3; m^2 per unit depth in 2D], centroid [m] and inertia tensor
    about the centroid per unit mass [m^2] (2D: the section turning about z)."""

    volume: float
    centroid: tuple
    inertia: tuple


def block_particles(lo, hi, dx: float, dim: int, layers: int, bottom: bool = False):
    """Boundary particles of an obstacle box [lo, hi], and the volume each stands for: fill_box's
    lattice (the outer layer half a spacing, at most dx/2, in from each face, where the fluid meets a
    tank wall, whatever the block's size), ``layers`` deep from each side face and from the top: a
    block as tall as the tank has a lid too, as a run-up without a wall friction climbs DamBreak 1's
    0.4 m obstruction and fell into the open block (docs/results/wall_pressure.md). A block standing
    on the floor has no bottom, the tank's floor is there; one that may leave it (``bottom``: a
    floating or moving body) has one: a floating box without it filled from below, and a held box
    at its draft felt a quarter of its buoyancy at dx = 1 cm."""
    pts, volume = fill_box(lo, hi, dx, dim)
    up = dim - 1
    shell = np.zeros(len(pts), dtype=bool)
    for ax in range(dim):
        n = cells(hi[ax] - lo[ax], dx)
        k = np.floor((pts[:, ax] - lo[ax]) / (hi[ax] - lo[ax]) * n).astype(int)  # the cell index
        if ax != up:
            shell |= (k < layers) | (k >= n - layers)
        else:
            shell |= (k >= n - layers) | ((k < layers) & bottom)
    return pts[shell], volume


def wedge_particles(lo, hi, dx: float, dim: int, layers: int, deadrise: float):
    """Boundary particles of a wedge in the box [lo, hi]: fill_box's lattice points inside it and
    within ``layers`` spacings of its sides or its top, and the volume each stands for."""
    pts, volume = fill_box(lo, hi, dx, dim)
    # how far each point stands above the wedge's side, vertically
    rise = pts[:, dim - 1] - lo[dim - 1] - np.abs(pts[:, 0] - 0.5 * (lo[0] + hi[0])) * math.tan(deadrise)
    near = (rise * math.cos(deadrise) < layers * dx) | (pts[:, dim - 1] > hi[dim - 1] - layers * dx)
    return pts[(rise >= 0.0) & near], volume


def _ring(radius: float, dx: float, stagger: float) -> np.ndarray:
    """Points a spacing apart on a circle of ``radius`` about the origin, (n, 2); the centre alone
    for a radius under half a spacing."""
    if radius < 0.5 * dx:
        return np.zeros((1, 2))
    n = max(3, round(2.0 * math.pi * radius / dx))
    angle = 2.0 * math.pi * (np.arange(n) + stagger) / n
    return radius * np.column_stack([np.cos(angle), np.sin(angle)])


def _radii(radius: float, dx: float, layers: int | None) -> list:
    """The rings' radii from half a spacing inside ``radius`` inward, ``layers`` of them (all the
    way to the centre when None)."""
    out, r = [], radius - 0.5 * dx
    while r > -0.25 * dx and (layers is None or len(out) < layers):
        out.append(max(r, 0.0))
        r -= dx
    return out


def _disc(radius: float, dx: float, layers: int | None) -> np.ndarray:
    return np.concatenate([_ring(r, dx, 0.5 * (j % 2)) for j, r in enumerate(_radii(radius, dx, layers))])


def _sphere_shell(radius: float, dx: float) -> np.ndarray:
    """Points about a spacing apart on a sphere (a Fibonacci lattice), (n, 3)."""
    n = max(1, round(4.0 * math.pi * radius * radius / (dx * dx)))
    if n == 1:
        return np.zeros((1, 3))
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = math.pi * (3.0 - math.sqrt(5.0)) * k
    s = np.sqrt(1.0 - z * z)
    return radius * np.column_stack([s * np.cos(phi), s * np.sin(phi), z])


def _across(dim: int, axis: int) -> list:
    """The two axes of a cylinder's section: (x, y) in 2D, the other two in 3D."""
    return [0, 1] if dim == 2 else [a for a in range(3) if a != axis]


def radius(obstacle, dim: int) -> float:
    """A round obstacle's radius: half its box's width across its axis (any axis of a sphere's)."""
    across = _across(dim, obstacle.axis)[0]
    return 0.5 * (obstacle.hi[across] - obstacle.lo[across])


def cylinder_particles(lo, hi, dx: float, dim: int, layers: int, axis: int):
    """Boundary particles of the cylinder inscribed in [lo, hi] about ``axis``: rings ``layers``
    deep under its round surface, and in 3D slices a spacing apart along it, filled to the centre
    within ``layers`` of its ends; each stands for dx^dim."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    centre = 0.5 * (lo + hi)
    a, b = _across(dim, axis)
    r = 0.5 * (hi[a] - lo[a])
    shell, full = _disc(r, dx, layers), _disc(r, dx, None)
    if dim == 2:
        pts = np.zeros((len(shell), 3))
        pts[:, [a, b]] = shell + centre[[a, b]]
        return pts, dx * dx
    n = cells(hi[axis] - lo[axis], dx)
    step = (hi[axis] - lo[axis]) / n
    out = []
    for k in range(n):
        section = full if k < layers or k >= n - layers else shell
        pts = np.zeros((len(section), 3))
        pts[:, [a, b]] = section + centre[[a, b]]
        pts[:, axis] = lo[axis] + (k + 0.5) * step
        out.append(pts)
    return np.concatenate(out), dx ** 3


def sphere_particles(lo, hi, dx: float, layers: int):
    """Boundary particles of the sphere inscribed in the cube [lo, hi]: shells ``layers`` deep under
    its surface; each stands for dx^3."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    shells = [_sphere_shell(r, dx) for r in _radii(0.5 * (hi[0] - lo[0]), dx, layers)]
    return np.concatenate(shells) + 0.5 * (lo + hi), dx ** 3


def particles(obstacle, dx: float, dim: int, layers: int):
    """The boundary particles of ``obstacle`` (a schema.Obstacle) and the volume each stands for; a
    box that may leave the floor (one that moves) has a bottom."""
    lo, hi = obstacle.lo, obstacle.hi
    if obstacle.shape == "wedge":
        return wedge_particles(lo, hi, dx, dim, layers, obstacle.deadrise)
    if obstacle.shape == "cylinder":
        return cylinder_particles(lo, hi, dx, dim, layers, obstacle.axis)
    if obstacle.shape == "sphere":
        return sphere_particles(lo, hi, dx, layers)
    if obstacle.shape == "points":
        return np.array(obstacle.points, dtype=np.float64), dx ** dim
    return block_particles(lo, hi, dx, dim, layers, bottom=obstacle.motion is not None)


def median_spacing(pts: np.ndarray, dim: int) -> float:
    """The median distance from each of ``pts`` (n x 3) to its nearest other: what a points body's
    particles are apart. Each point is held against the points of its own and the neighbouring
    cells of a grid (sorted by cell, a cell's points found by bisection); a nearest point no
    farther than a cell is the nearest of all, and the others look again in cells twice as wide,
    from cells too small to hold two. For many points, the median of SPACING_SAMPLE of them, evenly
    spread through the list. Infinite for one point."""
    pts = np.asarray(pts, dtype=np.float64)[:, :dim]
    n = len(pts)
    if n < 2:
        return math.inf
    lo = pts.min(axis=0)
    size = max(float(np.ptp(pts, axis=0).max()), 1e-12) / n  # as if on a line: a shell or a slab is denser
    sample = np.unique(np.linspace(0, n - 1, min(n, SPACING_SAMPLE)).astype(np.int64))
    nearest = np.empty(len(sample))
    todo = np.arange(len(sample))  # the sample's points without their nearest yet
    while len(todo):
        cell = np.floor((pts - lo) / size).astype(np.int64) + 1  # a margin of one cell on every side
        shape = cell.max(axis=0) + 2
        key = np.ravel_multi_index(cell.T, shape)
        order = np.argsort(key, kind="stable")
        sorted_key = key[order]
        mine = sample[todo]
        best = np.full(len(todo), np.inf)
        for offset in np.array(np.meshgrid(*[[-1, 0, 1]] * dim)).reshape(dim, -1).T:
            other = np.ravel_multi_index((cell[mine] + offset).T, shape)
            first, last = np.searchsorted(sorted_key, other), np.searchsorted(sorted_key, other, side="right")
            for k in range(int((last - first).max())):
                j = order[np.minimum(first + k, n - 1)]
                d = np.where((first + k < last) & (j != mine), np.linalg.norm(pts[mine] - pts[j], axis=1), np.inf)
                best = np.minimum(best, d)
        found = best <= size
        nearest[todo[found]] = best[found]
        todo = todo[~found]
        size *= 2.0
    return float(np.median(nearest))


def holds(obstacle, pts, dim: int, margin: float) -> np.ndarray:
    """Which of ``pts`` lie inside ``obstacle``'s solid grown by ``margin`` [m] (the fluid it takes
    the place of); a box, a wedge and points by their box."""
    lo, hi = np.asarray(obstacle.lo, dtype=float), np.asarray(obstacle.hi, dtype=float)
    in_box = np.all((pts[:, :dim] >= lo[:dim]) & (pts[:, :dim] <= hi[:dim]), axis=1)
    if obstacle.shape not in ROUND:
        return in_box
    d = pts - 0.5 * (lo + hi)
    if obstacle.shape == "sphere":
        return np.linalg.norm(d, axis=1) < radius(obstacle, dim) + margin
    a, b = _across(dim, obstacle.axis)
    round_ = np.hypot(d[:, a], d[:, b]) < radius(obstacle, dim) + margin
    if dim == 2:
        return round_
    ax = obstacle.axis
    return round_ & (np.abs(d[:, ax]) < 0.5 * (hi[ax] - lo[ax]) + margin)


def _polygon(xy: np.ndarray):
    """Area, centroid and second moments about the centroid (<x^2>, <y^2> per unit area) of a simple
    polygon, counter-clockwise (the shoelace sums)."""
    x, y = xy[:, 0], xy[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = cross.sum() / 2.0
    cx = ((x + xn) * cross).sum() / (6.0 * area)
    cy = ((y + yn) * cross).sum() / (6.0 * area)
    ixx = ((x * x + x * xn + xn * xn) * cross).sum() / (12.0 * area) - cx * cx
    iyy = ((y * y + y * yn + yn * yn) * cross).sum() / (12.0 * area) - cy * cy
    return area, (cx, cy), (ixx, iyy)


def wedge_section(lo, hi, dim: int, deadrise: float) -> np.ndarray:
    """The wedge's section in the (x, up) plane, counter-clockwise from its apex: a triangle when
    its sides reach the box's top inside the box, else a pentagon with the box's walls."""
    up = dim - 1
    apex, half, top = 0.5 * (lo[0] + hi[0]), 0.5 * (hi[0] - lo[0]), hi[up]
    reach = (top - lo[up]) / math.tan(deadrise)  # across, where a side meets the top
    if reach <= half:
        return np.array([(apex, lo[up]), (apex + reach, top), (apex - reach, top)])
    chine = lo[up] + half * math.tan(deadrise)
    return np.array([(apex, lo[up]), (hi[0], chine), (hi[0], top), (lo[0], top), (lo[0], chine)])


def solid(obstacle, dim: int) -> Solid:
    """The volume, centroid and inertia per unit mass of ``obstacle``'s solid, uniform."""
    lo, hi = np.asarray(obstacle.lo, dtype=float), np.asarray(obstacle.hi, dtype=float)
    size = hi - lo
    centre = 0.5 * (lo + hi)
    if dim == 2:
        size[2], centre[2] = 0.0, 0.0
    if obstacle.shape in ("box", "points"):  # points: the box, unless the scene gives the body's
        a, b, c = size
        return Solid(float(np.prod(size[:dim])), tuple(centre),
                     _diag((b * b + c * c) / 12.0, (a * a + c * c) / 12.0, (a * a + b * b) / 12.0))
    if obstacle.shape == "wedge":
        area, (cx, cu), (mxx, muu) = _polygon(wedge_section(lo, hi, dim, obstacle.deadrise))
        up = dim - 1
        centroid = list(centre)
        centroid[0], centroid[up] = cx, cu
        if dim == 2:
            return Solid(area, tuple(centroid), _diag(muu, mxx, mxx + muu))
        length = size[1]
        return Solid(area * length, tuple(centroid),
                     _diag(muu + length ** 2 / 12.0, mxx + muu, mxx + length ** 2 / 12.0))
    r = radius(obstacle, dim)
    if obstacle.shape == "sphere":
        m = 0.4 * r * r
        return Solid(4.0 / 3.0 * math.pi * r ** 3, tuple(centre), _diag(m, m, m))
    if dim == 2:
        q = r * r / 4.0
        return Solid(math.pi * r * r, tuple(centre), _diag(q, q, 2.0 * q))
    length = size[obstacle.axis]
    moments = [r * r / 4.0 + length * length / 12.0] * 3
    moments[obstacle.axis] = r * r / 2.0
    return Solid(math.pi * r * r * length, tuple(centre), _diag(*moments))


def _diag(a: float, b: float, c: float) -> tuple:
    return ((float(a), 0.0, 0.0), (0.0, float(b), 0.0), (0.0, 0.0, float(c)))


def contact(obstacle, dim: int) -> dict:
    """What of a round body meets the tank's walls (bodies.Floating's radius, round_axis and
    half_length); nothing for a box or a wedge, whose box's corners do."""
    if obstacle.shape not in ROUND:
        return {}
    if obstacle.shape == "sphere":
        return {"radius": radius(obstacle, dim)}
    axis = obstacle.axis  # z for a 2D disc, its length none
    return {"radius": radius(obstacle, dim), "round_axis": tuple(float(a == axis) for a in range(3)),
            "half_length": 0.5 * (obstacle.hi[axis] - obstacle.lo[axis]) if dim == 3 else 0.0}
