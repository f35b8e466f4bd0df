"""MCAP recordings shaped like ``ros2 bag record -s mcap``: a bag directory holding
``<name>_0.mcap`` and ``metadata.yaml`` (rosbag2 format version 9, Jazzy's).

The MCAP file has profile ``ros2``; one ``ros2msg`` schema per message type with the full
definition text from the installed message packages (``msgdefs``); ``cdr`` channels whose
metadata carries ``offered_qos_profiles`` (YAML, as rosbag2 writes it) and ``topic_type_hash``;
messages serialised by ``rclpy.serialization`` (the bytes a publisher sends), logged at their
simulated stamp. A metadata record ``gpusph_ros`` holds the scene, the resolved run
configuration, versions and device, written first; ``gpusph_ros.result`` (wall time, steps,
status) is written when the recording closes.

The file is chunked; a chunk is closed and handed to the OS when it reaches CHUNK_SIZE, when
FLUSH_EVERY seconds of wall clock have passed since the last one (``write``, and ``flush``, which
the node calls once a second even while paused) and when the recording stops; ``metadata.yaml``
is rewritten with the counts each time. A killed run (SIGKILL, an OOM kill, power loss) so loses
at most the last FLUSH_EVERY seconds: its file lacks only the MCAP summary and footer, which
``repair`` (``gpusph-analyze --repair BAG``, what ``ros2 bag reindex`` is to rosbag2) rebuilds from
the complete chunks, so that rosbags and the ``mcap`` tools open it.
"""
import dataclasses
import errno
import shutil
import time
from importlib.metadata import version
from pathlib import Path

import lz4.frame
import yaml
import zstandard
from mcap.records import Channel, Chunk, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import MCAP0_MAGIC, CompressionType, Writer
from rclpy.serialization import serialize_message

from . import msgdefs

CHUNK_SIZE = 1 << 20
COMPRESSION = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}
FLUSH_EVERY = 1.0  # [s] of wall clock: the most a killed recording loses
# A recording never fills its disk: before each message it checks that the open chunk, the message,
# the summary and footer a clean close writes, and SPACE_MARGIN still fit, and otherwise closes
# itself, whole and readable, with everything written so far (a write that failed on a full disk
# left a file that --repair, which needs as much space again, could not mend)
SPACE_MARGIN = 256 * 1024  # [bytes] for metadata.yaml and what the estimate below misses
MESSAGE_OVERHEAD = 64  # [bytes] a message record's header and its message index entry


# A chunk may inflate to MAX_CHUNK_RATIO times its compressed bytes, or to MIN_CHUNK_CAP: this
# writer's chunks hold CHUNK_SIZE of small messages, or one larger message (a particle cloud: float
# fields, which zstd and lz4 shrink a few times, not tens); mcap itself allows 4 GiB, and a 16 kB
# chunk of zeros that inflated to 512 MiB cost a reader 582 MB
MAX_CHUNK_RATIO = 64
MIN_CHUNK_CAP = 16 * CHUNK_SIZE


class DiskFull(OSError):
    """The recording closed itself: its disk has no room for more."""


class ChunkTooLarge(ValueError):
    """A chunk would inflate past what a recording of this package holds (MAX_CHUNK_RATIO)."""


def _inflated(chunk: Chunk) -> bytes:
    """A chunk's records as bytes, decompressed no further than its cap (ChunkTooLarge past it)."""
    cap = max(MIN_CHUNK_CAP, MAX_CHUNK_RATIO * len(chunk.data))
    if chunk.uncompressed_size > cap:
        raise ChunkTooLarge(f"a chunk says it inflates to {chunk.uncompressed_size:,} bytes from "
                            f"{len(chunk.data):,}, more than {cap:,}: not a recording of gpusph_ros")
    if chunk.compression == "zstd":
        data = zstandard.ZstdDecompressor().stream_reader(chunk.data).read(cap + 1)
    elif chunk.compression == "lz4":
        data = lz4.frame.LZ4FrameDecompressor().decompress(chunk.data, max_length=cap + 1)
    elif chunk.compression == "":
        data = chunk.data
    else:
        raise ValueError(f"a chunk compressed with {chunk.compression!r}; expected zstd, lz4 or none")
    if len(data) != chunk.uncompressed_size:
        raise ChunkTooLarge(f"a chunk inflates to {len(data):,}{'+' if len(data) > cap else ''} bytes where it says "
                            f"{chunk.uncompressed_size:,}: damaged, or not a recording of gpusph_ros")
    return data


def read_records(stream):
    """An MCAP stream's records in order, each chunk opened within its cap (``_inflated``): what
    mcap's StreamReader gives, without its unbounded decompression."""
    for record in StreamReader(stream, emit_chunks=True).records:
        if isinstance(record, Chunk):
            yield from breakup_chunk(dataclasses.replace(record, compression="", data=_inflated(record)))
        else:
            yield record

    def __init__(self, message: str):
        super().__init__(errno.ENOSPC, message)


def free_bytes(path) -> int:
    """Bytes free to this process on the file system of ``path``."""
    return shutil.disk_usage(path).free
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
    """Writes (topic, message, time) into a new bag directory ``path``, its chunks compressed with
    ``compression`` (COMPRESSION), each message logged at ``time_origin_ns`` plus its time."""

    def __init__(self, path, metadata: dict, chunk_size: int = CHUNK_SIZE, compression: str = "zstd",
                 time_origin_ns: int = 0, earlier: list = None):
        """``earlier``: the bag's files so far (``file_entries``) when a resumed run continues it in
        a file of its own, ``<name>_<k>.mcap``; else the folder must be new or empty."""
        self.path = Path(path)
        self._earlier = list(earlier or [])
        if not self._earlier and self.path.exists() and any(self.path.iterdir()):
            raise FileExistsError(f"record_dir: {self.path} exists and is not empty; choose a new directory")
        meta = {k: str(v) for k, v in metadata.items()}
        existing = next(q for q in [self.path, *self.path.parents] if q.exists())
        need = 2 * SPACE_MARGIN + sum(len(k) + len(v) for k, v in meta.items())
        free = free_bytes(existing)
        if free < need:  # refused before anything is made: no empty folder, no 0-byte file
            raise DiskFull(f"record_dir: {existing} has {free:,} bytes free; a recording needs "
                           f"at least {need:,} to start")
        created = not self.path.exists()
        self.path.mkdir(parents=True, exist_ok=True)
        self.file_name = f"{self.path.name}_{len(self._earlier)}.mcap"
        self._chunk_size = chunk_size
        self._origin = int(time_origin_ns)
        self._pending = 0  # bytes of messages in the open chunk (its compressed size is at most that)
        self._chunks = 0
        self._summary_fixed = 2048 + sum(len(k) + len(v) + 32 for k, v in meta.items())
        try:
            self._stream = _FlushingFile(self.path / self.file_name)
            self._writer = Writer(self._stream, chunk_size=chunk_size, compression=COMPRESSION[compression])
            self._writer.start(profile="ros2", library=f"gpusph_ros {version('gpusph_ros')}; mcap {version('mcap')}")
            self._writer.add_metadata("gpusph_ros", meta)
            self._schemas, self._channels, self._topics = {}, {}, {}
            self.count, self.first, self.last = 0, None, None
            self.closed = False
            self._flushed = time.monotonic()
            self._write_metadata_yaml()
        except OSError:
            if created:
                shutil.rmtree(self.path, ignore_errors=True)
            raise

    def add_topic(self, topic: str, type_name: str, qos: str):
        """Declare a topic before its first message (its offered QoS goes into the bag)."""
        if type_name not in self._schemas:
            text = msgdefs.full_text(type_name).encode()
            self._schemas[type_name] = self._writer.register_schema(name=type_name, encoding="ros2msg", data=text)
            self._summary_fixed += len(text) + 64
        self._channels[topic] = self._writer.register_channel(
            topic=topic, message_encoding="cdr", schema_id=self._schemas[type_name],
            metadata={"offered_qos_profiles": qos, "topic_type_hash": msgdefs.type_hash(type_name)})
        self._topics[topic] = {"type": type_name, "qos": qos, "count": 0}
        self._summary_fixed += 2 * len(topic) + len(qos) + 160  # its channel record and metadata.yaml entry

    def write(self, topic: str, message, t: float, data: bytes = None):
        """Record ``message`` on ``topic`` at simulated time ``t`` [s]; ``data`` is its CDR
        serialisation when the caller already has it (a publisher's bytes)."""
        if self.closed:
            raise DiskFull(f"{self.path}: the recording was closed (its disk is full)")
        if topic not in self._channels:
            self.add_topic(topic, msgdefs.type_name_of(type(message)), qos_yaml())
        ns = self._origin + int(round(t * 1e9))
        entry = self._topics[topic]
        data = serialize_message(message) if data is None else data
        need = self._pending + len(data) + MESSAGE_OVERHEAD + self._summary_bytes() + SPACE_MARGIN
        if free_bytes(self.path) < need:
            self.close({"status": f"stopped: the disk is full after {self.count} messages"})
            raise DiskFull(f"{self.path}: the disk is full: the recording is closed, readable, with its "
                           f"{self.count} messages up to t = {(self.last or 0) * 1e-9:.6g} s")
        self._writer.add_message(self._channels[topic], log_time=ns, publish_time=ns, data=data,
                                 sequence=entry["count"])
        self._pending += len(data) + MESSAGE_OVERHEAD
        if self._pending >= self._chunk_size:  # the writer closed the chunk
            self._pending, self._chunks = 0, self._chunks + 1
        entry["count"] += 1
        self.count += 1
        self.first = ns if self.first is None else min(self.first, ns)
        self.last = ns if self.last is None else max(self.last, ns)
        self.flush(due_only=True)

    def flush(self, due_only: bool = False):
        """Close the open chunk and rewrite metadata.yaml (with ``due_only``: only once FLUSH_EVERY
        seconds have passed since the last flush)."""
        now = time.monotonic()
        if self.closed or (due_only and now - self._flushed < FLUSH_EVERY):
            return
        self._flushed = now
        self._writer.flush()
        if self._pending:
            self._pending, self._chunks = 0, self._chunks + 1
        self._write_metadata_yaml()

    def _summary_bytes(self) -> int:
        """An upper estimate of what a clean close writes: schemas, channels, the chunk indexes
        (one entry per channel each), statistics, the metadata index and the footer."""
        return self._summary_fixed + (self._chunks + 1) * (128 + 24 * len(self._channels))

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

    def entry(self) -> dict:
        """This file's entry for metadata.yaml (as ``file_entries`` gives an earlier file's)."""
        return {"path": self.file_name, "topics": self._topics, "count": self.count, "first": self.first,
                "last": self.last}

    def _write_metadata_yaml(self):
        write_metadata_yaml(self.path, [*self._earlier, self.entry()])


def bag_files(path) -> list:
    """The MCAP files of the bag directory ``path`` in their order (<name>_0, _1, ...)."""
    def index(p):
        tail = p.stem.rpartition("_")[2]
        return (int(tail) if tail.isdigit() else -1, p.name)
    return sorted(Path(path).glob("*.mcap"), key=index)


def file_entries(path, upto: int = None) -> list:
    """metadata.yaml entries of the bag's MCAP files (the first ``upto``; all whole), read from
    their summaries."""
    from mcap.reader import make_reader

    out = []
    for file in bag_files(path)[:upto]:
        with open(file, "rb") as f:
            summary = make_reader(f).get_summary()
        stats = summary.statistics
        topics = {}
        for cid, channel in summary.channels.items():
            topics[channel.topic] = {"type": summary.schemas[channel.schema_id].name,
                                     "qos": channel.metadata.get("offered_qos_profiles", qos_yaml()),
                                     "count": stats.channel_message_counts.get(cid, 0)}
        count = stats.message_count
        out.append({"path": file.name, "topics": topics, "count": count,
                    "first": stats.message_start_time if count else None,
                    "last": stats.message_end_time if count else None})
    return out


def write_metadata_yaml(path: Path, files: list):
    """rosbag2's metadata.yaml for the bag ``path`` and its MCAP ``files``, each {path, topics:
    name -> {type, qos (YAML text), count}, count, first, last (the earliest and latest log times,
    ns)}."""
    topics = {}
    for f in files:
        for topic, e in f["topics"].items():
            topics.setdefault(topic, {**e, "count": 0})["count"] += e["count"]
    count = sum(f["count"] for f in files)
    firsts = [f["first"] for f in files if f["count"]]
    lasts = [f["last"] for f in files if f["count"]]
    start = min(firsts) if firsts else 0
    duration = (max(lasts) - start) if firsts else 0

    def span(f):
        return {"starting_time": {"nanoseconds_since_epoch": f["first"] or 0},
                "duration": {"nanoseconds": (f["last"] - f["first"]) if f["count"] else 0}}

    info = {
        "version": 9,
        "storage_identifier": "mcap",
        "duration": {"nanoseconds": duration},
        "starting_time": {"nanoseconds_since_epoch": start},
        "message_count": count,
        "topics_with_message_count": [
            {"topic_metadata": {"name": topic, "type": e["type"], "serialization_format": "cdr",
                                # version 9 keeps the profiles as YAML here, as a string in the MCAP channel
                                "offered_qos_profiles": yaml.safe_load(e["qos"]),
                                "type_description_hash": msgdefs.type_hash(e["type"])},
             "message_count": e["count"]}
            for topic, e in topics.items()],
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [f["path"] for f in files],
        "files": [{"path": f["path"], **span(f), "message_count": f["count"]} for f in files],
        "custom_data": {},
        "ros_distro": "jazzy",
    }
    tmp = path / "metadata.yaml.tmp"
    tmp.write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}, sort_keys=False))
    tmp.replace(path / "metadata.yaml")


# a finished file ends with its footer record (opcode 0x02, 20 bytes) and the magic
_FOOTER = bytes([0x02]) + (20).to_bytes(8, "little")
_FOOTER_TAIL = len(_FOOTER) + 20 + len(MCAP0_MAGIC)


def is_whole(file) -> bool:
    """Whether an MCAP file was finished: it ends with a footer record and the magic (a file cut
    anywhere, even right after its opening magic, does not)."""
    file = Path(file)
    size = file.stat().st_size
    if size < len(MCAP0_MAGIC) + _FOOTER_TAIL:
        return False
    with open(file, "rb") as f:
        f.seek(size - _FOOTER_TAIL)
        tail = f.read()
    return tail.startswith(_FOOTER) and tail.endswith(MCAP0_MAGIC)


def unreadable(file) -> str:
    """What in an MCAP file, whole or not, cannot be read, with its byte offset; "" where every
    record reads. The records' framing (an opcode and a length each) is walked first, so that a
    length past the end of the file is named where it stands without reading it; then each record
    is parsed, its chunks opened within their caps."""
    file = Path(file)
    size = file.stat().st_size
    with open(file, "rb") as f:
        if f.read(len(MCAP0_MAGIC)) != MCAP0_MAGIC:
            return "it does not begin with the MCAP magic"
        offset = len(MCAP0_MAGIC)
        while offset < size - len(MCAP0_MAGIC):
            head = f.read(9)
            if len(head) < 9:
                return f"the record at byte {offset:,} is cut inside its opcode and length"
            length = int.from_bytes(head[1:], "little")
            if offset + 9 + length > size:
                return (f"the record at byte {offset:,} (opcode 0x{head[0]:02x}) declares {length:,} bytes, past the "
                        f"file's end at byte {size:,}")
            offset += 9 + length
            f.seek(offset)
        f.seek(0)
        try:
            for _ in read_records(f):
                pass
        except Exception as err:
            return f"a record before byte {f.tell():,} cannot be read: {type(err).__name__}: {err}"
    return ""


def _records(f):
    """The records of an MCAP stream up to where it is cut: a cut can fall anywhere, inside the
    magic, a record's header or a chunk, and the MCAP reader then raises whatever its parse meets
    (McapError, struct.error, EOFError, ...): everything before it is whole."""
    try:
        yield from read_records(f)
    except Exception:
        return


def whole_messages(file, before: int = None) -> tuple:
    """(messages, the last one's log time [ns] or None, those logged before ``before`` [ns]) that an
    MCAP file holds whole, cut or not."""
    count, last, earlier = 0, None, 0
    with open(file, "rb") as f:
        for record in _records(f):
            if isinstance(record, Message):
                count, last = count + 1, record.log_time if last is None else max(last, record.log_time)
                earlier += before is not None and record.log_time < before
    return count, last, earlier


def repair(path, compression: str = "zstd", keep: int = None) -> dict:
    """Rebuild a killed recording's MCAP summary and footer from its complete chunks, in place
    (the bag's last file; the cut file is kept beside it as ``<file>.cut``, its chunks written
    again with ``compression``; with ``keep``, whole or not, only its first ``keep`` messages, those
    a checkpoint counted), and its metadata.yaml. A file that ends whole but holds a record that cannot
    be read (``unreadable``) is repaired as a cut one, to the record before. Returns what was found:
    repaired (False for a whole file that reads, left as it is), messages and topics recovered, and
    the problem of a whole file that did not read ("" otherwise)."""
    path = Path(path)
    files = bag_files(path) if path.is_dir() else []
    if not files:
        raise FileNotFoundError(f"{path}: no .mcap file here; expected a bag directory")
    source = files[-1]
    problem = ""
    if keep is None and is_whole(source):
        # a footer says the writer finished, not that every record before it reads
        problem = unreadable(source)
        if not problem:
            return {"repaired": False, "file": str(source)}
    cut = source.with_name(source.name + ".cut")
    source.replace(cut)
    topics, count, first, last = {}, 0, None, None
    schemas, channels, result, started = {}, {}, False, False
    with open(cut, "rb") as f, open(source, "wb") as out:
        writer = Writer(out, chunk_size=CHUNK_SIZE, compression=COMPRESSION[compression])
        for record in _records(f):
            if isinstance(record, Header):
                writer.start(record.profile, record.library)
                started = True
            elif isinstance(record, Schema) and record.id not in schemas:
                schemas[record.id] = (writer.register_schema(record.name, record.encoding, record.data),
                                      record.name)
            elif isinstance(record, Channel) and record.id not in channels:
                if record.schema_id not in schemas:  # damaged past its cut: what follows is lost too
                    break
                sid, type_name = schemas[record.schema_id]
                channels[record.id] = (writer.register_channel(record.topic, record.message_encoding, sid,
                                                               record.metadata), record.topic)
                topics[record.topic] = {"type": type_name, "count": 0,
                                        "qos": record.metadata.get("offered_qos_profiles", qos_yaml())}
            elif isinstance(record, Metadata):
                result |= record.name == "gpusph_ros.result"
                writer.add_metadata(record.name, record.metadata)
            elif isinstance(record, Message):
                if (keep is not None and count >= keep) or record.channel_id not in channels:
                    break
                cid, topic = channels[record.channel_id]
                writer.add_message(cid, log_time=record.log_time, publish_time=record.publish_time,
                                   data=record.data, sequence=record.sequence)
                topics[topic]["count"] += 1
                count += 1
                first = record.log_time if first is None else min(first, record.log_time)
                last = record.log_time if last is None else max(last, record.log_time)
        if not started:  # cut inside its header: a file of its own kind, empty
            writer.start("ros2", f"gpusph_ros {version('gpusph_ros')} (repaired); mcap {version('mcap')}")
        if not result:
            writer.add_metadata("gpusph_ros.result", {"status": f"killed: repaired, {count} messages recovered"})
        writer.finish()
    write_metadata_yaml(path, [*file_entries(path, len(files) - 1), {"path": source.name, "topics": topics,
                                                                      "count": count, "first": first, "last": last}])
    return {"repaired": True, "file": str(source), "cut_file": str(cut), "messages": count,
            "topics": {name: e["count"] for name, e in topics.items()}, "problem": problem}

