"""A scene plus numerics to a solver's starting point: configuration, particles and named bodies.

Fluid boxes are filled exactly (``boxes.fill_box``: top layer half a spacing below the stated
surface, mass = rho0 x box volume). The wet bed covers the floor outside the fluid boxes' and
obstacles' footprints, cut into rectangles that are each filled exactly. Obstacles are boxes of
boundary particles on a lattice that fills each exactly (``shapes.block_particles``), a wall's thickness
deep from its sides and its top, each its own body. Refinement zones (``refine:``) then split the
particles in them (``refine.py``).
"""
from dataclasses import dataclass

import numpy as np

from ..sph import bodies, boundaries
from ..sph.config import ConfigError, Plane, SolverConfig, check_device
from ..sph.device import chosen_device
from ..sph.eos import hydrostatic_density, hydrostatic_depth
from ..sph.particles import Particles
from ..sph.solver import Solver
from ..sph.state import BOUNDARY, FLUID
from . import reduce, refine, resources, shapes
from .boxes import box_tank
from .schema import Scene

# a points body's median spacing over the run's dx: its particles each stand for dx^dim
POINTS_SPACING = (0.8, 1.25)


@dataclass
class Model:
    """What a run starts from: the resolved solver configuration, the particles, and the body id
    of each obstacle by name."""

    scene: Scene
    config: SolverConfig
    particles: Particles
    bodies: dict

    @property
    def fluid_particles(self) -> int:
        return int((self.particles.ptype == FLUID).sum())

    def solver(self) -> Solver:
        """A solver that starts from this model."""
        return Solver(self.config, self.particles, body_names=sorted(self.bodies, key=self.bodies.get))


def floor_rectangles(extent, footprints, dim: int) -> list:
    """The floor [0, extent] (horizontal axes) less the footprints (lo, hi), as disjoint boxes:
    the cells of the grid through every footprint edge that no footprint covers, merged along x."""
    axes = dim - 1
    cuts = []
    for ax in range(axes):
        edges = {0.0, extent[ax]}
        for lo, hi in footprints:
            edges.update(min(max(c, 0.0), extent[ax]) for c in (lo[ax], hi[ax]))
        cuts.append(sorted(edges))
    rows = [(None, None)] if axes == 1 else list(zip(cuts[1][:-1], cuts[1][1:]))
    out = []
    for y0, y1 in rows:
        run = None
        for x0, x1 in zip(cuts[0][:-1], cuts[0][1:]):
            centre = [0.5 * (x0 + x1)] + ([] if axes == 1 else [0.5 * (y0 + y1)])
            covered = any(all(lo[ax] < centre[ax] < hi[ax] for ax in range(axes)) for lo, hi in footprints)
            if covered or x1 - x0 <= 0.0:
                if run:
                    out.append(run)
                run = None
            elif run is None:
                run = [x0, x1, y0, y1]
            else:
                run[1] = x1
        if run:
            out.append(run)
    return [((x0,) if axes == 1 else (x0, y0), (x1,) if axes == 1 else (x1, y1)) for x0, x1, y0, y1 in out]


def restratify(rho, dz, cfg: SolverConfig):
    """The density dz above a particle of density rho on the hydrostatic profile it was built on
    (boxes.box_tank: Tait's law at rho0 g d); a dry particle (rho0) stays at rho0."""
    depth = hydrostatic_depth(rho, cfg.rho0, cfg.eos_b, cfg.gamma, cfg.g_norm)
    return np.where(depth > 0.0, hydrostatic_density(depth - dz, cfg.rho0, cfg.eos_b, cfg.gamma, cfg.g_norm), rho)


def _check_refinable(scene: Scene, cfg: SolverConfig):
    """Refinement zones need walls whose particles carry the fluid's volume: the repulsive walls'
    and the planes' forces are set by constants of one spacing (their reach, r0 = dx)."""
    if boundaries.model(cfg.boundary).repulsive:
        raise ConfigError("boundary", cfg.boundary, "dynamic or mdbc with refinement zones (refine:): a repulsive "
                                                    "wall's force constants are set for one spacing")
    planes = {face: kind for face, kind in scene.walls.items() if kind != "particles"}
    if planes:
        raise ConfigError("walls", planes, "particles with refinement zones (refine:): a plane's repulsion distance "
                                           "is one spacing")


def build_run(scene: Scene, run_config) -> Model:
    """The model of ``scene`` under ``run_config`` (``settings.resolve``), reduced as it asks."""
    cfg = run_config.solver
    reduced = reduce.apply(scene, run_config.reduction, run_config.output.end_time, cfg.dx, cfg.hdx)
    return build_from(reduced, cfg)


def priced(scene: Scene, run_config) -> tuple:
    """(the reduced scene, its configuration, the particles its build makes at most without its
    zones) under ``run_config``: what a run costs, from the scene alone, nothing built."""
    cfg = run_config.solver
    reduced = reduce.apply(scene, run_config.reduction, run_config.output.end_time, cfg.dx, cfg.hdx)
    cfg = scene_config(reduced, cfg)
    return reduced, cfg, resources.particle_bound(reduced, cfg, fluid_boxes(reduced))


def build(scene: Scene, **numerics) -> Model:
    """The model of ``scene`` with the given numerics (``SolverConfig`` fields: dx, kernel, ...)."""
    return build_from(scene, SolverConfig(**numerics))


def scene_config(scene: Scene, cfg: SolverConfig) -> SolverConfig:
    """``cfg`` with what the scene decides (its dimension, gravity, depth and periodic axes) and the
    device this machine steps it on (``device: auto`` chosen here: sph.device.chosen_device)."""
    return cfg.replace(dim=scene.dim, gravity=scene.gravity, depth=scene.depth, periodic=scene.periodic,
                       device=chosen_device(cfg.device)).validate()


def fluid_boxes(scene: Scene) -> list:
    """(lo, hi) of every box of fluid the scene fills: its fluid boxes and its wet bed's pieces."""
    dim, up = scene.dim, scene.dim - 1
    boxes = [(b.lo[:dim], b.hi[:dim]) for b in scene.fluid]
    if scene.wet_bed > 0.0:
        footprints = [(b.lo, b.hi) for b in scene.fluid if b.lo[up] <= 0.0]
        footprints += [(o.lo, o.hi) for o in scene.obstacles]
        for lo, hi in floor_rectangles(scene.tank, footprints, dim):
            boxes.append((tuple(lo) + (0.0,), tuple(hi) + (scene.wet_bed,)))
    return boxes


def moving_bodies(scene: Scene, cfg: SolverConfig) -> list:
    """Each obstacle's prescribed motion by body id ([] when none moves), its particles' speed held
    under a tenth of the sound speed (weak compressibility's bound on the flow it drives)."""
    if all(o.motion is None for o in scene.obstacles):
        return []
    for k, o in enumerate(scene.obstacles):
        if isinstance(o.motion, bodies.Motion):
            speed = o.motion.peak_speed(bodies.farthest_corner(o.lo, o.hi, o.motion.centre))
            if speed > cfg.sound_speed / 10.0:
                raise ConfigError(f"obstacles[{k}].motion", o.name, f"a motion whose particles move at most c0 / 10 = "
                                                                    f"{cfg.sound_speed / 10.0:.3g} m/s; it reaches "
                                                                    f"{speed:.3g} m/s")
    return [o.motion for o in scene.obstacles]


def sweeps(scene: Scene) -> dict:
    """{obstacle id: (lo, hi), the box its motion sweeps (bodies.Motion.sweep)} of the moving
    obstacles; where no bound is known (a floating or driven body, a translation), its box at the
    start, and the run checks it stays on its side of every zone's faces (health: zone_edge)."""
    out = {}
    for k, o in enumerate(scene.obstacles):
        if o.motion is not None:
            sweep = o.motion.sweep(o.lo, o.hi) if isinstance(o.motion, bodies.Motion) else None
            out[k] = sweep or (np.asarray(o.lo, dtype=np.float64), np.asarray(o.hi, dtype=np.float64))
    return out


def build_from(scene: Scene, cfg: SolverConfig) -> Model:
    """The model of ``scene`` under the solver configuration ``cfg``, whose domain the scene sets."""
    dim = scene.dim
    cfg = scene_config(scene, cfg)
    dx = cfg.dx
    boxes = fluid_boxes(scene)
    check_device(cfg.device)
    resources.check(scene, cfg, boxes)  # before anything is allocated
    cfg, parts = box_tank(cfg, scene.tank[:dim], boxes, walls=scene.walls, headroom=scene.headroom)
    keep = np.ones(len(parts), dtype=bool)
    for k, o in enumerate(scene.obstacles):
        # a round body also takes the lattice points a quarter spacing outside it, closer to its rings
        inside = (parts.ptype == FLUID) & shapes.holds(o, parts.pos, dim, 0.25 * dx)
        if inside.any() and not o.displaces_fluid:
            raise ConfigError(f"obstacles[{k}]", o.name, f"a box clear of the fluid boxes: it covers {inside.sum()} "
                                                         "fluid particles; displaces_fluid: true removes them")
        keep &= ~inside
    if not (keep & (parts.ptype == FLUID)).any():
        raise ConfigError("fluid", [b.name for b in scene.fluid], "boxes that hold fluid outside the obstacles")
    pos, rho, mass = [parts.pos[keep]], [parts.rho[keep]], [parts.mass[keep]]
    ptype, body = [parts.ptype[keep]], [parts.body[keep]]
    layers = boundaries.model(cfg.boundary).layers(cfg.hdx)
    bodies, solids = {}, []
    for k, o in enumerate(scene.obstacles):
        # a moving body's box is not where its particles are, and a fixed wedge's or round body's box
        # holds fluid beside the solid: only a fixed box is a solid the fluid must stay out of (the
        # health check's) and a floating body meets
        if o.motion is None and o.shape == "box":
            solids.append((o.lo, o.hi))
        block, volume = shapes.particles(o, dx, dim, layers)
        if o.shape == "points":  # each stands for dx^dim: they must be a spacing apart
            apart = shapes.median_spacing(block, dim)
            if not POINTS_SPACING[0] * dx <= apart <= POINTS_SPACING[1] * dx:
                raise ConfigError(f"obstacles[{k}].points", o.name, f"points the run's spacing apart (dx = {dx:g} m, "
                                                                    f"within {POINTS_SPACING} of it); their median "
                                                                    f"spacing is {apart:.4g} m")
        pos.append(block)
        rho.append(np.full(len(block), cfg.rho0))  # mostly dry at the start; dynamic ones adjust
        mass.append(np.full(len(block), cfg.rho0 * volume))
        ptype.append(np.full(len(block), BOUNDARY))
        body.append(np.full(len(block), k, dtype=np.int32))
        bodies[o.name] = k
    motions = moving_bodies(scene, cfg)
    cfg = cfg.replace(solids=[(tuple(lo), tuple(hi)) for lo, hi in solids], motions=motions).validate()
    columns = {"pos": np.concatenate(pos), "rho": np.concatenate(rho), "mass": np.concatenate(mass),
               "ptype": np.concatenate(ptype), "body": np.concatenate(body)}
    spacing = None
    if scene.refine:
        _check_refinable(scene, cfg)
        refine.check_nesting(scene.refine, scene.tank, dim, dx, cfg.hdx)
        def limit(n):
            resources.check_count(n, cfg, "refine", [z.name for z in scene.refine], "the zones make",
                                  "coarser or smaller zones", refined=True)

        boxes = {k: (o.lo, o.hi) for k, o in enumerate(scene.obstacles) if o.shape == "box"}
        moving = sweeps(scene)
        refine.check_paths(scene.refine, moving, [o.name for o in scene.obstacles], scene.tank, dim, dx, cfg.hdx)
        columns, spacing = refine.split(columns, np.full(len(columns["pos"]), dx), scene.refine, scene.tank, dim, dx,
                                        cfg.hdx, stratify=lambda rho, dz: restratify(rho, dz, cfg), limit=limit,
                                        layers=layers, solids=boxes, moving=moving)
        columns, spacing = refine.reserve(columns, spacing, scene.refine, scene.tank, dim, dx, cfg.hdx, limit=limit)
        cfg = cfg.replace(zones=refine.zone_boxes(scene.refine, scene.tank, dim, dx))
    pos = columns["pos"] + np.asarray(scene.origin)
    if any(scene.origin):
        def move(point):
            return tuple(c + o if abs(c) < 1.0e30 else c for c, o in zip(point, scene.origin))

        scene = reduce.translate(scene, scene.origin)  # its moving bodies' reference points too
        cfg = cfg.replace(domain_lo=move(cfg.domain_lo), domain_hi=move(cfg.domain_hi), wall_lo=move(cfg.wall_lo),
                          wall_hi=move(cfg.wall_hi), wall_top=cfg.wall_top + scene.origin[scene.dim - 1],
                          solids=[(move(lo), move(hi)) for lo, hi in cfg.solids],
                          motions=[o.motion for o in scene.obstacles] if cfg.motions else [],
                          zones=[(move(lo), move(hi), spacing) for lo, hi, spacing in cfg.zones],
                          planes=[Plane(point=move(p.point), normal=p.normal) for p in cfg.planes])
    particles = Particles(pos=pos, vel=np.zeros((len(pos), 3)), rho=columns["rho"], mass=columns["mass"],
                          ptype=columns["ptype"], body=columns["body"], spacing=spacing)
    return Model(scene=scene, config=cfg, particles=particles, bodies=bodies)
