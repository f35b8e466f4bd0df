"""Refinement zones to particles: each zone (``refine:``, schema.Zone) adds a level of particles at
its spacing (sph/levels.py, adaptive particle refinement). Every particle of the parent level whose
centre lies in the zone gets 2^dim daughters on the sub-lattice of its own cell, each with
1/2^dim of its mass, its density, velocity, kind and body (the square pattern of Vacondio et al.
2013, CMAME 256, its daughters at the cell's sub-centres), so the zone's active fluid is that of
the uniform lattice at its spacing, mass exact. The parent's fluid stays as passive particles of
its level, and the parents just outside the zone give passive daughters (and walls) in a band one
fine kernel support wide: every active particle's kernel then holds particles of its own spacing
only. Fluid, walls and obstacles are split alike: a wall in a zone is at the zone's spacing too,
as many layers of it deep as the boundary model takes at that spacing (the daughters deeper in a
wall than that stand beyond every fluid particle's support of their level, so they are not made).

Zones are applied coarse to fine; a zone that reaches a tank face (lo or hi on the tank's
boundary) reaches on through that wall, so its wall particles are split too.
"""
import numpy as np

from ..sph.config import ConfigError
from ..sph.levels import band_width, edge_margin, sub_offsets
from ..sph.state import BOUNDARY, FLUID, PASSIVE, VACANT


def zone_bounds(zone, tank, dim):
    """The zone's box, open beyond every tank face it reaches (its walls' particles are in it)."""
    lo = np.array([-np.inf if zone.lo[ax] <= 0.0 else zone.lo[ax] for ax in range(dim)])
    hi = np.array([np.inf if zone.hi[ax] >= tank[ax] else zone.hi[ax] for ax in range(dim)])
    return lo, hi


def zone_boxes(zones, tank, dim: int, dx: float) -> list:
    """SolverConfig.zones: each zone's (lo, hi, spacing), 3D, beyond +-1e30 where it is open."""
    out = []
    for zone in zones:
        lo, hi = zone_bounds(zone, tank, dim)
        lo3, hi3 = np.full(3, -1.0e30), np.full(3, 1.0e30)
        lo3[:dim] = np.maximum(lo, -1.0e30)
        hi3[:dim] = np.minimum(hi, 1.0e30)
        out.append((tuple(float(v) for v in lo3), tuple(float(v) for v in hi3), zone.ratio * dx))
    return out


def check_nesting(zones, tank, dim: int, dx: float, hdx: float):
    """Each zone finer than half the scene's dx lies at least one kernel support (2h) of its parent
    level inside a zone of that level, so that no particle pairs with one of four times its spacing."""
    for k, z in enumerate(zones):
        if z.ratio >= 0.5:
            continue
        support = 2.0 * hdx * 2.0 * z.ratio * dx
        lo, hi = zone_bounds(z, tank, dim)
        fits = False
        for parent in zones:
            if parent.ratio != 2.0 * z.ratio:
                continue
            plo, phi = zone_bounds(parent, tank, dim)
            if np.all(lo - support >= plo) and np.all(hi + support <= phi):
                fits = True
        if not fits:
            raise ConfigError(f"refine[{k}]", z.name, f"a zone at least {support:.4g} m (the kernel support of ratio "
                                                      f"{2 * z.ratio:g}) inside a zone of ratio {2 * z.ratio:g}, or "
                                                      "reaching the same tank faces")


def distance_outside(pos: np.ndarray, lo: np.ndarray, hi: np.ndarray, dim: int) -> np.ndarray:
    """Each point's distance from the box [lo, hi] (0 inside it)."""
    gap = np.maximum(lo - pos[:, :dim], 0.0) + np.maximum(pos[:, :dim] - hi, 0.0)
    return np.linalg.norm(np.where(np.isfinite(gap), gap, 0.0), axis=1)


def wall_depth(pos: np.ndarray, body: np.ndarray, tank, solids, dim: int) -> np.ndarray:
    """How deep each boundary point lies in its solid: below a tank wall's face (``body`` -1; the
    tank [0, tank] open at the top) or in from the nearest face of obstacle ``body`` that the fluid
    meets (``solids``: {obstacle id: (lo, hi)} of the box obstacles; every face but one on the
    floor). An obstacle not in ``solids`` (a round one, a wedge) lies 0 deep: all of it is kept."""
    up = dim - 1
    lo = np.zeros(dim)
    hi = np.asarray(tank[:dim], dtype=np.float64).copy()
    hi[up] = np.inf
    depth = distance_outside(pos, lo, hi, dim)
    for k, (s_lo, s_hi) in solids.items():
        mine = body == k
        faces = [pos[mine, ax] - s_lo[ax] for ax in range(dim) if ax != up or s_lo[up] > 0.0]
        faces += [s_hi[ax] - pos[mine, ax] for ax in range(dim)]
        depth[mine] = np.min(faces, axis=0)
    depth[(body >= 0) & ~np.isin(body, list(solids))] = 0.0
    return depth


def _shallow(columns: dict, thickness: float, tank, solids, dim: int) -> np.ndarray:
    """Which of ``columns``' particles to keep: all but the boundary ones ``thickness`` or more deep
    in their solid."""
    wall = columns["ptype"] == BOUNDARY
    keep = np.ones(len(wall), dtype=bool)
    keep[wall] = wall_depth(columns["pos"][wall], columns["body"][wall], tank, solids, dim) < thickness
    return keep


def daughters(columns: dict, spacing: np.ndarray, parents: np.ndarray, target: float, dim: int, stratify=None):
    """The 2^dim daughters of ``parents`` (indices, each of spacing 2 ``target``) at spacing
    ``target``, as columns and spacings."""
    offsets = sub_offsets(2, dim)
    count = len(offsets)
    shift = np.tile(offsets, (len(parents), 1)) * np.repeat(spacing[parents], count)[:, None]
    out = {}
    for name, values in columns.items():
        rows = np.repeat(values[parents], count, axis=0)
        if name == "pos":
            rows = rows + shift
        elif name == "mass":
            rows = rows / count
        out[name] = rows
    if stratify is not None:
        out["rho"] = stratify(out["rho"], shift[:, dim - 1])
    return out, np.full(len(out["pos"]), target)


def check_paths(zones, moving: dict, names: list, tank, dim: int, dx: float, hdx: float):
    """Each moving body's path (``moving``: {obstacle id: (lo, hi) of the box it sweeps}) inside a
    zone, or clear of it, by levels.edge_margin of the zone's spacing: a body is not carried from one
    level to another."""
    for k, (lo, hi) in moving.items():
        lo, hi = np.asarray(lo)[:dim], np.asarray(hi)[:dim]
        for j, zone in enumerate(zones):
            z_lo, z_hi = zone_bounds(zone, tank, dim)
            margin = edge_margin(zone.ratio * dx, hdx)
            inside = np.all(lo - margin >= z_lo) and np.all(hi + margin <= z_hi)
            clear = np.any(lo - margin > z_hi) or np.any(hi + margin < z_lo)
            if not (inside or clear):
                raise ConfigError(f"refine[{j}]", zone.name, f"a zone that holds the path of moving obstacle "
                                                             f"'{names[k]}' or stays clear of it, {margin:.3g} m "
                                                             f"(levels.edge_margin) either side of its faces; the "
                                                             f"path spans {np.round(lo, 4).tolist()} to "
                                                             f"{np.round(hi, 4).tolist()} m")


def _reaching(moving: dict, lo: np.ndarray, hi: np.ndarray, dim: int) -> list:
    """The moving bodies whose path (``split``'s ``moving``) overlaps the box [lo, hi] (dim axes)."""
    return [k for k, (s_lo, s_hi) in moving.items()
            if np.all(np.asarray(s_lo)[:dim] <= hi) and np.all(np.asarray(s_hi)[:dim] >= lo)]


def split(columns: dict, spacing: np.ndarray, zones, tank, dim: int, dx: float, hdx: float, stratify=None,
          limit=None, layers=None, solids=None, moving=None):
    """``columns`` (name -> per-particle array: pos, rho, mass, ptype, body, ...) and ``spacing``
    with each zone's level added (levels.py, adaptive particle refinement):

    - every active particle of the parent level in the zone gets its daughters at the zone's spacing,
      active (fluid, walls, obstacles alike), and its fluid particles stay as the parent level's
      passive particles (state.PASSIVE); its walls stay as they are;
    - the parent level's active particles outside the zone get daughters too where these lie within
      a kernel support (2 h of the zone's level, and half its spacing) of the zone: walls, and
      passive fluid, so that every sum of the zone's active particles is over one spacing;
    - with ``layers`` (the boundary model's wall thickness in spacings), a wall's daughters only
      that many of the zone's spacings deep in their solid (``wall_depth``; ``solids`` the box
      obstacles' {id: (lo, hi)}), where the parent level's layers are twice as deep;
    - a moving body (``moving``: {id: the box it sweeps, (lo, hi) 3-vectors; check_paths}) inside
      the zone gets daughters all over, not only those the zone holds at the start: wherever it
      goes in the zone it is lined at the zone's spacing.

    ``stratify(rho, dz)``, if given, is the density a daughter dz above its parent of density rho
    starts with (the hydrostatic profile the lattice was built on), else the parent's. ``limit(n)``,
    if given, is asked before each level is added whether n particles may be (it raises if not)."""
    solids, moving = solids or {}, moving or {}
    for zone in sorted(zones, key=lambda z: -z.ratio):  # coarse to fine: a fine zone's parents are daughters
        target = zone.ratio * dx
        lo, hi = zone_bounds(zone, tank, dim)
        pos = columns["pos"]
        parent_level = (np.abs(spacing - 2.0 * target) < 1e-9 * dx) & (columns["ptype"] != PASSIVE)
        reach = band_width(target, hdx)
        near = distance_outside(pos, lo, hi, dim) <= reach + spacing  # a daughter lies within spacing / 2
        inside = parent_level & np.all((pos[:, :dim] >= lo) & (pos[:, :dim] <= hi), axis=1)
        inside |= parent_level & np.isin(columns["body"], _reaching(moving, lo, hi, dim))
        band = parent_level & near & ~inside
        if not inside.any():
            continue
        new, new_spacing = daughters(columns, spacing, np.flatnonzero(inside), target, dim, stratify)
        ring, ring_spacing = daughters(columns, spacing, np.flatnonzero(band), target, dim, stratify)
        keep = distance_outside(ring["pos"], lo, hi, dim) <= reach
        if layers is not None:
            thickness = layers * target
            made = _shallow(new, thickness, tank, solids, dim)
            new, new_spacing = {name: values[made] for name, values in new.items()}, new_spacing[made]
            keep &= _shallow(ring, thickness, tank, solids, dim)
        ring = {name: values[keep] for name, values in ring.items()}
        ring["ptype"] = np.where(ring["ptype"] == FLUID, PASSIVE, ring["ptype"]).astype(np.int32)
        if limit is not None:
            limit(len(spacing) + len(new_spacing) + int(keep.sum()))
        ptype = columns["ptype"].copy()
        ptype[inside & (ptype == FLUID)] = PASSIVE
        columns = {name: np.concatenate([ptype if name == "ptype" else values, new[name], ring[name]])
                   for name, values in columns.items()}
        spacing = np.concatenate([spacing, new_spacing, ring_spacing[keep]])
    return columns, spacing


# vacant slots a level holds over the fine lattice of its zone and band: water at the density bound
# (1.25 rho0) packs 1.25 particles a cell
RESERVE_SLACK = 1.3


def reserve(columns: dict, spacing: np.ndarray, zones, tank, dim: int, dx: float, hdx: float, limit=None):
    """``columns`` and ``spacing`` with the vacant slots (state.VACANT) each zone's level may need
    for the fluid that reaches it (sph/levels.py makes its particles there as it arrives): the fine
    lattice over the zone and its band, within the tank, x RESERVE_SLACK, less that level's fluid
    there now. ``limit(n)`` as for ``split``."""
    rows = []
    for zone in zones:
        target = zone.ratio * dx
        lo, hi = zone_bounds(zone, tank, dim)
        reach = band_width(target, hdx)
        lo_c = np.maximum(lo - reach, 0.0)
        hi_c = np.minimum(hi + reach, np.asarray(tank[:dim], dtype=float))
        cells = float(np.prod((hi_c - lo_c) / target))
        level = (np.abs(spacing - target) < 1e-9 * dx) & np.isin(columns["ptype"], (FLUID, PASSIVE)) \
            & (distance_outside(columns["pos"], lo, hi, dim) <= reach)
        count = max(0, int(np.ceil(RESERVE_SLACK * cells)) - int(level.sum()))
        centre = np.zeros(3)
        centre[:dim] = 0.5 * (lo_c + hi_c)
        rows.append((count, centre, target))
    total = sum(count for count, _, _ in rows)
    if limit is not None:
        limit(len(spacing) + total)
    rho = float(np.mean(columns["rho"]))
    new = {name: [values] for name, values in columns.items()}
    new_spacing = [spacing]
    for count, centre, target in rows:
        for name, values in columns.items():
            if name == "pos":
                block = np.tile(centre, (count, 1))
            elif name == "rho":
                block = np.full(count, rho)
            elif name == "ptype":
                block = np.full(count, VACANT, dtype=values.dtype)
            elif name == "body":
                block = np.full(count, -1, dtype=values.dtype)
            else:
                block = np.zeros((count,) + values.shape[1:], dtype=values.dtype)
            new[name].append(block)
        new_spacing.append(np.full(count, target))
    return {name: np.concatenate(blocks) for name, blocks in new.items()}, np.concatenate(new_spacing)

