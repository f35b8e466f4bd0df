"""Reading a recording back: the run's metadata and every measurement topic as time series.

Reads the MCAP file as a stream, record by record, so that a file cut short by a killed run
yields every message up to its last complete chunk. Particle clouds are kept as raw bytes and
decoded on request.
"""
import importlib
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml
from mcap.exceptions import McapError
from mcap.records import Channel, Message, Metadata, Schema
from rclpy.serialization import deserialize_message

from ..output.recording import ChunkTooLarge, bag_files, read_records


def mcap_files(path) -> list:
    """The .mcap files of a bag directory in their order (a resumed run adds <name>_1, ...), or
    the file itself."""
    path = Path(path)
    if path.is_file():
        return [path]
    files = bag_files(path)
    if not files:
        raise FileNotFoundError(f"{path}: no .mcap file here; expected a recording made by gpusph-run or sim_node")
    return files


def message_class(type_name: str):
    package, _, name = type_name.partition("/msg/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


@dataclass
class Recording:
    metadata: dict = field(default_factory=dict)  # the run's description, decoded YAML where it is YAML
    result: dict = field(default_factory=dict)  # status, wall time, ... (absent if the run was killed)
    types: dict = field(default_factory=dict)  # topic -> pkg/msg/Type
    series: dict = field(default_factory=dict)  # topic -> {"t": array, ...} for the small messages
    clouds: list = field(default_factory=list)  # (t, raw CDR bytes) of the particle clouds
    clock: list = field(default_factory=list)  # the /clock times
    complete: bool = True  # False when the file ended mid-record (a killed run)

    def topic(self, suffix: str) -> dict:
        """The series of the topic ending in ``suffix`` (e.g. 'probes/velocity')."""
        for name, values in self.series.items():
            if name.endswith("/" + suffix.lstrip("/")):
                return values
        raise KeyError(f"no topic ending in {suffix!r}; the recording has " + ", ".join(sorted(self.series)))

    def cloud(self, k: int):
        """Particle cloud ``k`` as a PointCloud2 message."""
        from sensor_msgs.msg import PointCloud2
        return deserialize_message(self.clouds[k][1], PointCloud2)


# the measurement types, read into series; the latched description, markers and frames are not
# measurements (and tf2_msgs may be missing where the recording is read)
MEASURED = ("geometry_msgs/msg/Vector3Stamped", "geometry_msgs/msg/PointStamped", "geometry_msgs/msg/WrenchStamped",
            "sensor_msgs/msg/FluidPressure", "geometry_msgs/msg/PoseStamped", "nav_msgs/msg/Odometry")


def _values(msg) -> dict:
    """The numbers a measurement message carries."""
    kind = type(msg).__name__
    if kind == "Vector3Stamped":
        return {"v": (msg.vector.x, msg.vector.y, msg.vector.z)}
    if kind == "PointStamped":
        return {"v": (msg.point.x, msg.point.y, msg.point.z)}
    if kind == "WrenchStamped":
        f, m = msg.wrench.force, msg.wrench.torque
        return {"force": (f.x, f.y, f.z), "torque": (m.x, m.y, m.z)}
    if kind == "FluidPressure":
        return {"v": msg.fluid_pressure}
    if kind in ("PoseStamped", "Odometry"):
        pose = msg.pose if kind == "PoseStamped" else msg.pose.pose
        p, q = pose.position, pose.orientation
        out = {"position": (p.x, p.y, p.z), "orientation": (q.x, q.y, q.z, q.w)}
        if kind == "Odometry":  # the twist in the body's own frame
            v, w = msg.twist.twist.linear, msg.twist.twist.angular
            out |= {"linear": (v.x, v.y, v.z), "angular": (w.x, w.y, w.z)}
        return out
    return {}


def _read_file(file, rec: Recording, rows: dict):
    """Read one MCAP file's records into ``rec`` and ``rows`` (topic -> [(t, values)])."""
    schemas, channels = {}, {}
    with open(file, "rb") as stream:
        try:
            for record in read_records(stream):
                if isinstance(record, Schema):
                    schemas[record.id] = record.name
                elif isinstance(record, Channel):
                    channels[record.id] = (record.topic, schemas[record.schema_id])
                    rec.types[record.topic] = schemas[record.schema_id]
                elif isinstance(record, Metadata):
                    if record.name == "gpusph_ros.result":
                        rec.result = dict(record.metadata)  # a later file's (a resumed run's) wins
                    else:
                        rec.metadata.update(record.metadata)
                elif isinstance(record, Message):
                    topic, type_name = channels[record.channel_id]
                    # simulated time: a run stamped with the wall clock says from when (written first)
                    t = (record.log_time - int(rec.metadata.get("time_origin_ns", 0))) * 1e-9
                    if type_name == "sensor_msgs/msg/PointCloud2":
                        rec.clouds.append((t, record.data))
                    elif type_name == "rosgraph_msgs/msg/Clock":
                        rec.clock.append(t)
                    elif type_name in MEASURED:
                        msg = deserialize_message(record.data, message_class(type_name))
                        rows.setdefault(topic, []).append((t, _values(msg)))
        except (McapError, EOFError, ValueError, KeyError, IndexError, struct.error) as err:
            if not schemas and not rec.metadata:  # nothing of a recording before the error
                raise ValueError(f"{file}: not a recording made by gpusph-run or sim_node (no MCAP records: "
                                 f"{type(err).__name__})") from None
            rec.complete = False
            rec.metadata.setdefault("read_error", f"{file.name}: {err}" if isinstance(err, ChunkTooLarge) else
                                    f"the file ends mid-record ({type(err).__name__}): a killed run")


def read(path) -> Recording:
    """Every file of the recording at ``path``, in order: a resumed run's files continue the first."""
    rec = Recording()
    rows = {}
    for file in mcap_files(path):
        _read_file(file, rec, rows)
    for key in ("run_config", "versions", "bodies"):
        if key in rec.metadata:
            rec.metadata[key] = yaml.safe_load(rec.metadata[key])
    for topic, items in rows.items():
        series = {"t": np.array([t for t, _ in items])}
        for name in items[0][1]:
            series[name] = np.array([v[name] for _, v in items], dtype=np.float64)
        rec.series[topic] = series
    return rec
