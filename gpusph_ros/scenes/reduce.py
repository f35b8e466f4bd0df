"""Scene reductions: the same physics with fewer particles.

- ``2d``: a 3D scene whose flow is uniform across y (every fluid box and obstacle spans the tank's
  width; DamBreak 2) becomes its x-z section. Probes keep x (and z); masses are per metre of width.
  Refinement zones that span the width become the section's zones; the other reductions do not
  carry zones yet.
- ``slab``: the same scene cut to a thin periodic slab across y, ``slab_width`` wide (0: the
  narrowest the cell search allows, ``min_slab_cells`` spacings, a little over three kernel
  supports), probes moved to its middle. 3D turbulence and the 3D kernel survive; the side walls,
  which a uniform flow does not feel, go.
- ``2d_until_reflection``: a 3D scene whose fluid spans the tank's width but whose obstacles do not
  (DamBreak 1) becomes the x-z section without those obstacles. Upstream of an obstacle it is the
  same flow until the obstacle's reflection comes back (``valid_until``): the front reaches the
  obstacle at the bore speed of shallow-water theory (Stoker's on a wet bed, theory/stoker.py;
  Ritter's 2 sqrt(g H) on a dry one), and nothing travels back upstream faster than sqrt(g H).
  Probes downstream of such an obstacle's upstream face are dropped.
- ``crop``: along each horizontal axis, the tank is cut to what a disturbance can reach before the
  end time, a front moving at most 2 sqrt(g H) (the dam-break front speed of shallow-water
  theory, Ritter 1892) from the fluid's vertical faces, probes kept inside; an obstacle disturbs
  only what has reached it already. A cut keeps the kind of wall the face it replaces had (a plane
  meeting a particle wall leaves the corner half-supported: measured, DamBreak 1 at 4 cm leaked
  through it at t = 0.1 s); nothing reaches it before the end.
- ``wall_planes``: every wall of boundary particles becomes a particle-less plane (the thesis ran
  DamBreak 2's side walls so; ``sph.boundaries``, planes).

``apply`` returns the reduced scene; ``applicable`` names the reductions that change a scene.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from ..sph.config import ConfigError
from ..sph.neighbours import shortest_period
from ..theory.stoker import stoker
from .boxes import PLANES
from .schema import Scene

MODELS = ("full", "slab", "2d", "2d_until_reflection")
NO_PROBE_UPSTREAM = "no probe lies upstream of an obstacle narrower than the tank"


@dataclass
class Reduction:
    """How a run models its scene (run settings ``model``, ``slab_width``, ``crop``, ``wall_planes``)."""

    model: str = "full"
    slab_width: float = 0.0  # [m]; 0 = min_slab_cells spacings
    crop: bool = False
    wall_planes: bool = False

    def validate(self) -> "Reduction":
        if self.model not in MODELS:
            raise ConfigError("model", self.model, "one of " + ", ".join(MODELS))
        if not (math.isfinite(self.slab_width) and self.slab_width >= 0.0):
            raise ConfigError("slab_width", self.slab_width, "a width >= 0 [m] (0 = the narrowest periodic slab)")
        return self

    @property
    def label(self) -> str:
        parts = [self.model] + (["crop"] if self.crop else []) + (["wall_planes"] if self.wall_planes else [])
        return "+".join(parts)


def min_slab_cells(hdx: float) -> int:
    """Spacings across the narrowest periodic slab (neighbours.shortest_period, h in dx)."""
    return int(math.ceil(shortest_period(hdx) - 1e-9))


def uniform_across_y(scene: Scene, obstacles: bool = True) -> str:
    """Why the flow of ``scene`` (of its fluid only, without ``obstacles``) is not uniform across y,
    or "" when it is."""
    if scene.dim != 3:
        return "the scene is 2D already"
    if scene.gravity[1] != 0.0:
        return f"gravity has a part across y ({scene.gravity[1]:g} m/s^2)"
    width = scene.tank[1]
    for kind, boxes in (("fluid", scene.fluid), ("obstacles", scene.obstacles if obstacles else [])):
        for k, box in enumerate(boxes):
            if box.lo[1] > 0.0 or box.hi[1] < width:
                return f"{kind}[{k}] ({box.name}) does not span the tank's width y = [0, {width:g}]"
    return ""


def _section(scene: Scene) -> Scene:
    """The x-z section of a scene uniform across y, as a 2D scene (its zones too)."""
    def box2(box):
        fields = {f.name: getattr(box, f.name) for f in dataclasses.fields(box)}
        fields["lo"] = (box.lo[0], box.lo[2], 0.0)
        fields["hi"] = (box.hi[0], box.hi[2], 0.0)
        return type(box)(**fields)

    probes = []
    for p in scene.probes:
        position = (p.position[0], p.position[2], 0.0) if p.type == "point" else (p.position[0], 0.0, 0.0)
        probes.append(dataclasses.replace(p, position=position))
    walls = {face: scene.walls.get(face, "particles") for face in ("x_min", "x_max", "floor")}
    return dataclasses.replace(scene, dim=2, tank=(scene.tank[0], scene.tank[2], 0.0),
                               gravity=(scene.gravity[0], scene.gravity[2], 0.0),
                               periodic=(scene.periodic[0], False, False),
                               walls=walls, fluid=[box2(b) for b in scene.fluid],
                               obstacles=[box2(o) for o in scene.obstacles], refine=[box2(z) for z in scene.refine],
                               probes=probes)


def _narrow_obstacles(scene: Scene) -> list:
    """The obstacles that do not span the tank's width."""
    return [o for o in scene.obstacles if o.lo[1] > 0.0 or o.hi[1] < scene.tank[1]]


def _front_speed(scene: Scene, g: float, depth: float) -> float:
    """The speed of a dam-break front of a column ``depth`` deep in ``scene``: Stoker's bore on its wet
    bed, Ritter's 2 sqrt(g H) dry."""
    if 0.0 < scene.wet_bed < depth:
        return stoker(depth, scene.wet_bed, g).bore_speed
    return 2.0 * math.sqrt(g * depth)


def valid_until(scene: Scene) -> dict:
    """{probe name: the time [s] until which the ``2d_until_reflection`` section holds there}, for
    the probes upstream of every narrow obstacle (see the module docstring); {} when none applies."""
    narrow = _narrow_obstacles(scene)
    if not narrow or uniform_across_y(scene, obstacles=False):
        return {}
    up = scene.dim - 1
    g, depth = abs(scene.gravity[up]), max(b.hi[up] for b in scene.fluid)
    # water that reaches the tank's far end stands at every obstacle already: no front to arrive
    front = max((b.hi[0] for b in scene.fluid if b.hi[0] < scene.tank[0]), default=scene.tank[0])
    speed, back = _front_speed(scene, g, depth), math.sqrt(g * depth)
    out = {}
    for p in scene.probes:
        ahead = [o.lo[0] for o in narrow if o.lo[0] > p.position[0]]
        if len(ahead) == len(narrow):
            face = min(ahead)
            out[p.name] = max(0.0, face - front) / speed + (face - p.position[0]) / back
    return out


def _until_reflection(scene: Scene) -> Scene:
    """The x-z section without the narrow obstacles, keeping the probes upstream of them."""
    keep = valid_until(scene)
    narrow = _narrow_obstacles(scene)
    full_width = [o for o in scene.obstacles if o not in narrow]
    probes = [p for p in scene.probes if p.name in keep]
    return _section(dataclasses.replace(scene, obstacles=full_width, probes=probes))


def _slab(scene: Scene, width: float) -> Scene:
    def narrow(box):
        return dataclasses.replace(box, lo=(box.lo[0], 0.0, box.lo[2]), hi=(box.hi[0], width, box.hi[2]))

    probes = [dataclasses.replace(p, position=(p.position[0], 0.5 * width, p.position[2])) for p in scene.probes]
    walls = {face: kind for face, kind in scene.walls.items() if face not in ("y_min", "y_max")}
    return dataclasses.replace(scene, tank=(scene.tank[0], width, scene.tank[2]),
                               periodic=(scene.periodic[0], True, False), walls=walls,
                               fluid=[narrow(b) for b in scene.fluid], obstacles=[narrow(o) for o in scene.obstacles],
                               probes=probes)


def reach(scene: Scene, end_time: float) -> float:
    """How far [m] a disturbance travels by ``end_time``: 2 sqrt(g H), H the deepest fluid."""
    up = scene.dim - 1
    depth = max(b.hi[up] for b in scene.fluid)
    return 2.0 * math.sqrt(abs(scene.gravity[up]) * depth) * end_time


def crop_window(scene: Scene, end_time: float, axis: int) -> tuple:
    """(lo, hi) of what must be modelled along horizontal ``axis``: within ``reach`` of a
    fluid box's face inside the tank (where the water starts to move), and every probe."""
    length = scene.tank[axis]
    sources = [c for b in scene.fluid for c in (b.lo[axis], b.hi[axis]) if 0.0 < c < length]
    if not sources or scene.periodic[axis]:
        return 0.0, length
    d = reach(scene, end_time)
    probes = [p.position[axis] for p in scene.probes]
    lo = max(0.0, min([min(sources) - d] + probes))
    hi = min(length, max([max(sources) + d] + probes))
    return lo, hi


def _crop(scene: Scene, end_time: float, dx: float) -> Scene:
    """The scene cut to its crop windows (on whole spacings, so the lattice keeps its place)."""
    lo, hi = [0.0, 0.0, 0.0], list(scene.tank)
    for axis in range(scene.dim - 1):
        a, b = crop_window(scene, end_time, axis)
        a = math.floor(a / dx) * dx
        b = min(scene.tank[axis], math.ceil(b / dx) * dx)
        if a > 0.0:
            lo[axis] = a
        if b < scene.tank[axis]:
            hi[axis] = b
    if lo == [0.0, 0.0, 0.0] and hi == list(scene.tank):
        return scene

    def inside(box):
        return all(box.hi[k] > lo[k] and box.lo[k] < hi[k] for k in range(scene.dim - 1))

    def clip(box):
        return dataclasses.replace(box, lo=tuple(max(box.lo[k], lo[k]) for k in range(3)),
                                   hi=tuple(min(box.hi[k], hi[k]) for k in range(3)))

    cut = dataclasses.replace(scene, tank=tuple(hi), fluid=[clip(b) for b in scene.fluid if inside(b)],
                              obstacles=[clip(o) for o in scene.obstacles if inside(o)])
    # the builder's tank starts at 0: the cut is built there and moved back by its origin
    local = translate(cut, tuple(-c for c in lo))
    return dataclasses.replace(local, tank=tuple(hi[k] - lo[k] for k in range(3)),
                               origin=tuple(scene.origin[k] + lo[k] for k in range(3)))


def translate(scene: Scene, offset) -> Scene:
    """``scene`` with its boxes and probes moved by ``offset`` (a horizontal 3-vector)."""
    def move(point):
        return tuple(point[k] + offset[k] for k in range(3))

    def move_box(box):
        return dataclasses.replace(box, lo=move(box.lo), hi=move(box.hi))

    def move_obstacle(o):  # a moving body's reference point goes with its box
        moved = move_box(o)
        return moved if o.motion is None else dataclasses.replace(
            moved, motion=dataclasses.replace(o.motion, centre=move(o.motion.centre)))

    return dataclasses.replace(scene, fluid=[move_box(b) for b in scene.fluid],
                               obstacles=[move_obstacle(o) for o in scene.obstacles],
                               probes=[dataclasses.replace(p, position=move(p.position)) for p in scene.probes])


def apply(scene: Scene, reduction: Reduction, end_time: float, dx: float, hdx: float) -> Scene:
    """``scene`` reduced as ``reduction`` says; ConfigError naming the setting when a reduction
    does not fit the scene."""
    reduction.validate()
    if any(o.motion is not None for o in scene.obstacles) and reduction.label != Reduction().label:
        raise ConfigError("model", reduction.label, "full, without crop or wall_planes: a scene with a moving obstacle "
                                                    "is not reduced yet")
    if scene.refine and reduction.label not in (Reduction().label, Reduction(model="2d").label):
        raise ConfigError("model", reduction.label, "full or 2d, without crop or wall_planes: the scene's refinement "
                                                    "zones (refine:) are not carried through the others yet")
    if scene.refine and reduction.model == "2d":
        for k, zone in enumerate(scene.refine):
            if zone.lo[1] > 0.0 or zone.hi[1] < scene.tank[1]:
                raise ConfigError(f"refine[{k}]", zone.name, f"a zone spanning the tank's width y = [0, "
                                                             f"{scene.tank[1]:g}] for model 2d (the section stands "
                                                             "for every y)")
    if reduction.model == "2d_until_reflection":
        why = uniform_across_y(scene, obstacles=False) or ("" if valid_until(scene) else NO_PROBE_UPSTREAM)
        if why:
            raise ConfigError("model", reduction.model, f"full or 2d: {why}")
        scene = _until_reflection(scene)
    elif reduction.model != "full":
        why = uniform_across_y(scene)
        if why:
            raise ConfigError("model", reduction.model, f"full: {why}")
        if reduction.model == "2d":
            scene = _section(scene)
        else:
            width = reduction.slab_width or min_slab_cells(hdx) * dx
            if width < min_slab_cells(hdx) * dx * (1 - 1e-9):
                raise ConfigError("slab_width", reduction.slab_width,
                                  f"0 or a width >= {min_slab_cells(hdx) * dx:.4g} m ({min_slab_cells(hdx)} spacings)")
            scene = _slab(scene, width)
    if reduction.crop:
        scene = _crop(scene, end_time, dx)
    if reduction.wall_planes:
        scene = dataclasses.replace(scene, walls={face: PLANES for face in scene.walls})
    return scene


def applicable(scene: Scene, end_time: float, dx: float) -> dict:
    """{reduction label: Reduction} for each reduction that changes ``scene``, with why the
    others do not apply under key "not applicable" ({label: reason})."""
    out, skipped = {}, {}
    why = uniform_across_y(scene)
    for model in ("slab", "2d"):
        if why:
            skipped[model] = why
        else:
            out[model] = Reduction(model=model)
    until = valid_until(scene)
    if until:
        out["2d_until_reflection"] = Reduction(model="2d_until_reflection")
    else:
        skipped["2d_until_reflection"] = uniform_across_y(scene, obstacles=False) or NO_PROBE_UPSTREAM
    cropped = _crop(scene, end_time, dx)
    if cropped is scene:
        skipped["crop"] = (f"nothing lies out of reach: a front covers {reach(scene, end_time):.3g} m "
                           f"by t = {end_time:g} s")
    else:
        out["crop"] = Reduction(crop=True)
    if any(kind == "particles" for kind in scene.walls.values()):
        out["wall_planes"] = Reduction(wall_planes=True)
    else:
        skipped["wall_planes"] = "every wall is a plane already"
    extras = [k for k in ("crop", "wall_planes") if k in out]
    if "2d" in out and extras:  # the cheapest: every reduction that applies at once
        out["2d+" + "+".join(extras)] = Reduction(model="2d", crop="crop" in out, wall_planes="wall_planes" in out)
    return {"apply": out, "not applicable": skipped}
