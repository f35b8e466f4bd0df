"""MCAP recordings shaped like ``ros2 bag record -s mcap``: a bag directory holding
``<name>_0.mcap`` and ``metadata.yaml`` (rosbag2 format version 9, Jazzy's).

The MCAP file has profile ``ros2``; one ``ros2msg`` schema per message type with the full
definition text from the installed message packages (``msgdefs``); ``cdr`` channels whose
metadata carries ``offered_qos_profiles`` (YAML, as rosbag2 writes it) and ``topic_type_hash``;
messages serialised by ``rclpy.serialization`` (the bytes a publisher sends), logged at their
simulated stamp. A metadata record ``gpusph_ros`` holds the scene, the resolved run
configuration, versions and device, written first; ``gpusph_ros.result`` (wall time, steps,
status) is written when the recording closes.

The file is chunked and flushed after each chunk, so a killed run leaves every complete chunk
readable by a streaming MCAP reader (``analysis.bag`` reads such files); ``metadata.yaml`` is
written when the bag opens and rewritten with the final counts when it closes.
"""
from importlib.metadata import version
from pathlib import Path

import yaml
from mcap.writer import CompressionType, Writer
from rclpy.serialization import serialize_message

from . import msgdefs

CHUNK_SIZE = 1 << 20
_INFINITE = {"sec": 9223372036, "nsec": 854775807}  # rmw's "infinite" duration


def qos_yaml(reliable: bool = True, depth: int = 10, transient_local: bool = False) -> str:
    """An offered_qos_profiles entry in the form rosbag2 (Jazzy, metadata version 9) writes."""
    profile = {"history": "keep_last", "depth": depth, "reliability": "reliable" if reliable else "best_effort",
               "durability": "transient_local" if transient_local else "volatile", "deadline": dict(_INFINITE),
               "lifespan": dict(_INFINITE), "liveliness": "automatic",
               "liveliness_lease_duration": dict(_INFINITE), "avoid_ros_namespace_conventions": False}
    return yaml.safe_dump([profile], sort_keys=False)


class _FlushingFile:
    """The stream the MCAP writer writes into, passed to the OS at each write: the writer
    writes a finished chunk at a time, so a kill loses at most the open chunk. (Not an
    io.RawIOBase, which the writer would wrap in a buffer of its own.)"""

    def __init__(self, path: Path):
        self._file = open(path, "wb")

    def write(self, data):
        n = self._file.write(data)
        self._file.flush()
        return n

    def tell(self):
        return self._file.tell()

    def flush(self):
        self._file.flush()

    def close(self):
        self._file.close()


class BagRecorder:
    """Writes (topic, message, time) into a new bag directory ``path``."""

    def __init__(self, path, metadata: dict, chunk_size: int = CHUNK_SIZE):
        self.path = Path(path)
        if self.path.exists() and any(self.path.iterdir()):
            raise FileExistsError(f"record_dir: {self.path} exists and is not empty; choose a new directory")
        self.path.mkdir(parents=True, exist_ok=True)
        self.file_name = f"{self.path.name}_0.mcap"
        self._stream = _FlushingFile(self.path / self.file_name)
        self._writer = Writer(self._stream, chunk_size=chunk_size, compression=CompressionType.NONE)
        self._writer.start(profile="ros2", library=f"gpusph_ros {version('gpusph_ros')}; mcap {version('mcap')}")
        self._writer.add_metadata("gpusph_ros", {k: str(v) for k, v in metadata.items()})
        self._schemas, self._channels, self._topics = {}, {}, {}
        self.count, self.first, self.last = 0, None, None
        self.closed = False
        self._write_metadata_yaml()

    def add_topic(self, topic: str, type_name: str, qos: str):
        """Declare a topic before its first message (its offered QoS goes into the bag)."""
        if type_name not in self._schemas:
            self._schemas[type_name] = self._writer.register_schema(
                name=type_name, encoding="ros2msg", data=msgdefs.full_text(type_name).encode())
        self._channels[topic] = self._writer.register_channel(
            topic=topic, message_encoding="cdr", schema_id=self._schemas[type_name],
            metadata={"offered_qos_profiles": qos, "topic_type_hash": msgdefs.type_hash(type_name)})
        self._topics[topic] = {"type": type_name, "qos": qos, "count": 0}

    def write(self, topic: str, message, t: float, data: bytes = None):
        """Record ``message`` on ``topic`` at simulated time ``t`` [s]; ``data`` is its CDR
        serialisation when the caller already has it (a publisher's bytes)."""
        if topic not in self._channels:
            self.add_topic(topic, msgdefs.type_name_of(type(message)), qos_yaml())
        ns = int(round(t * 1e9))
        entry = self._topics[topic]
        self._writer.add_message(self._channels[topic], log_time=ns, publish_time=ns,
                                 data=serialize_message(message) if data is None else data,
                                 sequence=entry["count"])
        entry["count"] += 1
        self.count += 1
        self.first = ns if self.first is None else min(self.first, ns)
        self.last = ns if self.last is None else max(self.last, ns)

    def close(self, result: dict = None):
        """Finish the file (summary, footer) and write the final metadata.yaml."""
        if self.closed:
            return
        if result:
            self._writer.add_metadata("gpusph_ros.result", {k: str(v) for k, v in result.items()})
        self._writer.finish()
        self._stream.close()
        self.closed = True
        self._write_metadata_yaml()

    def _write_metadata_yaml(self):
        start = self.first or 0
        duration = (self.last - self.first) if self.count else 0
        info = {
            "version": 9,
            "storage_identifier": "mcap",
            "duration": {"nanoseconds": duration},
            "starting_time": {"nanoseconds_since_epoch": start},
            "message_count": self.count,
            "topics_with_message_count": [
                {"topic_metadata": {"name": topic, "type": e["type"], "serialization_format": "cdr",
                                    # version 9 keeps the profiles as YAML here, as a string in the MCAP channel
                                    "offered_qos_profiles": yaml.safe_load(e["qos"]),
                                    "type_description_hash": msgdefs.type_hash(e["type"])},
                 "message_count": e["count"]}
                for topic, e in self._topics.items()],
            "compression_format": "",
            "compression_mode": "",
            "relative_file_paths": [self.file_name],
            "files": [{"path": self.file_name, "starting_time": {"nanoseconds_since_epoch": start},
                       "duration": {"nanoseconds": duration}, "message_count": self.count}],
            "custom_data": {},
            "ros_distro": "jazzy",
        }
        tmp = self.path / "metadata.yaml.tmp"
        tmp.write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}, sort_keys=False))
        tmp.replace(self.path / "metadata.yaml")
