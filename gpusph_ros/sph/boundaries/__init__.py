"""Wall treatments, one module each, named for its model:

- ``lennard_jones``: repulsive boundary particles, Monaghan 1994; thesis Eq. 2.24-2.25;
- ``monaghan_kajtar``: repulsive boundary particles, Monaghan & Kajtar 2009; thesis Eq. 2.26-2.27;
- ``dynamic``: boundary particles with a density by continuity, Crespo et al. 2007;
- ``mdbc``: the same particles with the density of the fluid at their mirror image, English et
  al. 2021;
- ``adami``: the same particles with the pressure of the fluid around them, extrapolated with the
  force balance across the wall, Adami, Hu & Adams 2012;
- ``planes``: particle-less walls, the fluid's mirror image integrated over the half-space.

Each module owns its name, what a scene needs from it (layers, spacing), its constants, its solver
hooks and its device functions (``model.BoundaryModel``). This package owns the registry, the ids
the passes read from ``Params.boundary`` (each model's place in ``PARTICLE_MODELS``), and the
device functions that dispatch on that id: the passes call those and never test a model's id.
"""

import functools
from types import SimpleNamespace

import numpy as np
import warp as wp

from .. import state
from ..device import default_device
from . import adami, dynamic, lennard_jones, mdbc, monaghan_kajtar, planes
from .model import BoundaryModel

# models of walls made of particles (the run setting ``boundary``); their ids are their places here
PARTICLE_MODELS = (lennard_jones.MODEL, monaghan_kajtar.MODEL, dynamic.MODEL, mdbc.MODEL, adami.MODEL)
NAMES = tuple(m.name for m in PARTICLE_MODELS)
BOUNDARY_ID = {name: k for k, name in enumerate(NAMES)}
# every wall treatment a study compares: the repulsive ones, the planes, the ones with a volume
STUDIED = tuple(m.name for m in (lennard_jones.MODEL, monaghan_kajtar.MODEL, planes.MODEL, dynamic.MODEL, mdbc.MODEL,
                                 adami.MODEL))
_ALL = {m.name: m for m in (*PARTICLE_MODELS, planes.MODEL)}
LENNARD_JONES = BOUNDARY_ID[lennard_jones.MODEL.name]
FLUID, BOUNDARY = state.FLUID, state.BOUNDARY


def model(name: str) -> BoundaryModel:
    """The wall treatment called ``name`` (one of STUDIED)."""
    try:
        return _ALL[name]
    except KeyError:
        raise ValueError(f"boundary: {name!r} is not one of {', '.join(STUDIED)}") from None


def wall_constants(g: float, depth: float, dx: float, mk_beta: float, dim: int) -> dict:
    """Every wall model's constants for gravity ``g``, fluid depth H and spacing dx, named as in
    Params: a run may mix walls of particles with planes, so all are set."""
    return {**lennard_jones.constants(g, depth, dx), **monaghan_kajtar.constants(g, depth, dx, mk_beta, dim),
            **planes.constants(dx)}


def model_params(name: str, g: float, depth: float, dx: float, mk_beta: float, dim: int) -> dict:
    """The Params fields of particle walls of the model ``name``: its id, what the passes ask of it,
    and the constants."""
    m = model(name)
    return {"boundary": BOUNDARY_ID[name], "wall_volume": int(m.volume), "wall_continuity": int(m.continuity),
            "wall_backstop_r0": m.backstop * dx, **wall_constants(g, depth, dx, mk_beta, dim)}


def params(cfg) -> dict:
    """The Params fields of the walls of ``cfg`` (a SolverConfig): the particle walls' model, mDBC's
    slip mode and the number of planes."""
    return {**model_params(cfg.boundary, cfg.g_norm, cfg.depth, cfg.dx, cfg.mk_beta, cfg.dim),
            "mdbc_slip": mdbc.SLIP_ID[cfg.mdbc_slip], "n_planes": len(cfg.planes)}


@functools.lru_cache(maxsize=None)
def build(scalar):
    """The device functions of the wall treatments for one floating-point type."""
    vec = wp.types.vector(3, scalar)
    Params = state.build(scalar).Params
    LJ, MK = lennard_jones.build(scalar), monaghan_kajtar.build(scalar)
    lj_force, mk_force, lj_potential, mk_potential = LJ.force, MK.force, LJ.potential, MK.potential
    wall_density_rate = dynamic.build(scalar).density_rate
    P = planes.build(scalar)

    @wp.func
    def repulsion(p: Params, m_a: scalar, m_b: scalar, r_ab: vec, r: scalar) -> vec:
        """What a wall particle of a repulsive model, of mass m_b at -r_ab, does to a fluid particle
        of mass m_a: an acceleration."""
        if p.boundary == LENNARD_JONES:
            return lj_force(p.lj_d, p.lj_r0, r_ab, r)
        return mk_force(p.mk_k, p.mk_beta, p.mk_d, p.inv_h, m_a, m_b, r_ab, r)

    @wp.func
    def backstop(p: Params, r_ab: vec, r: scalar, u_ab: vec, scale: scalar) -> vec:
        """What a wall particle at -r_ab, moving at -u_ab relative to a fluid particle of the level
        of ``scale``, does to it besides the pressure and viscous terms, on walls that have a
        backstop (model.BoundaryModel.backstop), else nothing: the Lennard-Jones force (thesis Eq.
        2.24) within the backstop's reach while the two approach, none while they part. It takes
        energy out and never puts any in (boundaries/adami.py says why)."""
        if p.wall_backstop_r0 == scalar(0.0) or wp.dot(u_ab, r_ab) >= scalar(0.0):
            return vec(scalar(0.0))
        return lj_force(p.lj_d, p.wall_backstop_r0 * scale, r_ab, r)

    @wp.func
    def repulsion_potential(p: Params, m_a: scalar, m_b: scalar, r: scalar) -> scalar:
        """The energy per unit fluid mass that ``repulsion`` stores at distance r."""
        if p.boundary == LENNARD_JONES:
            return lj_potential(p.lj_d, p.lj_r0, r)
        return mk_potential(p.mk_k, p.mk_beta, p.mk_d, p.inv_h, m_a, m_b, r)

    @wp.kernel(enable_backward=False, module="unique")
    def evaluate_repulsion(p: Params, mass: scalar, points: wp.array(dtype=vec), wall: wp.array(dtype=vec),
                           acc: wp.array(dtype=vec), energy: wp.array(dtype=scalar)):
        i = wp.tid()
        a = vec(scalar(0.0))
        e = scalar(0.0)
        for j in range(wall.shape[0]):
            r_ab = points[i] - wall[j]
            r = wp.length(r_ab)
            a += repulsion(p, mass, mass, r_ab, r)
            e += repulsion_potential(p, mass, mass, r)
        acc[i] = a
        energy[i] = e

    return SimpleNamespace(repulsion=repulsion, backstop=backstop, repulsion_potential=repulsion_potential,
                           wall_density_rate=wall_density_rate, plane_wall=P.plane_wall,
                           plane_corners=P.plane_corners, evaluate_repulsion=evaluate_repulsion)


def repulsion(boundary: str, points, wall, g: float, depth: float, dx: float, hdx: float = 1.3,
              mk_beta: float = 2.0, dim: int = 2, device: str = None):
    """What the boundary particles at ``wall`` do to a fluid particle (of their mass) at each of
    ``points`` under the repulsive model ``boundary`` (lennard_jones, monaghan_kajtar), with the
    scene's constants (``wall_constants``): (accelerations, the energy per unit mass they store),
    host arrays computed by the device functions in float64."""
    if not model(boundary).repulsive:
        raise ValueError(f"boundary: {boundary!r} is not a repulsive model")
    device = device or default_device()
    p = state.build(wp.float64).Params()
    for name, value in model_params(boundary, g, depth, dx, mk_beta, dim).items():
        setattr(p, name, value)
    p.inv_h = 1.0 / (hdx * dx)
    pts = wp.array(np.asarray(points, dtype=np.float64), dtype=wp.vec3d, device=device)
    walls = wp.array(np.asarray(wall, dtype=np.float64), dtype=wp.vec3d, device=device)
    acc = wp.zeros(len(pts), dtype=wp.vec3d, device=device)
    energy = wp.zeros(len(pts), dtype=wp.float64, device=device)
    wp.launch(build(wp.float64).evaluate_repulsion, dim=len(pts), inputs=[p, 1.0, pts, walls, acc, energy],
              device=device)
    return acc.numpy(), energy.numpy()
