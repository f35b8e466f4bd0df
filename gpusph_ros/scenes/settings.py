"""The run configuration: numerics and output settings of one run, kept apart from the scene.

Layers, later ones winning: the solver's defaults (``SolverConfig``), the scene's ``run:`` section,
run configuration files (YAML mappings, e.g. ``config/runs/thesis_scenario1.yaml``), then
``--set key=value`` overrides (values read as YAML: ``xsph=true``, ``dx=0.02``). Every key is
checked: an unknown one gets the list of known ones, a value of the wrong kind says which kind.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from ..sph.config import ConfigError, Domain, HealthLimits, Numerics, SolverConfig, settings_of, unknown_key
from . import yaml_input
from .reduce import Reduction, apply
from .schema import Scene, read_yaml, shipped

# SolverConfig fields that the scene decides, or that the scene builder derives
SCENE_FIELDS = tuple(f.name for f in settings_of(Domain))
MAX_OUTPUT_RATE = 10_000.0  # [Hz] simulated: outputs 0.1 ms apart, a wall-pressure transducer's rate
MIN_OUTPUT_RATE = 1.0e-3  # [Hz] simulated: an output every 1000 s at least (a denormal rate is no rate)
# [s] simulated: a day of flow is beyond any case here (a tank's sloshing decays in minutes) and would
# run for years on a CPU; 1 microsecond is a few steps
MIN_END_TIME, MAX_END_TIME = 1.0e-6, 1.0e5
COMPRESSIONS = ("zstd", "lz4", "none")
STAMPS = ("simulated", "epoch")
NUMERIC_FIELDS = tuple(f.name for part in (Numerics, HealthLimits) for f in settings_of(part))


@dataclass
class Output:
    """When a run stops and what it writes. Probes, wrenches and /clock go out at ``output_rate``;
    particle clouds at ``particle_rate`` (0 = none), on the output steps nearest that rate; the
    bodies' wrenches, poses and twists also at ``wrench_rate`` (0 = not), on topics of their own."""

    end_time: float = 1.0  # [s] simulated
    output_rate: float = 100.0  # [Hz] simulated (the thesis's DamBreak 1 rate)
    particle_rate: float = 10.0  # [Hz] simulated
    # [Hz] simulated: each body's wrench, pose and twist alone, the wrench the mean over the steps
    # since the last (a controller's rate); 0 = with the outputs only
    wrench_rate: float = 0.0
    # a recording's MCAP chunk compression: zstd is what `ros2 bag record -s mcap` writes by default,
    # lz4 is faster to write and larger, none the largest
    compression: str = "zstd"
    # what a message's stamp counts: simulated seconds from 0 (1970 in a viewer), or that time added
    # to the wall clock at the start of the run (UTC epoch), for tools that show dates
    stamps: str = "simulated"
    # [s] of wall clock between two checkpoints of a recorded gpusph-run (and one when it is stopped),
    # from which `gpusph-run --resume` continues; 0 = none
    checkpoint_interval: float = 600.0

    @property
    def particle_every(self) -> int:
        """Outputs between two particle clouds (0 = no clouds)."""
        return 0 if self.particle_rate == 0.0 else max(1, int(round(self.output_rate / self.particle_rate)))


OUTPUT_FIELDS = tuple(f.name for f in dataclasses.fields(Output))
REDUCTION_FIELDS = tuple(f.name for f in dataclasses.fields(Reduction))
RUN_KEYS = NUMERIC_FIELDS + OUTPUT_FIELDS + REDUCTION_FIELDS
_DEFAULTS = {**{f.name: f.default_factory() if f.default is dataclasses.MISSING else f.default
                for f in dataclasses.fields(SolverConfig) if f.name in NUMERIC_FIELDS},
             **{f.name: f.default for f in dataclasses.fields(Output)},
             **{f.name: f.default for f in dataclasses.fields(Reduction)}}


@dataclass
class RunConfig:
    """One run's settings: the solver configuration (validated, built once, with the scene's
    domain), the run settings that were named (``numerics``: what a layer set, for the record), the
    outputs and the reduction."""

    numerics: dict  # the SolverConfig fields some layer set
    output: Output
    reduction: Reduction = field(default_factory=Reduction)
    solver: SolverConfig = None

    def as_dict(self) -> dict:
        return {**self.numerics, **dataclasses.asdict(self.output), **dataclasses.asdict(self.reduction)}


def run_config_names() -> list:
    return shipped("runs")


def read_run_file(name_or_path) -> dict:
    """A run configuration file: a path, or a name from config/runs."""
    path, _, data = read_yaml("runs", name_or_path, "run_config", "run configuration")
    data = {} if data is None else data
    if not isinstance(data, dict):
        raise ConfigError("run_config", str(path), "a YAML mapping of run settings")
    return data


def parse_set(item: str) -> tuple:
    """``key=value`` with the value read as YAML."""
    key, sep, value = item.partition("=")
    if not sep or not key.strip():
        raise ConfigError("--set", item, "key=value, e.g. dx=0.02 or kernel=quadratic")
    return key.strip(), yaml_input.value(value)


def _coerce(key, value):
    default = _DEFAULTS[key]
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ConfigError(key, value, "true or false")
    elif isinstance(default, int):
        if isinstance(value, float) and value.is_integer():
            value = int(value)  # 1e6
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(key, value, "an integer")
    elif isinstance(default, float):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(key, value, "a number")
        value = float(value)
    elif isinstance(default, str) and isinstance(value, bool):
        value = "on" if value else "off"  # YAML 1.1 read `step_graph=off` as false; the choices check it
    elif isinstance(default, str) and not isinstance(value, str):
        raise ConfigError(key, value, "a name (string)")
    return value


def check_output(output: Output) -> Output:
    """``output``, or ConfigError naming the first field out of its range or choices (a setting, or
    what a state file says a run's outputs were)."""
    for key in ("end_time", "output_rate", "particle_rate", "wrench_rate", "checkpoint_interval"):
        value = getattr(output, key)
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            raise ConfigError(key, value, "a number")
    if not (math.isfinite(output.end_time) and MIN_END_TIME <= output.end_time <= MAX_END_TIME):
        raise ConfigError("end_time", output.end_time, f"a time in [{MIN_END_TIME:g}, {MAX_END_TIME:g}] s")
    if not (math.isfinite(output.output_rate) and MIN_OUTPUT_RATE <= output.output_rate <= MAX_OUTPUT_RATE):
        raise ConfigError("output_rate", output.output_rate, f"a rate in [{MIN_OUTPUT_RATE:g}, {MAX_OUTPUT_RATE:g}] Hz")
    # outputs fall at k / output_rate and a run stops at the last one at or before end_time: a shorter
    # end_time ran no step and reported "completed: 0 steps, t = 0 s"
    if output.end_time * output.output_rate < 1.0 - 1.0e-9:
        raise ConfigError("end_time", output.end_time, f"at least one output interval, 1 / output_rate = "
                                                       f"{1.0 / output.output_rate:g} s (or a higher output_rate)")
    rate = output.particle_rate
    if not (math.isfinite(rate) and (rate == 0.0 or MIN_OUTPUT_RATE <= rate <= output.output_rate)):
        raise ConfigError("particle_rate", rate, f"0 (no particle clouds) or a rate in [{MIN_OUTPUT_RATE:g}, "
                                                 f"output_rate = {output.output_rate:g}] Hz")
    rate = output.wrench_rate
    if not (math.isfinite(rate) and (rate == 0.0 or MIN_OUTPUT_RATE <= rate <= MAX_OUTPUT_RATE)):
        raise ConfigError("wrench_rate", rate, f"0 (the bodies' messages with the outputs only) or a rate in "
                                               f"[{MIN_OUTPUT_RATE:g}, {MAX_OUTPUT_RATE:g}] Hz")
    if not (math.isfinite(output.checkpoint_interval) and 0.0 <= output.checkpoint_interval <= MAX_END_TIME):
        raise ConfigError("checkpoint_interval", output.checkpoint_interval,
                          f"a wall time in [0, {MAX_END_TIME:g}] s (0: no checkpoints)")
    for key, choices in (("compression", COMPRESSIONS), ("stamps", STAMPS)):
        if getattr(output, key) not in choices:
            raise ConfigError(key, getattr(output, key), "one of " + ", ".join(choices))
    return output


def resolve(scene: Scene, files=(), sets=(), **overrides) -> RunConfig:
    """The run configuration of ``scene``: its run section, then ``files``, then ``sets``
    (``key=value`` strings), then keyword ``overrides``."""
    layers = [scene.run_settings] + [read_run_file(f) for f in files] + [dict(parse_set(s) for s in sets), overrides]
    merged = {}
    for layer in layers:
        for key, value in layer.items():
            if key in SCENE_FIELDS:
                raise ConfigError(key, value, "a run setting (this one is set by the scene); the settings are "
                                  + ", ".join(RUN_KEYS))
            if key not in RUN_KEYS:
                raise unknown_key("", key, RUN_KEYS, "run_config", noun="settings")
            merged[key] = _coerce(key, value)
    output = Output(**{k: merged.pop(k) for k in OUTPUT_FIELDS if k in merged})
    check_output(output)
    reduction = Reduction(**{k: merged.pop(k) for k in REDUCTION_FIELDS if k in merged}).validate()
    numerics = {k: merged[k] for k in NUMERIC_FIELDS if k in merged}
    cfg = SolverConfig(dim=scene.dim, gravity=scene.gravity, depth=scene.depth, periodic=scene.periodic,
                       **numerics).validate()
    apply(scene, reduction, output.end_time, cfg.dx, cfg.hdx)  # a reduction the scene does not allow fails here
    return RunConfig(numerics=numerics, output=output, reduction=reduction, solver=cfg)
