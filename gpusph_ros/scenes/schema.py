"""Scene files: the YAML schema of a scene, read and checked into plain data.

A scene is geometry and gauges only: the tank, the water, the obstacles and where to measure.
Numerics (dx, kernel, viscosity, boundary model, precision, CFL, output rate, end time, ...) come
from the run configuration (``settings.py``); a scene may suggest run settings under ``run:`` (its end
time, say) that a run configuration or a ``--set`` overrides.

Conventions: SI units; the tank is the open-top box [0, tank]; the vertical axis is the last one
(y in 2D, z in 3D) and gravity points down it. Points are written with ``dim`` components.
Every problem raises ``ConfigError`` naming the field (``fluid[1].hi``), its value and what is
allowed, so one message tells a user what to change.

A scene file may change another: ``base: dambreak1_lab`` and then only the keys it changes (a
``refine:`` list, say); its keys replace the base's whole.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from ..share import config_dir
from ..sph import bodies
from ..sph.config import ConfigError, unknown_key
from ..theory import wavemaker
from . import shapes, yaml_input
from .boxes import WALL_KINDS, wall_faces

PROBE_TYPES = ("point", "column", "profile", "gauge", "pressure_sensor")
# how a pressure_sensor reads its face (measure/sensors.py): ``wall``, the wall model's pressure at the
# face; ``smoothed``, as De Courcy et al. 2024 read theirs (the fluid at the face, a kernel twice as wide,
# negative pressures clipped)
SENSOR_READINGS = ("wall", "smoothed")
# how a pressure_sensor reports between outputs (measure/transducers.py): ``mean``, over the steps since
# the last output; ``step``, the output step's reading alone
SENSOR_SAMPLINGS = ("mean", "step")
MAX_RESPONSE = 10.0  # [s] a transducer's time constant: longer is no transducer of a wave or an impact
# how a gauge reads the level (measure/surface.py): ``fraction``, where the fluid's kernel sum along its
# line first falls below one half above water that stands on the floor (DualSPHysics' GaugeSwl);
# ``top``, the top of the highest fluid particle within a spacing of its line
GAUGE_READINGS = ("fraction", "top")
SCENE_KEYS = ("name", "description", "source", "dim", "tank", "headroom", "lid", "gravity", "depth", "periodic",
              "walls", "fluid", "wet_bed", "obstacles", "refine", "probes", "run", "analysis")
# a refinement zone's spacing over the scene's dx: each level halves its parent's (scenes/refine.py)
ZONE_RATIOS = (0.5, 0.25, 0.125)
MAX_ZONES = 16
# gravity's magnitude [m/s^2]: from a hundredth of the Earth's to a centrifuge model's hundred g
MIN_GRAVITY, MAX_GRAVITY = 0.0981, 981.0
# the comparisons a scene may ask its recordings to get (``analysis: {case: ..., gpusph: ...}``), by the
# measurements they compare with; analysis/report.py holds one analysis for each
ANALYSES = ("dambreak1", "dambreak2", "lobovsky")


@dataclass
class Box:
    """A named axis-aligned box [lo, hi] (3-vectors; z = 0 and unused in 2D)."""

    name: str
    lo: tuple
    hi: tuple


@dataclass
class Obstacle(Box):
    """A fixed box of boundary particles whose wrench is reported; ``block_offsets`` [m] are the
    distances from its upstream and downstream faces at which the thesis's pressure blocks sit.
    An obstacle that overlaps a fluid box is an error unless ``displaces_fluid`` says the fluid
    there is to be removed."""

    block_offsets: tuple = (0.0, 0.06)
    displaces_fluid: bool = False
    motion: object = None  # sph.bodies.Motion, or None: fixed
    shape: str = "box"  # shapes.SHAPES: a wedge rises at ``deadrise`` [rad], a cylinder turns about ``axis``
    deadrise: float = 0.0
    axis: int = 2  # 0, 1, 2: x, y, z (2D: z, the disc's)
    points: tuple = ()  # shape points: its boundary particles, 3-tuples in the scene's axes [m]

    def centre(self, dim: int) -> tuple:
        """The body's reference point, the centre of its box (z = 0 in 2D): its torque is about it."""
        c = [(a + b) / 2 for a, b in zip(self.lo, self.hi)]
        return (c[0], c[1], c[2] if dim == 3 else 0.0)


@dataclass
class Zone(Box):
    """A refinement zone: the particles in [lo, hi] are at ``ratio`` x the scene's dx (ZONE_RATIOS).
    ``around`` names the obstacle it was grown from by ``margin`` [m], if any. A zone that reaches a
    tank face takes in that wall's particles too."""

    ratio: float = 0.5
    around: str = ""
    margin: float = 0.0


@dataclass
class Probe:
    """A named gauge. ``point``: kernel-interpolated values at ``position``; ``column``: mean
    velocity of the fluid in a vertical column of radius ``radius_dx`` spacings around the
    horizontal ``position``; ``profile``: point values at ``heights`` above the floor there;
    ``gauge``: free-surface elevation there, read as ``reading`` says (GAUGE_READINGS);
    ``pressure_sensor``: a transducer of ``diameter`` [m] centred at ``position`` on a wall or body
    face whose inward (into the fluid) unit ``normal`` is given (measure.sensors), reporting as
    ``sampling``, ``clip`` and ``response`` say (measure.transducers). ``position`` and ``normal``
    are always stored as 3-vectors."""

    name: str
    type: str
    position: tuple
    radius_dx: float = 3.0
    heights: tuple = ()
    normal: tuple = ()
    diameter: float = 0.0
    reading: str = "wall"  # a pressure_sensor's: SENSOR_READINGS (measure/sensors.py); a gauge's: GAUGE_READINGS
    sampling: str = "mean"  # a pressure_sensor's: SENSOR_SAMPLINGS (measure/transducers.py)
    clip: bool = True  # a pressure_sensor's: gauge pressure, each step's reading clipped at 0
    response: float = 0.0  # [s] a pressure_sensor's first-order time constant; 0: an ideal transducer


@dataclass
class Scene:
    name: str
    dim: int
    tank: tuple
    gravity: tuple
    depth: float
    fluid: list
    description: str = ""
    source: str = ""
    headroom: float = 0.5
    periodic: tuple = (False, False, False)
    walls: dict = field(default_factory=dict)
    wet_bed: float = 0.0
    obstacles: list = field(default_factory=list)
    refine: list = field(default_factory=list)  # Zones, in the file's order
    probes: list = field(default_factory=list)
    run_settings: dict = field(default_factory=dict)  # the file's `run:` section (settings.py)
    # the file's `analysis:` section: which comparison its recordings get (ANALYSES), and whether the
    # thesis's GPUSPH tables are of this very geometry; empty: none
    analysis: dict = field(default_factory=dict)
    # what is legal but rarely meant, said once where the scene is run (gpusph-run, the node's log)
    warnings: list = field(default_factory=list)
    text: str = ""  # the file as written, recorded with each run
    # where the tank's corner lies in the world: (0, 0, 0) but for a cropped scene (reduce.py),
    # whose boxes and probes are given from its own corner
    origin: tuple = (0.0, 0.0, 0.0)


def shipped(sub: str) -> list:
    """Names of the YAML files shipped in config/<sub>."""
    return sorted(p.stem for p in config_dir(sub).glob("*.yaml"))


def builtin_names() -> list:
    """The scenes shipped in config/scenes."""
    return shipped("scenes")


def read_yaml(sub: str, name_or_path, field_name: str, what: str):
    """(path, text, data) of a YAML file given by path or by the name of one shipped in
    config/<sub>; ConfigError on ``field_name`` when it is missing or not YAML."""
    if len(str(name_or_path)) > MAX_PATH:
        raise ConfigError(field_name, name_or_path, f"a path of at most {MAX_PATH} characters")
    path = Path(name_or_path)
    if not path.suffix and (config_dir(sub) / f"{name_or_path}.yaml").is_file():
        path = config_dir(sub) / f"{name_or_path}.yaml"
    if not path.is_file():
        raise ConfigError(field_name, str(name_or_path),
                          f"a built-in {what} (" + ", ".join(shipped(sub)) + f") or a path to a YAML {what} file")
    text = yaml_input.read_text(path, field_name)
    return path, text, yaml_input.parse(text, field_name, str(path))


def load_scene(name_or_path) -> Scene:
    """A scene from a built-in name (``builtin_names()``) or a YAML file path."""
    path, text, data = _scene_file(name_or_path, "scene", ())
    scene = parse_scene(data, default_name=path.stem)
    scene.text = text
    return scene


def _scene_file(name_or_path, field_name: str, chain: tuple):
    """(path, text, data) of a scene file. A file with ``base:`` (a built-in scene's name, or a path
    beside the file) changes that scene: its own keys replace the base's, its name is its own, and
    its text is the merged scene, so that a recording holds all of it."""
    path, text, data = read_yaml("scenes", name_or_path, field_name, "scene")
    if not isinstance(data, dict):
        raise ConfigError(field_name, str(path),
                          f"a YAML mapping of scene fields (the file holds {type(data).__name__})")
    if "base" not in data:
        return _read_files(path, text, data)
    base = data["base"]
    if not isinstance(base, str) or base in chain or len(chain) >= MAX_BASES:
        raise ConfigError("base", base, f"the name or path of another scene file, in a chain of at most "
                                        f"{MAX_BASES} files without a loop")
    if Path(base).suffix and not Path(base).is_absolute():
        base = str(path.parent / base)
    _, _, base_data = _scene_file(base, "base", chain + (data["base"],))
    merged = {**base_data, **{key: value for key, value in data.items() if key != "base"}}
    merged["name"] = data.get("name", path.stem)
    text = f"# {path.name}: the scene {data['base']} with this file's keys\n" + yaml.safe_dump(merged, sort_keys=False)
    return _read_files(path, text, merged)


def _read_files(path: Path, text: str, data: dict):
    """(path, text, data) with each obstacle's points ``file`` and each series motion's ``file``
    (a CSV beside the scene file, or a path) read into its columns, and the text the scene with
    them, which a recording then holds whole."""
    read = []
    for k, item in enumerate(data.get("obstacles") or []):
        if not isinstance(item, dict):
            continue
        motion = item.get("motion")
        if isinstance(motion, dict) and motion.get("type") == "series" and "file" in motion:
            columns = read_columns(path, motion["file"], f"obstacles[{k}].motion.file", SERIES_CHANNELS, "time")
            item["motion"] = {**{key: v for key, v in motion.items() if key != "file"}, **columns}
            read.append(motion["file"])
        if item.get("shape") == "points" and "file" in item:
            item["points"] = read_columns(path, item.pop("file"), f"obstacles[{k}].file", POINT_COLUMNS, "x")
            read.append(f"obstacles[{k}]'s points")
    if not read:
        return path, text, data
    return path, f"# {path.name} with its files read in ({', '.join(map(str, read))})\n" + \
        yaml.safe_dump(data, sort_keys=False, default_flow_style=None), data


def read_columns(scene_path: Path, name, field_name: str, columns: tuple, first: str) -> dict:
    """A CSV file's columns (``name`` beside the scene file at ``scene_path``, or a path): text whose
    first line names them (``first`` and any of ``columns``, each once), then one row of numbers a
    line; lines starting with # are comments."""
    if not isinstance(name, str) or len(name) > MAX_PATH:
        raise ConfigError(field_name, name, f"a path of at most {MAX_PATH} characters")
    path = scene_path.parent / name
    if not path.is_file():  # a FIFO or a device would block the read
        raise ConfigError(field_name, str(path), "a CSV file beside the scene file, or its path")
    lines = [line for line in yaml_input.read_text(path, field_name, limit=MAX_CSV_BYTES).splitlines()
             if line.strip() and not line.lstrip().startswith("#")]
    allowed = (first,) + tuple(c for c in columns if c != first)
    if not lines:
        raise ConfigError(field_name, str(path), "a CSV file: a header naming " + ", ".join(allowed) + ", then rows")
    names = [n.strip() for n in lines[0].split(",")]
    if first not in names or any(n not in allowed for n in names) or len(set(names)) < len(names):
        # the file's own words are not quoted: a scene may name any file the node can read
        raise ConfigError(field_name, str(path), f"a header naming {first} and any of " + ", ".join(allowed[1:])
                                                 + ", each once")
    if len(lines) - 1 > MAX_CSV_ROWS:
        raise ConfigError(field_name, str(path), f"at most {MAX_CSV_ROWS:,} rows ({len(lines) - 1:,})")
    values = {n: [] for n in names}
    for row, line in enumerate(lines[1:], start=2):
        try:
            numbers = [float(c) for c in line.split(",")]
        except ValueError:
            numbers = []
        if len(numbers) != len(names):
            raise ConfigError(field_name, str(path), f"{len(names)} numbers a row; line {row} of its data is not")
        for n, v in zip(names, numbers):
            values[n].append(v)
    return values


# -- field readers: each names the field it reads ------------------------------------------
def _number(where, value, lo=-math.inf, hi=math.inf, lo_open=False):
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if ok:
        ok = (value > lo if lo_open else value >= lo) and value <= hi
    if not ok:
        bound = []
        if lo > -math.inf:
            bound.append(("> " if lo_open else ">= ") + f"{lo:g}")
        if hi < math.inf:
            bound.append(f"<= {hi:g}")
        raise ConfigError(where, value, "a finite number" + (" " + " and ".join(bound) if bound else ""))
    return float(value)


def _vector(where, value, length, lo=-math.inf):
    if not isinstance(value, (list, tuple)) or len(value) != length:
        raise ConfigError(where, value, f"a list of {length} numbers")
    return tuple(_number(f"{where}[{k}]", c, lo=lo) for k, c in enumerate(value))


def _pad3(vec):
    return tuple(vec) + (0.0,) * (3 - len(vec))


def _mapping(where, value, keys, required=(), whole="scene"):
    if not isinstance(value, dict):
        raise ConfigError(where, value, "a mapping with keys " + ", ".join(keys))
    for key in value:
        if key not in keys:
            raise unknown_key(where, key, keys, whole)
    for key in required:
        if key not in value:
            raise ConfigError(f"{where}.{key}" if where else key, None, "a value (this field is required)")
    return value


MAX_BASES = 4  # a scene file on a base on a base ...: more is a loop more likely than a design
MAX_PATH = 4096  # characters of a path (Linux's PATH_MAX): a longer one is refused before the file system sees it
MAX_HEADROOM = 10.0  # [tank heights] of air above the tank: more is a domain of nothing
MAX_RADIUS_DX = 100.0  # [dx] a column probe wider than this averages the tank, not a column
# what one output measures and publishes grows with these: measured on DamBreak 1 at 6 cm on this
# project's 2-core CPU, 1,000 gauges cost 0.056 s of sampling and 0.015 s of messages an output,
# 5,000 cost 0.27 s and 0.07 s (and a node with them answered no parameter call for 96 s); 256
# probes cost under 0.02 s an output
MAX_PROBES = 256
MAX_HEIGHTS = 64  # of one profile probe
MAX_OBSTACLES = 32  # bodies: each has a wrench, pressure blocks and a face load an output
MAX_NAME = 64  # characters of a scene, box or probe name: it becomes part of a topic name


def _name(where, value):
    # ROS topic names take ASCII letters, digits and _ only: 'wässer' passed isalnum and failed at reset
    if (not isinstance(value, str) or not value.isascii() or not value.replace("_", "").isalnum()
            or not value[0].isalpha() or len(value) > MAX_NAME):
        raise ConfigError(where, value, f"a name of at most {MAX_NAME} ASCII letters, digits and _ starting with a "
                                        "letter (used in topic names)")
    return value


def _text(where, value) -> str:
    if not isinstance(value, str):
        raise ConfigError(where, value, "a text (a YAML string)")
    return value.strip()


def _inside(where, point, tank, dim):
    for ax in range(dim):
        if not 0.0 <= point[ax] <= tank[ax]:
            raise ConfigError(where, point[:dim], f"a point inside the tank [0, {list(tank[:dim])}]")


def _box(where, value, tank, dim, extra_keys=()):
    item = _mapping(where, value, ("name", "lo", "hi") + extra_keys, required=("name", "lo", "hi"))
    name = _name(f"{where}.name", item["name"])
    lo = _pad3(_vector(f"{where}.lo", item["lo"], dim))
    hi = _pad3(_vector(f"{where}.hi", item["hi"], dim))
    for ax in range(dim):
        if hi[ax] <= lo[ax]:
            raise ConfigError(f"{where}.hi", list(hi[:dim]), f"every component above lo {list(lo[:dim])}")
    _inside(f"{where}.lo", lo, tank, dim)
    _inside(f"{where}.hi", hi, tank, dim)
    return item, name, lo, hi


def _unique(where, names):
    seen = set()
    for k, name in enumerate(names):
        if name in seen:
            raise ConfigError(f"{where}[{k}].name", name, "a name not used by another entry")
        seen.add(name)


def _walls(walls_in, dim, lid: bool) -> dict:
    """The wall kind of each face (the top's too with a lid): one kind for all, or a mapping face -> kind."""
    faces = wall_faces(dim, lid)
    if isinstance(walls_in, str):
        walls_in = {face: walls_in for face in faces}
    walls_in = _mapping("walls", walls_in, faces)
    walls = {}
    for face in faces:
        kind = walls_in.get(face, "particles")
        if kind not in WALL_KINDS:
            raise ConfigError(f"walls.{face}", kind, "one of " + ", ".join(WALL_KINDS))
        walls[face] = kind
    return walls


def _obstacles(items, tank, dim, depth: float, g: float) -> list:
    """Solid boxes standing on the floor, each with its pressure-block offsets."""
    up = dim - 1
    obstacles = []
    if not isinstance(items, list):
        raise ConfigError("obstacles", items, "a list of boxes {name, lo, hi, ...}")
    if len(items) > MAX_OBSTACLES:
        raise ConfigError("obstacles", f"{len(items)} obstacles", f"at most {MAX_OBSTACLES} (each a body measured "
                                                                  "at every output)")
    for k, item in enumerate(items):
        where = f"obstacles[{k}]"
        item, name, lo, hi = _box(where, item, tank, dim,
                                  extra_keys=("block_offsets", "displaces_fluid", "motion", "floating", "shape",
                                              "deadrise_deg", "axis", "points", "file"))
        offsets = item.get("block_offsets", [0.0, 0.06])
        if not isinstance(offsets, list):
            raise ConfigError(f"{where}.block_offsets", offsets, "a list of distances >= 0 [m]")
        offsets = tuple(_number(f"{where}.block_offsets[{j}]", o, lo=0.0) for j, o in enumerate(offsets))
        if lo[up] > 0.0 and item.get("floating") is None and item.get("motion") is None and \
                item.get("shape") != "points":
            raise ConfigError(f"{where}.lo", list(lo[:dim]), "a box standing on the floor (lo on the vertical axis "
                                                             "0), unless it floats or moves or is given as points")
        displaces = item.get("displaces_fluid", False)
        if not isinstance(displaces, bool):
            raise ConfigError(f"{where}.displaces_fluid", displaces, "true or false")
        obstacle = Obstacle(name, lo, hi, offsets, displaces)
        _shape(where, item, obstacle, dim)
        if item.get("motion") is not None and item.get("floating") is not None:
            raise ConfigError(where, name, "one of motion (prescribed) and floating (moved by the fluid), not both")
        if item.get("motion") is not None:
            obstacle.motion = _motion(f"{where}.motion", item["motion"], obstacle, tank, dim, depth, g)
        if item.get("floating") is not None:
            obstacle.motion = _floating(f"{where}.floating", item["floating"], obstacle, dim, g)
        obstacles.append(obstacle)
    _unique("obstacles", [o.name for o in obstacles])
    return obstacles


def _shape(where, item, obstacle, dim):
    """An obstacle's shape inside its box (scenes/shapes.py), with a wedge's deadrise and a
    cylinder's axis; a round shape's box is square across its axis (a cube for a sphere)."""
    shape = item.get("shape", "box")
    if shape not in shapes.SHAPES:
        raise ConfigError(f"{where}.shape", shape, "one of " + ", ".join(shapes.SHAPES))
    if (shape == "wedge") != ("deadrise_deg" in item):
        raise ConfigError(f"{where}.deadrise_deg", item.get("deadrise_deg"), "the wedge's deadrise angle [deg], "
                                                                            "for shape: wedge only")
    if (shape == "cylinder" and dim == 3) != ("axis" in item):
        raise ConfigError(f"{where}.axis", item.get("axis"), "the cylinder's axis, one of x, y, z, for shape: "
                                                            "cylinder in 3D only (a 2D cylinder is a disc)")
    if shape == "sphere" and dim == 2:
        raise ConfigError(f"{where}.shape", shape, "box, wedge, cylinder or points in 2D (a 2D cylinder is a disc)")
    if (shape == "points") != ("points" in item or "file" in item):
        raise ConfigError(f"{where}.points", item.get("points", item.get("file")),
                          "the body's particles (points, or a CSV file of them beside the scene file), for shape: "
                          "points only")
    obstacle.shape = shape
    if shape == "points":
        obstacle.points = _points(where, item, obstacle, dim)
    if shape == "wedge":
        obstacle.deadrise = math.radians(_number(f"{where}.deadrise_deg", item["deadrise_deg"], lo=1.0, hi=80.0))
    if "axis" in item:
        if item["axis"] not in shapes.AXES:
            raise ConfigError(f"{where}.axis", item["axis"], "one of " + ", ".join(shapes.AXES))
        obstacle.axis = shapes.AXES.index(item["axis"])
    if shape in shapes.ROUND:
        across = [a for a in range(dim) if a != obstacle.axis or shape == "sphere"]
        sizes = [obstacle.hi[a] - obstacle.lo[a] for a in across]
        if max(sizes) - min(sizes) > 1.0e-9 * max(sizes):
            names = ", ".join(shapes.AXES[a] for a in across)
            raise ConfigError(f"{where}.hi", list(obstacle.hi[:dim]), f"a box as wide along {names} (the {shape} "
                                                                      f"is inscribed in it); it is {sizes}")


MAX_POINTS = 500_000  # of a points body: more than every other particle of most scenes
MAX_CSV_ROWS = MAX_POINTS  # of a series or points file
MAX_CSV_BYTES = 32 << 20  # of such a file: 500,000 rows of three numbers
POINT_COLUMNS = ("x", "y", "z")


def _points(where, item, obstacle, dim) -> tuple:
    """A points body's particles: ``points``, each [x, y(, z)] [m] in the scene's axes inside its
    box (which stays its extent: what it meets, what it displaces, how it is drawn); each stands
    for dx^dim, so they are a spacing apart (build checks them against the run's dx)."""
    if "file" in item:
        raise ConfigError(f"{where}.file", item["file"], "a points file read from a scene file (gpusph-run "
                                                         "SCENE.yaml, whose folder it is in); a scene given whole "
                                                         "carries the points")
    pts = item["points"]
    if isinstance(pts, dict):  # a file's columns
        if any(c not in pts for c in POINT_COLUMNS[:dim]):
            raise ConfigError(f"{where}.file", sorted(pts), "columns " + ", ".join(POINT_COLUMNS[:dim]))
        pts = [list(row) for row in zip(*(pts[c] for c in POINT_COLUMNS[:dim]))]
    if not isinstance(pts, list) or not 1 <= len(pts) <= MAX_POINTS:
        raise ConfigError(f"{where}.points", pts, f"a list of 1 to {MAX_POINTS:,} points [x, y(, z)] [m]")
    rows = np.array([_vector(f"{where}.points[{k}]", p, dim) for k, p in enumerate(pts)])
    lo, hi = np.asarray(obstacle.lo[:dim]), np.asarray(obstacle.hi[:dim])
    outside = np.any((rows < lo) | (rows > hi), axis=1)
    if outside.any():
        k = int(np.argmax(outside))
        raise ConfigError(f"{where}.points[{k}]", rows[k].tolist(), f"a point inside the body's box [{lo.tolist()}, "
                                                                    f"{hi.tolist()}]")
    return tuple(tuple(float(c) for c in row) + (0.0,) * (3 - dim) for row in rows)


MOTION_KEYS = {"translate": ("type", "velocity", "start"),
               "sinusoid": ("type", "amplitude", "period", "phase_deg", "angle_deg", "axis", "centre"),
               "move": ("type", "displacement", "duration", "start"),
               "driven": ("type", "max_speed", "max_acceleration", "max_angular_speed", "max_angular_acceleration",
                          "timeout", "frame"),
               "series": ("type", "time", "x", "y", "z", "angle_deg", "axis", "centre", "file"),
               "piston": ("type", "wave_height", "period", "ramp", "depth"),
               "flap": ("type", "wave_height", "period", "ramp", "depth")}
DRIVEN_TIMEOUT = 0.5  # [s] of simulated time a command is held before the body is brought to rest
# a frame id by the ROS name rules (rcl's topic-name tokens, tf2's frames without a leading /): tokens of
# letters, digits and _, none starting with a digit, joined by single /; no "__" (ROS 2 reserves it);
# short (a 10^6-character frame_id was written into every message, 590 MB of recording in 6 s)
FRAME_ID = re.compile(r"(?!.*__)[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*")
MAX_FRAME_ID = 256
MAX_SERIES_ROWS = 100_000  # samples of a series: a wavemaker's 10 minutes at 100 Hz is 60,000
SERIES_CHANNELS = ("x", "y", "z", "angle_deg")


def _series(where, item, dim) -> tuple:
    """A series' rows (t, d_x, d_y, d_z, theta [rad]) from its columns: ``time`` [s], rising from 0
    or later, and any of x, y (and z in 3D) [m] and angle_deg, each as long and 0 in its first row
    (the body starts where the scene put it)."""
    if "file" in item:
        raise ConfigError(f"{where}.file", item["file"], "a series file read from a scene file (gpusph-run "
                                                         "SCENE.yaml, whose folder it is in); a scene given whole "
                                                         "carries the columns: time, x, y, z, angle_deg")
    times = item.get("time")
    if not isinstance(times, list) or not 2 <= len(times) <= MAX_SERIES_ROWS:
        raise ConfigError(f"{where}.time", times, f"a list of 2 to {MAX_SERIES_ROWS:,} times [s]")
    t = np.array([_number(f"{where}.time[{k}]", v, lo=0.0) for k, v in enumerate(times)])
    if np.any(np.diff(t) <= 0.0):
        k = int(np.argmax(np.diff(t) <= 0.0)) + 1
        raise ConfigError(f"{where}.time[{k}]", float(t[k]), f"a time after the one before ({t[k - 1]:g} s)")
    given = [c for c in SERIES_CHANNELS if c in item]
    if not given:
        raise ConfigError(where, sorted(item), "a series with at least one of " + ", ".join(SERIES_CHANNELS))
    rows = np.zeros((len(t), 5))
    rows[:, 0] = t
    for c in given:
        if c == "z" and dim == 2:
            raise ConfigError(f"{where}.z", item[c], "no z in 2D: x along the tank, y up")
        column = item[c]
        if not isinstance(column, list) or len(column) != len(t):
            raise ConfigError(f"{where}.{c}", column, f"a list of {len(t)} numbers, one per time")
        values = np.array([_number(f"{where}.{c}[{k}]", v) for k, v in enumerate(column)])
        if values[0] != 0.0:
            raise ConfigError(f"{where}.{c}[0]", float(values[0]), "0: a series starts where the scene put the body")
        rows[:, 1 + SERIES_CHANNELS.index(c)] = np.radians(values) if c == "angle_deg" else values
    return tuple(tuple(float(v) for v in row) for row in rows)


def _wavemaker(where, item, kind, obstacle, dim, depth, g) -> bodies.Motion:
    """A piston or a flap hinged at the bed making waves of ``wave_height`` and ``period`` in water
    ``depth`` deep (default the scene's): its stroke from linear wavemaker theory
    (theory/wavemaker.py), its amplitude ramped in over ``ramp`` seconds (default two periods)."""
    height = _number(f"{where}.wave_height", item["wave_height"], lo=0.0, lo_open=True)
    period = _number(f"{where}.period", item["period"], lo=0.0, lo_open=True)
    h = _number(f"{where}.depth", item.get("depth", depth), lo=0.0, lo_open=True)
    kh = wavemaker.wavenumber(period, h, g) * h
    ramp = _number(f"{where}.ramp", item.get("ramp", 2.0 * period), lo=0.0)
    if kind == "piston":
        stroke = height / wavemaker.piston_ratio(kh)
        return bodies.Motion(law="sinusoid", centre=obstacle.centre(dim), amplitude=(stroke / 2.0, 0.0, 0.0),
                             period=period, ramp=ramp)
    stroke = height / wavemaker.flap_ratio(kh)  # at the still water level, h above the hinge
    hinge = (0.5 * (obstacle.lo[0] + obstacle.hi[0]), 0.0, 0.0) if dim == 2 else \
        (0.5 * (obstacle.lo[0] + obstacle.hi[0]), 0.5 * (obstacle.lo[1] + obstacle.hi[1]), 0.0)
    axis = (0.0, 0.0, 1.0) if dim == 2 else (0.0, 1.0, 0.0)
    sign = -1.0 if dim == 2 else 1.0  # the top towards +x: about -z in the x-y plane, +y in 3D
    return bodies.Motion(law="sinusoid", centre=hinge, angle=sign * math.atan(stroke / (2.0 * h)), axis=axis,
                         period=period, ramp=ramp)


def _axis(where, item, dim) -> tuple:
    """A motion's rotation axis: z in 2D (none may be given), ``axis`` in 3D (default z)."""
    if dim == 2 and "axis" in item:
        raise ConfigError(f"{where}.axis", item["axis"], "no axis in 2D: a 2D body turns in its plane (about z)")
    axis = _vector(f"{where}.axis", item.get("axis", [0.0, 0.0, 1.0]), 3) if dim == 3 else (0.0, 0.0, 1.0)
    if math.hypot(*axis) == 0.0:
        raise ConfigError(f"{where}.axis", list(axis), "a non-zero vector")
    return axis


def _motion(where, value, obstacle, tank, dim, depth: float, g: float) -> bodies.Motion:
    """An obstacle's prescribed motion (sph/bodies.py): a sinusoid of its displacement and of its
    angle about an axis through ``centre`` (default the box's centre), a move by ``displacement``
    over ``duration`` (the box must stay in the tank over either's translation), a series of
    displacements and angles (``time`` and any of x, y, z, angle_deg, or a CSV ``file`` of those
    columns beside the scene file: _series, bodies.series_table), or driven by
    commands (drive.py) within its limits: max_speed and max_acceleration (required, > 0), the
    angular ones (default 0: it does not turn), and the timeout a command is held."""
    kind = value.get("type") if isinstance(value, dict) else None
    if kind not in bodies.LAWS:
        raise ConfigError(f"{where}.type", kind, "one of " + ", ".join(bodies.LAWS))
    keys = MOTION_KEYS[kind]
    item = _mapping(where, value, keys, required={"sinusoid": ("type", "period"), "translate": ("type", "velocity"),
                                                  "series": ("type",)}.get(kind, keys[:3]))
    if kind == "translate":
        return bodies.Motion(law="translate", centre=obstacle.centre(dim),
                             amplitude=_pad3(_vector(f"{where}.velocity", item["velocity"], dim)),
                             start=_number(f"{where}.start", item.get("start", 0.0), lo=0.0))
    if kind in ("piston", "flap"):
        if obstacle.lo[dim - 1] > 0.0:
            raise ConfigError(f"{where}.type", kind, "a paddle standing on the floor")
        return _wavemaker(where, item, kind, obstacle, dim, depth, g)
    if kind == "driven":
        limits = {key: _number(f"{where}.{key}", item.get(key, 0.0), lo=0.0, lo_open=key in keys[1:3])
                  for key in keys[1:5]}
        frame = item.get("frame", "")
        if not isinstance(frame, str) or len(frame) > MAX_FRAME_ID or (frame and not FRAME_ID.fullmatch(frame)):
            raise ConfigError(f"{where}.frame", frame, f"a TF frame id of at most {MAX_FRAME_ID} characters: "
                                                       "names of letters, digits and _ (none starting with a "
                                                       "digit) joined by /")
        return bodies.Motion(law="driven", centre=obstacle.centre(dim), **limits,
                             timeout=_number(f"{where}.timeout", item.get("timeout", DRIVEN_TIMEOUT), lo=0.0,
                                             lo_open=True), frame=frame)
    if kind == "series":
        rows = _series(where, item, dim)
        axis = _axis(where, item, dim)
        centre = _pad3(_vector(f"{where}.centre", item["centre"], dim)) if "centre" in item else obstacle.centre(dim)
        motion = bodies.Motion(law="series", centre=centre, axis=axis, series=rows)
    elif kind == "move":
        shift = _pad3(_vector(f"{where}.displacement", item["displacement"], dim))
        motion = bodies.Motion(law="move", centre=obstacle.centre(dim), amplitude=shift,
                               duration=_number(f"{where}.duration", item["duration"], lo=0.0, lo_open=True),
                               start=_number(f"{where}.start", item.get("start", 0.0), lo=0.0))
    else:
        amplitude = _pad3(_vector(f"{where}.amplitude", item.get("amplitude", [0.0] * dim), dim))
        phase = math.radians(_number(f"{where}.phase_deg", item.get("phase_deg", 0.0), lo=-360.0, hi=360.0))
        angle = math.radians(_number(f"{where}.angle_deg", item.get("angle_deg", 0.0), lo=-90.0, hi=90.0))
        axis = _axis(where, item, dim)
        centre = _pad3(_vector(f"{where}.centre", item["centre"], dim)) if "centre" in item else obstacle.centre(dim)
        if not any(amplitude) and angle == 0.0:
            raise ConfigError(where, value, "a sinusoid with a non-zero amplitude or angle_deg")
        motion = bodies.Motion(law="sinusoid", centre=centre, amplitude=amplitude,
                               period=_number(f"{where}.period", item["period"], lo=0.0, lo_open=True),
                               phase=phase, angle=angle, axis=axis)
    reach, _ = motion.reach()
    for ax in range(dim - 1):  # the vertical axis: the tank is open at the top
        low, high = obstacle.lo[ax] + reach[ax][0], obstacle.hi[ax] + reach[ax][1]
        if low < 0.0 or high > tank[ax]:
            raise ConfigError(where, value, f"a motion that keeps the box in the tank: along axis {ax} it reaches "
                                            f"[{low:.4g}, {high:.4g}] m of [0, {tank[ax]:g}]")
    return motion


FLOATING_KEYS = ("density", "mass", "centre_of_mass", "inertia", "translate", "rotate", "release", "velocity",
                 "omega", "max_force", "max_torque")
# a client's push on a floating body (cmd_wrench) is held to its weight by default: 300 N up on a
# 10 kg/m box sent it 7.5 m up, through the headroom, before anything said so (issue 58)
MAX_FORCE_LIMIT = 1.0e9  # [N] the most a scene may allow


def _flags(where, value, length) -> tuple:
    if isinstance(value, bool):
        value = [value] * length
    if not isinstance(value, list) or len(value) != length or not all(isinstance(v, bool) for v in value):
        raise ConfigError(where, value, f"true, false or a list of {length} of them (per axis: free or held)")
    return tuple(value)


def _floating(where, value, obstacle, dim, g: float) -> bodies.Floating:
    """A floating obstacle (sph/bodies.py): its mass from ``density`` x its solid's volume (area per
    unit depth in 2D; scenes/shapes.py) or given, its centre of mass (default the solid's centroid),
    its inertia about that (default the uniform solid's, carried to the centre of mass), which axes
    it may move along and turn about (2D: translate [x, y], rotate about z), when it is let go, and
    its velocity and angular velocity then, and the largest force and torque a client may push it
    with (default its weight m g, and m g at its farthest corner from the centre of mass)."""
    item = _mapping(where, value, FLOATING_KEYS)
    if obstacle.shape == "points":
        for key in ("mass", "centre_of_mass", "inertia"):
            if key not in item:
                raise ConfigError(f"{where}.{key}", None, "a floating points body's mass, centre_of_mass and inertia "
                                                          "(its solid is not known from its particles)")
    if ("density" in item) == ("mass" in item):
        raise ConfigError(where, value, "one of density [kg/m^3] and mass [kg; kg/m in 2D]")
    body = shapes.solid(obstacle, dim)
    if "density" in item:
        mass = _number(f"{where}.density", item["density"], lo=0.0, lo_open=True) * body.volume
    else:
        mass = _number(f"{where}.mass", item["mass"], lo=0.0, lo_open=True)
    centre = body.centroid
    com = _pad3(_vector(f"{where}.centre_of_mass", item["centre_of_mass"], dim)) if "centre_of_mass" in item else centre
    if "inertia" in item:
        given = item["inertia"]
        if dim == 2:
            inertia = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                       (0.0, 0.0, _number(f"{where}.inertia", given, lo=0.0, lo_open=True)))
        elif isinstance(given, list) and len(given) == 3 and all(isinstance(row, list) for row in given):
            inertia = tuple(_vector(f"{where}.inertia[{k}]", row, 3) for k, row in enumerate(given))
        else:
            inertia = tuple(tuple(d if j == k else 0.0 for j in range(3))
                            for k, d in enumerate(_vector(f"{where}.inertia", given, 3, lo=0.0)))
    else:
        about_centre = mass * np.asarray(body.inertia)
        d = np.asarray(com) - np.asarray(centre)
        shifted = about_centre - mass * (d @ d * np.eye(3) - np.outer(d, d))  # parallel axes, to the centre of mass
        inertia = tuple(tuple(float(c) for c in row) for row in (shifted if dim == 3 else np.diag(
            [0.0, 0.0, shifted[2, 2]])))
    translate = _flags(f"{where}.translate", item.get("translate", True), dim) + ((False,) if dim == 2 else ())
    rotate = _flags(f"{where}.rotate", item.get("rotate", True), 1 if dim == 2 else 3)
    rotate = (False, False, rotate[0]) if dim == 2 else rotate
    velocity = _pad3(_vector(f"{where}.velocity", item.get("velocity", [0.0] * dim), dim))
    omega = (0.0, 0.0, _number(f"{where}.omega", item.get("omega", 0.0))) if dim == 2 else \
        _vector(f"{where}.omega", item.get("omega", [0.0] * 3), 3)
    weight = mass * g
    reach = bodies.farthest_corner(obstacle.lo, obstacle.hi, com)
    max_force = _number(f"{where}.max_force", item.get("max_force", weight), lo=0.0, hi=MAX_FORCE_LIMIT)
    max_torque = _number(f"{where}.max_torque", item.get("max_torque", weight * reach), lo=0.0, hi=MAX_FORCE_LIMIT)
    return bodies.Floating(mass=mass, centre=com, inertia=inertia, translate=translate, rotate=rotate,
                           release=_number(f"{where}.release", item.get("release", 0.0), lo=0.0),
                           velocity=velocity, omega=omega, max_force=max_force, max_torque=max_torque,
                           corner_lo=tuple(a - c for a, c in zip(obstacle.lo, com)),
                           corner_hi=tuple(b - c for b, c in zip(obstacle.hi, com)), **shapes.contact(obstacle, dim))


def _zones(items, tank, dim, obstacles) -> list:
    """Refinement zones: boxes {name, lo, hi, ratio} or bands {name, around: <obstacle>, margin, ratio},
    clipped to the tank, each of ratio below 0.5 inside one of twice its ratio."""
    if not isinstance(items, list):
        raise ConfigError("refine", items, "a list of zones {name, lo, hi, ratio} or {name, around, margin, ratio}")
    if len(items) > MAX_ZONES:
        raise ConfigError("refine", f"{len(items)} zones", f"at most {MAX_ZONES}")
    by_name = {o.name: o for o in obstacles}
    zones = []
    for k, item in enumerate(items):
        where = f"refine[{k}]"
        keys = ("name", "lo", "hi", "around", "margin", "ratio")
        item = _mapping(where, item, keys, required=("name", "ratio"))
        ratio = item["ratio"]
        if ratio not in ZONE_RATIOS or isinstance(ratio, bool):
            raise ConfigError(f"{where}.ratio", ratio, "one of " + ", ".join(f"{r:g}" for r in ZONE_RATIOS)
                              + " (the zone's spacing over the scene's dx; each level halves the one around it)")
        if "around" in item:
            for key in ("lo", "hi"):
                if key in item:
                    raise ConfigError(f"{where}.{key}", item[key], f"no {key}: a zone is a box (lo, hi) or a band "
                                                                   "around an obstacle (around, margin), not both")
            if item["around"] not in by_name:
                raise ConfigError(f"{where}.around", item["around"], "the name of an obstacle of the scene ("
                                  + (", ".join(by_name) or "it has none") + ")")
            if "margin" not in item:
                raise ConfigError(f"{where}.margin", None, "the band's width around the obstacle [m]")
            margin = _number(f"{where}.margin", item["margin"], lo=0.0, hi=max(tank), lo_open=True)
            o = by_name[item["around"]]
            lo = tuple(max(0.0, c - margin) if ax < dim else 0.0 for ax, c in enumerate(o.lo))
            hi = tuple(min(tank[ax], c + margin) if ax < dim else 0.0 for ax, c in enumerate(o.hi))
            name = _name(f"{where}.name", item["name"])
            zones.append(Zone(name, lo, hi, float(ratio), o.name, margin))
        else:
            if "margin" in item:
                raise ConfigError(f"{where}.margin", item["margin"], "no margin: only a band (around) takes one")
            _, name, lo, hi = _box(where, {key: item[key] for key in ("name", "lo", "hi") if key in item}, tank, dim)
            zones.append(Zone(name, lo, hi, float(ratio)))
    _unique("refine", [z.name for z in zones])
    for k, z in enumerate(zones):
        if z.ratio < max(ZONE_RATIOS) and not any(
                p.ratio == 2 * z.ratio and all(p.lo[ax] <= z.lo[ax] and z.hi[ax] <= p.hi[ax] for ax in range(dim))
                for p in zones):
            raise ConfigError(f"refine[{k}]", z.name, f"a zone inside a zone of ratio {2 * z.ratio:g} (each level "
                                                      "halves the spacing of the one around it)")
    return zones


def _probes(probes_in, tank, dim) -> list:
    """Probes by name (PROBE_TYPES), each inside the tank."""
    up = dim - 1
    probes = []
    if not isinstance(probes_in, dict):
        raise ConfigError("probes", probes_in, "a mapping from probe name to {type, position, ...}")
    if len(probes_in) > MAX_PROBES:
        raise ConfigError("probes", f"{len(probes_in)} probes", f"at most {MAX_PROBES} probes (each is a topic "
                                                                 "measured and published at every output)")
    for name, item in probes_in.items():
        where = f"probes.{name}"
        _name(where, name)
        item = _mapping(where, item, ("type", "position", "radius_dx", "heights", "normal", "diameter", "reading",
                                      "sampling", "clip", "response"), required=("type", "position"))
        kind = item["type"]
        if kind not in PROBE_TYPES:
            raise ConfigError(f"{where}.type", kind, "one of " + ", ".join(PROBE_TYPES))
        length = dim if kind in ("point", "pressure_sensor") else dim - 1
        position = _pad3(_vector(f"{where}.position", item["position"], length))
        _inside(f"{where}.position", position, tank, length)
        radius = _number(f"{where}.radius_dx", item.get("radius_dx", 3.0), lo=0.0, hi=MAX_RADIUS_DX, lo_open=True)
        heights = ()
        if kind == "profile":
            raw = item.get("heights")
            if not isinstance(raw, list) or not raw:
                raise ConfigError(f"{where}.heights", raw, "a list of heights above the floor [m]")
            if len(raw) > MAX_HEIGHTS:
                raise ConfigError(f"{where}.heights", f"{len(raw)} heights", f"at most {MAX_HEIGHTS} (a topic each)")
            heights = tuple(_number(f"{where}.heights[{j}]", z, lo=0.0, hi=tank[up]) for j, z in enumerate(raw))
        elif "heights" in item:
            raise ConfigError(f"{where}.heights", item["heights"], "no heights: only profile probes take them")
        normal, diameter, reading, sampling, clip, response = (), 0.0, "wall", "mean", True, 0.0
        if kind == "pressure_sensor":
            if "normal" not in item:
                raise ConfigError(f"{where}.normal", None, f"the face's inward normal, a list of {dim} numbers")
            raw = _vector(f"{where}.normal", item["normal"], dim)
            norm = math.sqrt(sum(c * c for c in raw))
            if norm == 0.0:
                raise ConfigError(f"{where}.normal", list(raw), "a non-zero vector into the fluid")
            normal = _pad3(tuple(c / norm for c in raw))
            diameter = _number(f"{where}.diameter", item.get("diameter", 0.0), lo=0.0, hi=max(tank))
            reading = item.get("reading", "wall")
            if reading not in SENSOR_READINGS:
                raise ConfigError(f"{where}.reading", reading, "one of " + ", ".join(SENSOR_READINGS))
            sampling = item.get("sampling", "mean")
            if sampling not in SENSOR_SAMPLINGS:
                raise ConfigError(f"{where}.sampling", sampling, "one of " + ", ".join(SENSOR_SAMPLINGS))
            clip = item.get("clip", True)
            if not isinstance(clip, bool):
                raise ConfigError(f"{where}.clip", clip, "true (gauge pressure, clipped at 0) or false (its sign kept)")
            response = float(_number(f"{where}.response", item.get("response", 0.0), lo=0.0, hi=MAX_RESPONSE))
        else:
            if kind == "gauge":
                reading = item.get("reading", "fraction")
                if reading not in GAUGE_READINGS:
                    raise ConfigError(f"{where}.reading", reading, "one of " + ", ".join(GAUGE_READINGS))
            takes = ("normal", "diameter", "sampling", "clip", "response") + (() if kind == "gauge" else ("reading",))
            for key in takes:
                if key in item:
                    raise ConfigError(f"{where}.{key}", item[key], f"no {key}: only pressure_sensor probes take one")
        probes.append(Probe(name, kind, position, radius, heights, normal, diameter, reading, sampling, clip, response))
    return probes


def parse_scene(data, default_name: str = "scene") -> Scene:
    """Check a scene read from YAML (a dict) and return it as a ``Scene``."""
    data = _mapping("", data, SCENE_KEYS, required=("dim", "tank", "fluid"))
    dim = data["dim"]
    if dim not in (2, 3) or isinstance(dim, bool):
        raise ConfigError("dim", dim, "2 or 3")
    up = dim - 1
    tank = _pad3(_vector("tank", data["tank"], dim, lo=0.0))
    if min(tank[:dim]) <= 0.0:
        raise ConfigError("tank", list(tank[:dim]), "a list of lengths > 0 [m]")
    default_g = [0.0] * dim
    default_g[up] = -9.81
    gravity = _pad3(_vector("gravity", data.get("gravity", default_g), dim))
    # a horizontal part is a tank's horizontal acceleration a (the fluid feels g - a), up to 1 g
    across = math.sqrt(sum(gravity[ax] ** 2 for ax in range(dim) if ax != up))
    if gravity[up] >= 0.0 or across > -gravity[up]:
        raise ConfigError("gravity", list(gravity[:dim]),
                          f"a vector pointing down the vertical axis ({'xyz'[up]}), tilted by at most 45 degrees "
                          f"(a horizontal acceleration of the tank up to 1 g), e.g. {default_g}")
    if not MIN_GRAVITY <= math.sqrt(sum(c * c for c in gravity)) <= MAX_GRAVITY:
        raise ConfigError("gravity", list(gravity[:dim]), f"a magnitude in [{MIN_GRAVITY:g}, {MAX_GRAVITY:g}] m/s^2 "
                                                          "(it sets the sound speed and so the time step)")
    headroom = _number("headroom", data.get("headroom", 0.5), lo=0.0, hi=MAX_HEADROOM)
    periodic = data.get("periodic", [False] * dim)
    if (not isinstance(periodic, list) or len(periodic) != dim
            or not all(isinstance(p, bool) for p in periodic) or periodic[up]):
        raise ConfigError("periodic", periodic, f"a list of {dim} booleans, false for the vertical axis")
    periodic = tuple(periodic) + (False,) * (3 - dim)

    lid = data.get("lid", False)
    if not isinstance(lid, bool):
        raise ConfigError("lid", lid, "true or false (a wall across the tank's top, of the kind walls.lid names)")
    walls = _walls(data.get("walls", "particles"), dim, lid)

    fluid_in = data["fluid"]
    if not isinstance(fluid_in, list) or not fluid_in:
        raise ConfigError("fluid", fluid_in, "a list of at least one box {name, lo, hi}")
    fluid = []
    for k, item in enumerate(fluid_in):
        _, name, lo, hi = _box(f"fluid[{k}]", item, tank, dim)
        fluid.append(Box(name, lo, hi))
    _unique("fluid", [b.name for b in fluid])
    for k, a in enumerate(fluid):  # two boxes over one region fill it twice: particles on top of each other
        for b in fluid[k + 1:]:
            if all(min(a.hi[ax], b.hi[ax]) > max(a.lo[ax], b.lo[ax]) for ax in range(dim)):
                raise ConfigError(f"fluid[{fluid.index(b)}]", b.name, f"a box clear of the other fluid boxes: it "
                                                                      f"overlaps {a.name!r}")
    surface = max(b.hi[up] for b in fluid)
    warnings = [f"fluid box {b.name!r} fills the whole tank: the water has nowhere to go but over the walls"
                for b in fluid if not lid and all(b.lo[ax] <= 0.0 and b.hi[ax] >= tank[ax] for ax in range(dim))]
    # the reference depth H sets c0 = c0_coef sqrt(g H) and the wall forces: a fluid deeper than the
    # tank is no tank's, and its sound speed would take millions of steps a second
    depth = _number("depth", data.get("depth", surface), lo=0.0, hi=tank[up], lo_open=True)
    wet_bed = _number("wet_bed", data.get("wet_bed", 0.0), lo=0.0, hi=tank[up])

    obstacles = _obstacles(data.get("obstacles") or [], tank, dim, depth, math.hypot(*gravity))
    refine = _zones(data.get("refine") or [], tank, dim, obstacles)
    probes = _probes(data.get("probes") or {}, tank, dim)

    run = data.get("run") or {}
    if not isinstance(run, dict):
        raise ConfigError("run", run, "a mapping of run settings (see the run configuration)")
    name = data.get("name", default_name)
    _name("name", name)
    return Scene(name=name, dim=dim, tank=tank, gravity=gravity, depth=depth, fluid=fluid,
                 description=_text("description", data.get("description", "")),
                 source=_text("source", data.get("source", "")),
                 headroom=headroom, periodic=periodic, walls=walls, wet_bed=wet_bed, obstacles=obstacles,
                 refine=refine, probes=probes, run_settings=dict(run),
                 analysis=_analysis(data.get("analysis"), probes, obstacles),
                 warnings=warnings)


# what each analysis reads from a recording (analysis/report.py): probes by name and the types it takes,
# and for DamBreak 1 an obstacle with pressure blocks at its faces and 0.06 m out
ANALYSIS_PROBES = {"dambreak1": {"velocity": ("point",), "D": ("point",)}, "dambreak2": {"bore": ("column",)},
                   "lobovsky": {}}
LOBOVSKY_PROBES = ("sensor_1", "sensor_2", "sensor_3", "sensor_4", "H1", "H2", "H3", "H4")


def _analysis(value, probes, obstacles) -> dict:
    """The ``analysis:`` section: {case: one of ANALYSES, gpusph: true when the thesis's GPUSPH
    results are of this geometry (default false)}; refused when the scene lacks what the case's
    analysis reads, so that a run is not made for an analysis that cannot be done."""
    if value is None:
        return {}
    value = _mapping("analysis", value, ("case", "gpusph"), required=("case",))
    case = value["case"]
    if case not in ANALYSES:
        raise ConfigError("analysis.case", case, "one of " + ", ".join(ANALYSES))
    kinds = {p.name: p.type for p in probes}
    for name, types in ANALYSIS_PROBES[case].items():
        if kinds.get(name) not in types:
            raise ConfigError("analysis.case", case, f"a scene with a {' or '.join(types)} probe named {name!r}, "
                              f"which the {case} analysis reads (probes here: {', '.join(kinds) or 'none'})")
    if case == "dambreak1" and not (obstacles and {0.0, 0.06} <= set(obstacles[0].block_offsets)):
        raise ConfigError("analysis.case", case, "a scene whose first obstacle has pressure blocks at 0 and 0.06 m "
                          "(block_offsets), whose forces the dambreak1 analysis reads")
    if case == "lobovsky" and not set(kinds) & set(LOBOVSKY_PROBES):
        raise ConfigError("analysis.case", case, "a scene with a probe of the lobovsky analysis: "
                          + ", ".join(LOBOVSKY_PROBES))
    gpusph = value.get("gpusph", False)
    if not isinstance(gpusph, bool):
        raise ConfigError("analysis.gpusph", gpusph, "true or false (the thesis's GPUSPH results are of this scene)")
    return {"case": value["case"], "gpusph": gpusph}
