"""A study file: which runs a convergence study makes, and where its results go.

    name: thesis_dambreak1_coarse
    scenes: [dambreak1_thesis]
    scenarios:                 # named run configurations: a file in config/runs, or a mapping
      scenario1: thesis_scenario1
      defaults: {}
    grid:                      # every combination of these run settings
      dx: [0.05, 0.04, 0.03]
    set: {end_time: 3.0}       # fixed run settings of every case
    metrics: [peak_velocity, peak_force_0p06m]
    out: runs/studies/thesis_dambreak1_coarse   # relative to the working directory
    workers: 2                 # optional: Dask workers of the local cluster (default: one per core)

Cases are scenes x scenarios x the grid's product, each checked (scene, run settings) before any
runs, with a name that is also its folder: ``dambreak1_thesis-scenario1-dx=0.04``.
"""
import dataclasses
import itertools
from dataclasses import dataclass
from pathlib import Path

from ..analysis.report import LABELS
from ..scenes.schema import _mapping, load_scene, read_yaml, shipped
from ..scenes.settings import read_run_file, resolve
from ..sph.config import ConfigError

KEYS = ("name", "description", "scenes", "scenarios", "grid", "set", "metrics", "out", "workers")


@dataclass(frozen=True)
class Case:
    name: str
    scene: str
    scenario: str
    settings: dict  # run settings: the scenario's, then `set`, then this grid point's
    grid: dict  # this grid point alone (the study's variables)


@dataclass
class Study:
    name: str
    description: str
    scenes: list
    scenarios: dict  # name -> run settings
    grid: dict  # key -> list of values
    fixed: dict
    metrics: list
    out: Path
    workers: int = 0

    def cases(self) -> list:
        keys = list(self.grid)
        out = []
        for scene, (scenario, settings) in itertools.product(self.scenes, self.scenarios.items()):
            for values in itertools.product(*(self.grid[k] for k in keys)):
                point = dict(zip(keys, values))
                tag = "-".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in point.items())
                out.append(Case(name=f"{scene}-{scenario}" + (f"-{tag}" if tag else ""), scene=scene,
                                scenario=scenario, settings={**settings, **self.fixed, **point}, grid=point))
        return out


def study_names() -> list:
    return shipped("studies")


def load_study(name_or_path) -> Study:
    """A study from a shipped name (config/studies) or a YAML path; every case is checked."""
    path, _, data = read_yaml("studies", name_or_path, "study", "study")
    item = _mapping("", data, KEYS, required=("scenes", "scenarios", "metrics"), whole="study")
    scenes = item["scenes"]
    if not isinstance(scenes, list) or not scenes:
        raise ConfigError("scenes", scenes, "a list of scene names or paths")
    scenarios = {}
    if not isinstance(item["scenarios"], dict) or not item["scenarios"]:
        raise ConfigError("scenarios", item["scenarios"], "a mapping of scenario name to a run configuration "
                                                           "(a name in config/runs, a path, or a mapping)")
    for name, spec in item["scenarios"].items():
        scenarios[str(name)] = read_run_file(spec) if isinstance(spec, str) else (spec or {})
        if not isinstance(scenarios[str(name)], dict):
            raise ConfigError(f"scenarios.{name}", spec, "a run configuration name, path or mapping")
    grid = item.get("grid") or {}
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise ConfigError(f"grid.{key}", values, "a non-empty list of values")
    metrics = item["metrics"]
    if not isinstance(metrics, list) or not all(m in LABELS for m in metrics):
        raise ConfigError("metrics", metrics, "a list of: " + ", ".join(LABELS))
    workers = item.get("workers", 0)
    if not isinstance(workers, int) or workers < 0:
        raise ConfigError("workers", workers, "an integer >= 0 (0 = one per core, or per GPU)")
    study = Study(name=item.get("name", path.stem), description=item.get("description", ""), scenes=scenes,
                  scenarios=scenarios, grid=grid, fixed=item.get("set") or {}, metrics=metrics,
                  out=Path(item.get("out", f"runs/studies/{path.stem}")), workers=workers)
    loaded = {name: load_scene(name) for name in scenes}
    for case in study.cases():
        try:
            resolve(loaded[case.scene], **case.settings)
        except ConfigError as err:
            raise ConfigError(f"case {case.name}: {err.field}", err.value, err.allowed) from None
    return study


def with_out(study: Study, out) -> Study:
    return dataclasses.replace(study, out=Path(out))
