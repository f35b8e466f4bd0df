"""The parameters of sim_node: what each means, what it may be, when it takes effect, and the
run (scene + run configuration) a set of values describes.

Plain data and checks, no rclpy node: the node declares a ROS parameter with a descriptor for
each entry of ``PARAMS`` and asks ``check`` before accepting a change, so a parameter file, a
``-p name:=value`` and a ``ros2 param set`` all get the same reasons.
"""
import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

from ..measure.cloud import FIELDS as PARTICLE_FIELDS
from ..output.folders import folder_problem
from ..scenes import resources
from ..scenes.build import fluid_boxes, priced
from ..scenes.reduce import MODELS
from ..scenes.schema import FRAME_ID, MAX_FRAME_ID, MAX_PATH, builtin_names, load_scene
from ..scenes.settings import COMPRESSIONS, NUMERIC_FIELDS, STAMPS, resolve
from ..sph.config import LIVE, RESET, ConfigError, SolverConfig, shown
from ..sph.device import AUTO

# when a change takes effect: RESET (needs new particles or buffers: at the next ~/reset) and LIVE
# (from the next step or output) as the solver's settings say, and
RECORDING = "recording"  # at the next recording
STARTUP = "startup"  # read-only, set at start-up
SERVICE = "service"  # read by the service that uses it

VISCOSITY_CHOICES = ("artificial", "laminar")  # SPS is laminar + the sub-particle-scale stress: `sps`


@dataclass(frozen=True)
class Param:
    name: str
    default: object
    description: str
    applies: str
    choices: tuple = ()
    lo: float = None
    hi: float = None


HAND_DECLARED = ("viscosity",)  # a solver setting whose parameter PARAMS declares itself (sps beside it)
# the run settings of gpusph-run that the node takes another way: the clouds follow output_rate and
# publish_particles; a recorded node writes no checkpoints (~/save_state does)
NOT_NODE_SETTINGS = {"particle_rate": "the node's clouds follow output_rate (publish_particles turns them off)",
                     "checkpoint_interval": "the node writes no checkpoints of its own; ~/save_state does"}


# the node's own defaults where they differ from the solver's: its default run is DamBreak 1 at
# 3 cm, on the CPU whatever $GPUSPH_ROS_DEVICE says
NODE_DEFAULTS = {"dx": 0.03, "device": "cpu"}


def _scene_first() -> frozenset:
    """The solver settings declared for the node whose default leaves the scene's run: value: all
    but those the node declared first (``node=True`` in sph/config.py), which always override it."""
    return frozenset(f.name for f in dataclasses.fields(SolverConfig)
                     if f.name in NUMERIC_FIELDS and f.name not in HAND_DECLARED and not f.metadata.get("node"))


def _solver_params() -> tuple:
    """A parameter for each solver setting a run may set (``--set``: the numerics and the health
    limits, ``scenes.settings.NUMERIC_FIELDS``) but those declared by hand below (viscosity): its
    meaning, choices or range and when a change applies come from the setting itself. A setting
    the node does not declare is ignored by rclpy without a word (`-p neighbour_search:=cells` ran
    with lists), so every one is declared."""
    out = []
    for f in dataclasses.fields(SolverConfig):
        m = f.metadata
        if m.get("node") or (f.name in NUMERIC_FIELDS and f.name not in HAND_DECLARED):
            default = NODE_DEFAULTS.get(f.name, f.default)
            out.append(Param(f.name, default, m["doc"], m["applies"], choices=tuple(m["choices"] or ()), lo=m["lo"],
                             hi=m["hi"]))
    return tuple(out)


# the parameter clock: what the node does with /clock; "none", not "off": ROS reads parameters as YAML
# 1.1, where `clock:=off` is the boolean false
CLOCKS = ("publish", "follow", "lockstep", "none")
SOLVER_PARAMS = _solver_params()
SCENE_FIRST = _scene_first()
PARAMS = (
    Param("scene", "dambreak1_thesis", "built-in scene name (" + ", ".join(builtin_names()) + ") or a path "
          "to a scene YAML file", RESET),
    *SOLVER_PARAMS,
    Param("viscosity", "artificial", "viscosity model: artificial (Monaghan 1992; not in the thesis) or laminar "
          "(Morris 1997, thesis Eq. 2.16-2.17)", LIVE, choices=VISCOSITY_CHOICES),
    Param("sps", False, "add the sub-particle-scale turbulence stress to laminar viscosity (Dalrymple & Rogers "
          "2006, thesis Eq. 2.18-2.21); needs viscosity laminar", LIVE),
    Param("model", "full", "how the scene is modelled: full, slab (a thin periodic slab across y) or 2d (the x-z "
          "section), for a flow uniform across y such as dambreak2_*; 2d_until_reflection (the x-z section without "
          "the narrow obstacles, for the probes upstream of them until their reflection returns)", RESET,
          choices=MODELS),
    Param("crop", False, "cut the tank to what a front moving at 2 sqrt(g H) reaches by the end time", RESET),
    Param("slab_width", 0.0, "with model slab, the slab's width across y [m]; 0 = the narrowest periodic slab",
          RESET, lo=0.0, hi=1.0e3),
    Param("wall_planes", False, "every wall of boundary particles as a particle-less plane", RESET),
    Param("end_time", 0.0, "simulated time the run stops at [s]; 0 = the scene's own", LIVE, lo=0.0, hi=1.0e5),
    Param("output_rate", 0.0, "outputs per simulated second [Hz]: /clock, probes, wrenches and particles; "
          "0 = the scene's own", LIVE, lo=0.0, hi=1.0e4),
    Param("wrench_rate", 0.0, "each body's wrench, pose and twist alone, without the cloud, this many times a "
          "simulated second [Hz] on ~/bodies/<name>/wrench_fast, pose_fast and odom_fast (and /clock before them), "
          "the wrench the mean over the steps since the last, for a controller's rate; each such time ends a step; "
          "0 = with the outputs only", RESET, lo=0.0, hi=1.0e4),
    Param("clock", "publish", "the /clock topic: publish (the fluid's simulated time), follow (take /clock from "
          "another publisher, a robot simulator's, and advance the fluid to each time it receives, never past it; a "
          "clock that goes back resets the run), lockstep (a master steps the fluid: it advances only to each time "
          "sent on ~/advance_to, std_msgs/Header's stamp, lands on it and answers on ~/reached with its time; no "
          "/clock) or none (no clock: a recording-only run)", STARTUP, choices=CLOCKS),
    Param("max_lag", 0.1, "under clock: follow, how far the fluid may fall behind the followed clock [s] before "
          "the node warns (once; /diagnostics counts each clock message after that with the fluid further behind)",
          LIVE, lo=0.0, hi=1.0e3),
    Param("real_time_factor", 0.0, "simulated seconds per wall second the node keeps to at most; 0 = as fast "
          "as possible", LIVE, lo=0.0, hi=1.0e3),
    Param("publish_particles", True, "build and publish the particle cloud at each output (and record it)", LIVE),
    Param("particle_fields", list(PARTICLE_FIELDS), "cloud fields after x, y, z (float32 each): any of "
          + ", ".join(PARTICLE_FIELDS), LIVE, choices=PARTICLE_FIELDS),
    Param("record_dir", "", "folder that recordings (rosbag2 + MCAP, one sub-folder each) go to; empty = no "
          "recording", RECORDING),
    Param("compression", "zstd", "a recording's MCAP chunk compression: zstd (as ros2 bag record -s mcap), lz4 "
          "(faster, larger) or none", RECORDING, choices=COMPRESSIONS),
    Param("stamps", "simulated", "what the stamps count: simulated (seconds from 0) or epoch (the simulated time "
          "added to the wall clock at the run's start, for viewers that show dates)", RESET, choices=STAMPS),
    Param("frame_id", "world", "the world frame (z up) of every message; a body's wrench is in <frame_id>/<body>",
          LIVE),
    Param("state_file", "", "the file ~/save_state writes the run's whole state to and ~/load_state reads it from "
          "(the same scene and settings)", SERVICE),
    Param("autostart", True, "configure and activate the (lifecycle) node at start-up", STARTUP),
)
BY_NAME = {p.name: p for p in PARAMS}
DEFAULTS = {p.name: p.default for p in PARAMS}

# The one list of what a running session takes live, and where each setting goes: the solver's
# numerics (Solver.reconfigure), the run's outputs (Run.set_output), the cloud (Run.set_cloud) or
# the node's pacing. A LIVE parameter comes to the settings of the same name, except those below.
LIVE_SETTINGS = {**{p.name: "solver" for p in SOLVER_PARAMS if p.applies == LIVE}, "viscosity": "solver",
                 "end_time": "output", "output_rate": "output", "particle_rate": "output", "particle_fields": "cloud",
                 "frame_id": "cloud", "real_time_factor": "pace", "max_lag": "pace"}
_SETTINGS_OF = {"sps": ("viscosity",), "publish_particles": ("particle_rate",)}


def undeclared(names) -> list:
    """A line for each of ``names`` (parameters given at start-up) the node does not take: a run
    setting it takes another way, or an unknown name with the closest it declares."""
    import difflib

    out = []
    for name in sorted(set(names) - set(BY_NAME)):
        if name in NOT_NODE_SETTINGS:
            out.append(f"{name}: a run setting of gpusph-run that the node does not take ({NOT_NODE_SETTINGS[name]})")
            continue
        close = difflib.get_close_matches(name, list(BY_NAME), n=1)
        out.append(f"{name}: not a parameter of this node" + (f" (did you mean {close[0]}?)" if close else "")
                   + "; it is ignored")
    return out


def applies_text(name: str) -> str:
    return {RESET: "at the next ~/reset (it needs new particles)", LIVE: "from the next step",
            RECORDING: "at the next recording", STARTUP: "at start-up only",
            SERVICE: "at the next ~/save_state or ~/load_state"}[BY_NAME[name].applies]


def _device_names() -> list:
    import warp as wp

    return [AUTO] + [d.alias for d in wp.get_devices()]


# the longest text a parameter takes: a path (Linux's PATH_MAX), a frame id (schema.MAX_FRAME_ID)
MAX_TEXT = {"scene": MAX_PATH, "record_dir": MAX_PATH, "state_file": MAX_PATH, "frame_id": MAX_FRAME_ID}


def _check_one(p: Param, value):
    """The reason ``value`` is not allowed for ``p``, or None."""
    if p.name in MAX_TEXT and len(value) > MAX_TEXT[p.name]:
        return f"{p.name}: a text of {len(value):,} characters; at most {MAX_TEXT[p.name]:,} are allowed"
    if p.name == "particle_fields":
        bad = [v for v in value if v not in p.choices]
        if bad:
            return f"particle_fields: {shown(bad[0])} is not one of {', '.join(p.choices)}"
        if len(set(value)) != len(value):
            return f"particle_fields: {shown(list(value))} names a field twice"
    elif p.choices and value not in p.choices:
        hint = " (for SPS set viscosity laminar and sps true)" if (p.name, value) == ("viscosity", "sps") else ""
        return f"{p.name}: {shown(value)} is not one of {', '.join(p.choices)}{hint}"
    elif p.lo is not None and not (math.isfinite(value) and p.lo <= value <= p.hi):
        return f"{p.name}: {value!r} is outside [{p.lo:g}, {p.hi:g}] ({p.description})"
    elif p.name == "device" and value not in _device_names():
        return f"device: {value!r} is not available here; the devices are {', '.join(_device_names())}"
    elif p.name == "frame_id" and not FRAME_ID.fullmatch(value):
        return (f"frame_id: {shown(value)} is not a ROS frame name: names of letters, digits and _ (none starting "
                "with a digit, no __) joined by /, e.g. world or robot1/odom")
    elif p.name == "record_dir" and value and (problem := folder_problem(value)):
        return f"record_dir: {value!r} cannot be written: {problem}"
    elif p.name == "state_file" and value and (problem := folder_problem(str(Path(value).expanduser().parent))):
        return f"state_file: {value!r} cannot be written: its folder {problem}"
    return None


def check(values: dict, changed=None):
    """The reason the parameter ``values`` (all of them) make no run, or None. ``changed`` names
    the parameters being set: they are checked first, one by one, then the whole combination."""
    for name in changed or BY_NAME:
        reason = _check_one(BY_NAME[name], values[name])
        if reason:
            return reason
    if values["clock"] in ("follow", "lockstep") and values["stamps"] != "simulated":
        return (f"clock: {values['clock']} takes the master clock's time as the simulated time; it needs stamps "
                f"simulated, not {values['stamps']!r}")
    if values["sps"] and values["viscosity"] != "laminar":
        return (f"sps: true needs viscosity laminar (SPS adds the sub-particle-scale stress to laminar "
                f"viscosity); viscosity is {values['viscosity']!r}")
    try:
        scene, config = run_settings(values)
        # what ~/reset's build would refuse (a 1e300 m tank, a dx of 0.1 mm), refused when set, not
        # left pending: the particles it makes at most against max_particles and free memory
        reduced, cfg, _ = priced(scene, config)
        resources.check(reduced, cfg, fluid_boxes(reduced))
    except ConfigError as err:
        return str(err)
    return None


def live_settings(values: dict, changed) -> dict:
    """The session settings (LIVE_SETTINGS) that a change of the live parameters ``changed`` comes
    to, ``values`` being every parameter after the change. The outputs go as one: the clouds
    follow output_rate, and an output time depends on both rate and end time."""
    _, config = run_settings(values)
    out = config.output
    resolved = {**values, "viscosity": config.solver.viscosity, "end_time": out.end_time,
                "output_rate": out.output_rate, "particle_rate": out.particle_rate}
    touched = {s for name in changed for s in _SETTINGS_OF.get(name, (name,))}
    if any(LIVE_SETTINGS.get(s) == "output" for s in touched):
        touched |= {s for s, where in LIVE_SETTINGS.items() if where == "output"}
    return {s: resolved[s] for s in touched if s in LIVE_SETTINGS}


def run_settings(values: dict):
    """(scene, RunConfig) of the parameter ``values``; ConfigError when they make no run."""
    scene = load_scene(values["scene"])
    output = {k: values[k] for k in ("end_time", "output_rate") if values[k] > 0.0}
    output |= {k: values[k] for k in ("compression", "stamps", "wrench_rate")}
    # a setting the node took only to refuse nothing silently (SCENE_FIRST) is passed where set off
    # its default: at the default, the scene's own run: section stands (a sinking column's
    # energy_growth_ratio: 0 was overridden by 0.05 and the run failed its energy check)
    numerics = {p.name: values[p.name] for p in SOLVER_PARAMS
                if p.name not in SCENE_FIRST or values[p.name] != p.default}
    numerics["viscosity"] = "sps" if values["sps"] else values["viscosity"]
    reduction = {k: values[k] for k in ("model", "crop", "wall_planes")}
    if values["slab_width"] != 0.0:  # as SCENE_FIRST: at 0, the scene's own
        reduction["slab_width"] = values["slab_width"]
    # the node's clouds follow output_rate
    config = resolve(scene, **numerics, **output, **reduction, particle_rate=0.0)
    rate = config.output.output_rate if values["publish_particles"] else 0.0
    config.output = dataclasses.replace(config.output, particle_rate=rate)
    return scene, config
