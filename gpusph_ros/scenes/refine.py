"""Refinement zones to particles: every particle of the scene's lattice whose centre lies in a zone
(``refine:``, schema.Zone) is split into k^dim daughters on the sub-lattice of its own cell, k its
spacing over the zone's, each with 1/k^dim of its mass, its density, velocity, kind and body
(Vacondio et al. 2013, CMAME 256, the square pattern with its daughters at the cell's sub-centres).
Mass and momentum are therefore those of the uniform lattice exactly, and the fine particles
tile the cells they replace, so the interface is a staircase of the coarse cells with no gap and
no overlap. Fluid, walls and obstacles are split alike: a wall in a zone is at the zone's spacing.

Zones are applied coarse to fine; a zone that reaches a tank face (lo or hi on the tank's
boundary) reaches on through that wall, so its wall particles are split too.
"""
import numpy as np

from ..sph.config import ConfigError


def zone_bounds(zone, tank, dim):
    """The zone's box, open beyond every tank face it reaches (its walls' particles are in it)."""
    lo = np.array([-np.inf if zone.lo[ax] <= 0.0 else zone.lo[ax] for ax in range(dim)])
    hi = np.array([np.inf if zone.hi[ax] >= tank[ax] else zone.hi[ax] for ax in range(dim)])
    return lo, hi


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


def sub_offsets(k: int, dim: int) -> np.ndarray:
    """The k^dim daughters' offsets from their parent's centre in units of its spacing."""
    c = (np.arange(k) + 0.5) / k - 0.5
    grids = np.meshgrid(*([c] * dim), indexing="ij")
    out = np.zeros((grids[0].size, 3))
    for ax in range(dim):
        out[:, ax] = grids[ax].ravel()
    return out


def split(columns: dict, spacing: np.ndarray, zones, tank, dim: int, dx: float, stratify=None, limit=None):
    """``columns`` (name -> per-particle array: pos, rho, mass, ptype, body, ...) and ``spacing``
    with every particle in a zone replaced by its daughters at the zone's spacing. ``stratify(rho,
    dz)``, if given, is the density a daughter dz above its parent of density rho starts with (the
    hydrostatic profile the lattice was built on), else the parent's. ``limit(n)``, if given, is
    asked before each level is made whether n particles may be (it raises if not)."""
    for zone in sorted(zones, key=lambda z: -z.ratio):  # coarse to fine: a fine zone splits its parent's daughters
        target = zone.ratio * dx
        lo, hi = zone_bounds(zone, tank, dim)
        pos = columns["pos"]
        inside = np.all((pos[:, :dim] >= lo) & (pos[:, :dim] <= hi), axis=1) & (spacing > target * (1.0 + 1e-9))
        if not inside.any():
            continue
        ks = np.rint(spacing[inside] / target).astype(int)
        if limit is not None:
            limit(len(spacing) + int((ks ** dim - 1).sum()))
        new = {name: [] for name in columns}
        new_spacing = []
        for k in np.unique(ks):
            parents = np.flatnonzero(inside)[ks == k]
            offsets = sub_offsets(int(k), dim)
            daughters = len(offsets)
            shift = np.tile(offsets, (len(parents), 1)) * np.repeat(spacing[parents], daughters)[:, None]
            for name, values in columns.items():
                rows = np.repeat(values[parents], daughters, axis=0)
                if name == "pos":
                    rows = rows + shift
                elif name == "mass":
                    rows = rows / daughters
                new[name].append(rows)
            if stratify is not None:
                new["rho"][-1] = stratify(new["rho"][-1], shift[:, dim - 1])
            new_spacing.append(np.full(len(parents) * daughters, target))
        columns = {name: np.concatenate([values[~inside]] + new[name]) for name, values in columns.items()}
        spacing = np.concatenate([spacing[~inside]] + new_spacing)
    return columns, spacing
