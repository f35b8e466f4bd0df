"""A recording's simulated series beside the measured ones, on the recording's own clock, for the
tools ROS users replay bags in (``gpusph-analyze --export DIR``).

For each series the analysis compares (``report.analyse``) it writes ``DIR/<name>.csv`` (the
recording's time, the simulated value as the analysis reads it, the measurement interpolated at
the same time where it was measured) and, in the bag ``DIR/reference`` (rosbag2 + MCAP, stamped
as the recording is), the measured points on ``/reference/<source>/<name>`` with the message type
of the simulated topic, so that Foxglove or PlotJuggler draws one over the other. Where the
analysis moved a simulated curve to put its peak on the measured one (DamBreak 1: the experiment's
time origin is not known), the measurement is moved back by the same amount instead, and the CSV
says by how much. Measured points that fall before the recording's t = 0 are left out of the bag.
"""
import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from ..output import messages
from . import report
from .bag import read


@dataclass
class Series:
    name: str  # the file and topic name: force, velocity, sensor_1, H2, ...
    source: str  # the measurement's: yeh_petroff, lobovsky_2014
    simulated: str  # what the simulated values are, with their topic
    unit: str
    t: np.ndarray  # [s] the recording's time
    value: np.ndarray
    t_measured: np.ndarray  # [s] on the recording's clock
    measured: np.ndarray
    shift: float  # [s] added to the measurement's own times
    message: object  # value -> the reference message's builder, (t, value) -> message

    @property
    def topic(self) -> str:
        return f"/reference/{self.source}/{self.name}"


def _dambreak1(curves, scene) -> list:
    out = []
    shift = curves["shift"]
    t, u, exp = curves["velocity"]
    if exp:
        out.append(Series("velocity", "yeh_petroff", "x-velocity at the probe (probes/velocity, 0.04 s average)",
                          "m/s", t - shift["velocity"], u, exp[0] - shift["velocity"], exp[1], -shift["velocity"],
                          lambda ts, v: messages.vector(ts, (v, 0.0, 0.0))))
    forces, exp = curves["force"]
    if exp and "peak_force_body" in forces:
        tf, f = forces["peak_force_body"]
        moved = shift["peak_force_body"]
        out.append(Series("force", "yeh_petroff", "x-force on the obstruction's particles (bodies/<name>/wrench, "
                          "0.04 s average)", "N", tf - moved, f, exp[0] - moved, exp[1], -moved,
                          lambda ts, v: messages.wrench(ts, (v, 0.0, 0.0), (0.0, 0.0, 0.0))))
    return out


def _lobovsky(curves, scene) -> list:
    c = curves["lobovsky"]
    units = c["units"]
    tu, pu, depth = units["time"], units["pressure"], units["depth"]
    out = []
    for k, (t, p, exp) in c["pressure"].items():
        if exp:
            out.append(Series(f"sensor_{k}", "lobovsky_2014", f"wall pressure at sensor {k} (probes/sensor_{k})", "Pa",
                              t / tu, p * pu, np.asarray(exp[0]) / tu, np.asarray(exp[1]) * pu, 0.0,
                              lambda ts, v: messages.pressure(ts, v)))
    probes = scene.get("probes") or {}
    for gauge, (t, h, exp) in c["levels"].items():
        if exp:
            x = float((probes.get(gauge) or {}).get("position", [0.0])[0])
            out.append(Series(gauge, "lobovsky_2014", f"water level at {gauge} (probes/{gauge}, on z)", "m",
                              t / tu, h * depth, np.asarray(exp[0]) / tu, np.asarray(exp[1]) * depth, 0.0,
                              lambda ts, v, x=x: messages.point(ts, (x, 0.0, v))))
    return out


# each analysis case's measured time series (dambreak2's measurements are a mean and a profile)
EXPORTS = {"dambreak1": _dambreak1, "lobovsky": _lobovsky}


def series_of(path, data=None) -> list:
    """(the Series of the recording at ``path`` that have a measured counterpart, its metadata)."""
    rec = read(path)
    _, curves = report.analyse(path, data, rec)
    meta = rec.metadata
    scene = yaml.safe_load(meta.get("scene", "")) or {}
    make = EXPORTS.get(report.analysis_of(scene, meta.get("scene_name", scene.get("name", "?"))).get("case"))
    return (make(curves, scene) if make else []), meta


def write_csv(s: Series, out_dir: Path) -> Path:
    path = out_dir / f"{s.name}.csv"
    order = np.argsort(s.t_measured)
    tm, vm = s.t_measured[order], s.measured[order]
    inside = (s.t >= tm[0]) & (s.t <= tm[-1])
    measured = np.where(inside, np.interp(s.t, tm, vm), np.nan)
    with open(path, "w", newline="") as f:
        f.write(f"# simulated: {s.simulated}; measured: {s.source}, moved by {s.shift:+.4f} s onto the recording's "
                f"clock and interpolated at its times; unit {s.unit}\n")
        w = csv.writer(f)
        w.writerow(["time_s", f"simulated_{s.unit}", f"measured_{s.unit}"])
        for t, v, m in zip(s.t, s.value, measured):
            w.writerow([f"{t:.9g}", f"{v:.9g}", "" if np.isnan(m) else f"{m:.9g}"])
    return path


def export(path, out_dir, data=None) -> dict:
    """Write the CSVs and the reference bag of the recording at ``path`` into ``out_dir``; returns
    {"csv": [paths], "bag": path or None, "topics": {topic: messages}}."""
    from ..output.recording import BagRecorder

    series, meta = series_of(path, data)
    if not series:
        raise ValueError(f"{path}: its scene's analysis has no measured time series to export "
                         "(DamBreak 1 and Lobovsky have them)")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = [str(write_csv(s, out_dir)) for s in series]
    origin = int(meta.get("time_origin_ns", 0))
    bag = BagRecorder(out_dir / "reference", {"reference_of": str(path), "scene_name": meta.get("scene_name", "")},
                      time_origin_ns=origin)
    counts = {}
    points = sorted((t, k, v) for k, s in enumerate(series) for t, v in zip(s.t_measured, s.measured) if t >= 0.0)
    for t, k, v in points:  # in time order, as a recorder writes
        s = series[k]
        msg = s.message(t, float(v))
        if origin:
            messages.restamp(msg, t, origin)
        bag.write(s.topic, msg, t)
        counts[s.topic] = counts.get(s.topic, 0) + 1
    bag.close({"status": "completed"})
    return {"csv": written, "bag": str(bag.path), "topics": counts}
