"""DamBreak 1 of the thesis (Section 3.2), as GPUSPH's DamBreak3D ran it.

After Yeh & Petroff's experiment (University of Washington; used by Gomez-Gesteira & Dalrymple
2004 and GPUSPH's DamBreak3D): a 1.6 x 0.67 x 0.4 m tank, water filling x = 0-0.4 m across the
width to 0.4 m, a 0.01 m wet bed elsewhere, and a 0.12 x 0.12 m square obstruction at x =
0.90-1.02 m, y = 0.24-0.36 m standing through the full height. The obstruction is body 0.
"""
import numpy as np

from ..sph.config import SolverConfig
from ..sph.solver import BOUNDARY, Particles
from .boxes import box_tank, boundary_layers, lattice

TANK = (1.6, 0.67, 0.4)
COLUMN = ((0.0, 0.0, 0.0), (0.4, 0.67, 0.4))
WET_BED = 0.01
OBSTRUCTION = ((0.90, 0.24, 0.0), (1.02, 0.36, 0.4))


def _inside(pts, box, margin=0.0):
    lo, hi = np.asarray(box[0]) - margin, np.asarray(box[1]) + margin
    return np.all((pts >= lo) & (pts <= hi), axis=1)


def dambreak1(dx: float, **overrides):
    """(config, particles) for DamBreak 1 at particle spacing ``dx``; overrides go to the config."""
    cfg = SolverConfig(dim=3, dx=dx, depth=COLUMN[1][2], gravity=(0.0, 0.0, -9.81), **overrides)
    boxes = [COLUMN, ((COLUMN[1][0], 0.0, 0.0), (TANK[0], TANK[1], WET_BED))]  # box_tank fills each exactly
    cfg, parts = box_tank(cfg, TANK, boxes, headroom=1.0)
    keep = ~((parts.ptype == 0) & _inside(parts.pos, OBSTRUCTION))
    # the obstruction: boundary particles on the lattice, a wall's thickness in from each face
    layers = boundary_layers(cfg.boundary, cfg.hdx)
    (x0, y0, _), (x1, y1, z1) = OBSTRUCTION
    block = lattice((x0, y0, 0.0), (x1, y1, z1), dx, 3)
    inner = ((x0 + layers * dx, y0 + layers * dx, -1.0), (x1 - layers * dx, y1 - layers * dx, z1 + 1.0))
    block = block[~_inside(block, inner)]
    n_b = len(block)
    rho_block = np.full(n_b, cfg.rho0)
    parts = Particles(
        pos=np.concatenate([parts.pos[keep], block]),
        vel=np.zeros((keep.sum() + n_b, 3)),
        rho=np.concatenate([parts.rho[keep], rho_block]),
        mass=np.concatenate([parts.mass[keep], np.full(n_b, cfg.rho0 * dx ** 3)]),
        ptype=np.concatenate([parts.ptype[keep], np.full(n_b, BOUNDARY)]),
        body=np.concatenate([parts.body[keep], np.zeros(n_b, dtype=np.int32)]),
    )
    return cfg, parts
