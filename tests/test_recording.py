"""Recordings: the bag a run writes opens with rosbags and with mcap_ros2 (no project code),
carries ros2msg schemas whose RIHS01 hashes match the installed packages', decodes to the
solver's own arrays, and survives a kill up to its last complete chunk; SIGTERM closes it whole."""
import os
import signal
import subprocess
import sys
import time
from io import BytesIO
from pathlib import Path

import numpy as np
import pytest
import yaml
import zstandard
from mcap.data_stream import RecordBuilder
from mcap.reader import make_reader
from mcap.records import Chunk, Header
from mcap.stream_reader import StreamReader
from mcap.writer import MCAP0_MAGIC, CompressionType, Writer
from mcap_ros2.reader import read_ros2_messages
from rclpy.serialization import deserialize_message
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from gpusph_ros.analysis.bag import message_class, read
from gpusph_ros.output import msgdefs, recording
from gpusph_ros.runner import Run
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.scenes.settings import resolve
from gpusph_ros.sph.state import FLUID

pytestmark = pytest.mark.ros

REPO = Path(__file__).resolve().parents[1]
TYPES = ["sensor_msgs/msg/PointCloud2", "geometry_msgs/msg/WrenchStamped", "geometry_msgs/msg/Vector3Stamped",
         "geometry_msgs/msg/PointStamped", "sensor_msgs/msg/FluidPressure", "rosgraph_msgs/msg/Clock"]


@pytest.mark.parametrize("type_name", TYPES)
def test_schema_text_hashes_to_the_installed_type_hash(type_name):
    """rosbags rebuilds the type from our concatenated text alone and gets rosidl's RIHS01 hash."""
    text = msgdefs.full_text(type_name)
    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(text, type_name))
    assert store.hash_rihs01(type_name) == msgdefs.type_hash(type_name)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """DamBreak 1 at a coarse spacing for 0.03 s, every output with a particle cloud."""
    scene = load_scene("dambreak1_thesis")
    run = Run(scene, resolve(scene, sets=["dx=0.06", "end_time=0.03", "particle_rate=100"]))
    path = tmp_path_factory.mktemp("bags") / "db1"
    result = run.execute(run.open_recording(path))
    return run, path, result


def test_rosbags_reads_every_topic_and_the_cloud_is_the_solver_state(recorded):
    run, path, result = recorded
    assert result["status"] == "completed" and result["outputs"] == 4
    snap = run.solver.snapshot()
    with AnyReader([path]) as reader:
        topics = {c.topic: c.msgtype for c in reader.connections}
        counts = {c.topic: c.msgcount for c in reader.connections}
        clouds = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages()
                  if c.msgtype == "sensor_msgs/msg/PointCloud2"]
        stamps = [t for _, t, _ in reader.messages()]
    assert topics["/clock"] == "rosgraph_msgs/msg/Clock"
    assert topics["/sim_node/particles"] == "sensor_msgs/msg/PointCloud2"
    assert topics["/sim_node/bodies/obstruction/wrench"] == "geometry_msgs/msg/WrenchStamped"
    assert topics["/sim_node/bodies/obstruction/pressure_blocks/d060mm"] == "geometry_msgs/msg/WrenchStamped"
    assert topics["/sim_node/probes/velocity"] == "geometry_msgs/msg/Vector3Stamped"
    assert topics["/sim_node/probes/D/pressure"] == "sensor_msgs/msg/FluidPressure"
    assert counts["/sim_node/scene"] == counts["/sim_node/geometry"] == 1
    assert {n for t, n in counts.items() if t not in ("/sim_node/scene", "/sim_node/geometry")} == {4}
    info = yaml.safe_load((path / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    durability = {e["topic_metadata"]["name"]: e["topic_metadata"]["offered_qos_profiles"][0]["durability"]
                  for e in info["topics_with_message_count"]}
    assert durability["/sim_node/geometry"] == durability["/sim_node/scene"] == "transient_local"  # latched
    assert durability["/sim_node/particles"] == "volatile"
    assert max(stamps) == 30_000_000  # simulated time, ns
    last = clouds[-1]
    assert [f.name for f in last.fields] == ["x", "y", "z", "vx", "vy", "vz", "density", "pressure", "kind",
                                             "spacing"]
    assert last.width == run.solver.n and last.point_step == 40
    values = np.frombuffer(last.data.tobytes(), dtype="<f4").reshape(last.width, 10)
    assert np.array_equal(values[:, 0:3], snap["pos"].astype(np.float32))
    assert np.array_equal(values[:, 3:6], snap["vel"].astype(np.float32))
    assert np.array_equal(values[:, 6], snap["rho"].astype(np.float32))
    assert np.array_equal(values[:, 7], snap["pressure"].astype(np.float32))
    # kind: 0 fluid, 1 the tank's walls, 2 the obstruction (body 0), as the scene built them
    parts = run.model.particles
    expected = np.where(parts.ptype == FLUID, 0, np.where(parts.body == 0, 2, 1))
    assert np.array_equal(values[:, 8], expected) and set(np.unique(values[:, 8])) == {0, 1, 2}
    assert np.all(values[:, 9] == np.float32(run.model.config.dx))  # one level: the scene's spacing


def test_a_2d_scene_is_published_z_up(tmp_path):
    """A 2D scene computes with y up and is published in the x-z plane (REP 103): the cloud's z is
    the solver's y, its vz the solver's vy, y and vy are 0; a gauge's point has the level on z."""
    scene = load_scene("lobovsky_2d")
    run = Run(scene, resolve(scene, sets=["dx=0.02", "end_time=0.05", "output_rate=20", "particle_rate=20"]))
    result = run.execute(run.open_recording(tmp_path / "bag"))
    assert result["status"] == "completed"
    snap = run.solver.snapshot()
    with AnyReader([tmp_path / "bag"]) as reader:
        last = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages()
                if c.msgtype == "sensor_msgs/msg/PointCloud2"][-1]
    values = np.frombuffer(last.data.tobytes(), dtype="<f4").reshape(last.width, len(last.fields))
    assert np.array_equal(values[:, 0], snap["pos"][:, 0].astype(np.float32))
    assert np.array_equal(values[:, 2], snap["pos"][:, 1].astype(np.float32))
    assert np.array_equal(values[:, 5], snap["vel"][:, 1].astype(np.float32))
    assert not values[:, 1].any() and not values[:, 4].any() and np.abs(snap["vel"][:, 1]).max() > 0.1
    rec = read(tmp_path / "bag")
    level = rec.topic("probes/H1")["v"][-1]
    assert level[1] == 0.0 and 0.5 * 0.3 < level[2] < 1.5 * 0.3  # the 0.3 m column's level, on z
    assert rec.metadata["axes"].startswith("z up")


def test_compressed_chunks_and_epoch_stamps(tmp_path):
    """The same run recorded with zstd, lz4 and no chunk compression holds the same messages
    (rosbags and mcap's reader decompress both), the compressed files are smaller; with epoch
    stamps every stamp and log time is the wall clock of the run's start plus the simulated
    time, and the analysis reads simulated time back."""
    scene = load_scene("dambreak1_thesis")
    contents, sizes = {}, {}
    for compression in ("none", "zstd", "lz4"):
        run = Run(scene, resolve(scene, sets=["dx=0.06", "end_time=0.02", "particle_rate=100",
                                              f"compression={compression}"]))
        run.execute(run.open_recording(tmp_path / compression))
        with open(next((tmp_path / compression).glob("*.mcap")), "rb") as f:
            reader = make_reader(f)
            chunks = {c.compression for c in reader.get_summary().chunk_indexes}
            # all but the run's description, which names the compression and the time it started; as
            # messages (a CDR serialisation's padding bytes are not set)
            contents[compression] = [(c.topic, m.log_time, deserialize_message(m.data, message_class(s.name)))
                                     for s, c, m in reader.iter_messages() if c.topic != "/sim_node/scene"]
        assert chunks == ({""} if compression == "none" else {compression})
        sizes[compression] = sum(p.stat().st_size for p in (tmp_path / compression).glob("*.mcap"))
        with AnyReader([tmp_path / compression]) as bag:
            assert bag.message_count == len(contents[compression]) + 1
    assert contents["zstd"] == contents["none"] == contents["lz4"]
    assert sizes["zstd"] < 0.7 * sizes["none"] and sizes["lz4"] < sizes["none"]
    before = time.time_ns()
    run = Run(scene, resolve(scene, sets=["dx=0.06", "end_time=0.02", "stamps=epoch"]))
    run.execute(run.open_recording(tmp_path / "epoch"))
    origin = run.time_origin_ns
    assert before <= origin <= time.time_ns()
    with AnyReader([tmp_path / "epoch"]) as reader:
        stamped = [(t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages()
                   if c.topic.endswith("obstruction/wrench")]
    assert [t - origin for t, _ in stamped] == [0, 10_000_000, 20_000_000]
    assert all(m.header.stamp.sec * 10**9 + m.header.stamp.nanosec == t for t, m in stamped)
    assert list(read(tmp_path / "epoch").topic("obstruction/wrench")["t"]) == pytest.approx([0.0, 0.01, 0.02])


def test_mcap_ros2_reader_decodes_the_file_and_metadata_describes_the_run(recorded):
    run, path, _ = recorded
    msgs = list(read_ros2_messages(str(next(path.glob("*.mcap")))))
    per_topic = {}
    for m in msgs:
        per_topic[m.channel.topic] = per_topic.get(m.channel.topic, 0) + 1
    latched = {"/sim_node/scene", "/sim_node/geometry"}
    assert latched < set(per_topic) and {per_topic[t] for t in latched} == {1}
    assert len(per_topic) == 13 and {n for t, n in per_topic.items() if t not in latched} == {4}
    sample = run.measurements.sample()
    described = yaml.safe_load(next(m.ros_msg.data for m in msgs if m.channel.topic == "/sim_node/scene"))
    assert described["scene_name"] == "dambreak1_thesis" and described["run_config"]["dx"] == 0.06
    assert described["cloud_kinds"] == {0: "fluid", 1: "wall", 2: "body obstruction"}
    geometry = next(m.ros_msg for m in msgs if m.channel.topic == "/sim_node/geometry")
    box = next(m for m in geometry.markers if m.ns == "obstacles")
    assert (box.pose.position.x, box.scale.x, box.scale.z) == pytest.approx((0.96, 0.12, 0.4))
    arrow = [m.ros_msg for m in msgs if m.channel.topic.endswith("force_arrows")][-1].markers[0]
    assert (arrow.points[0].x, arrow.points[0].y, arrow.points[0].z) == pytest.approx((0.96, 0.3, 0.2))
    # an arrow 0.4 m long (the body's largest side) for its displaced weight, 1000 * 9.81 * 0.12^2 * 0.4 N
    drawn = np.subtract(*[(p.x, p.y, p.z) for p in arrow.points[::-1]])
    force = np.asarray(sample["wrenches"]["obstruction"][0])
    assert drawn == pytest.approx(force * 0.4 / (1000 * 9.81 * 0.12 * 0.12 * 0.4), abs=1e-12)
    for topic, key in (("obstruction/wrench", "wrenches"), ("obstruction/pressure_load", "pressure_loads")):
        wrench = [m.ros_msg for m in msgs if m.channel.topic.endswith(topic)][-1]
        force, _ = sample[key]["obstruction"]
        assert wrench.wrench.force.x == pytest.approx(force[0], rel=1e-6, abs=1e-9)
    rec = read(path)
    assert rec.complete and rec.result["status"] == "completed"
    assert rec.metadata["scene_name"] == "dambreak1_thesis" and rec.metadata["run_config"]["dx"] == 0.06
    assert "warp" in rec.metadata["versions"] and rec.metadata["device"] == "cpu"
    assert "Yeh & Petroff" in rec.metadata["scene"]


def _start(out, *extra):
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    # -X faulthandler: a run that hangs can be made to print where (SIGABRT, see the SIGTERM test)
    return subprocess.Popen([sys.executable, "-X", "faulthandler", "-m", "gpusph_ros.cli", "run", "collapse_2d",
                             "--set", "dx=0.003", "--set", "end_time=5", "--set", "particle_rate=100", "--quiet",
                             "--out", str(out), *extra],
                            cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def _wait_for_size(proc, path, size, timeout=120):
    start = time.time()
    while time.time() - start < timeout:
        files = list(path.glob("*.mcap"))
        if files and files[0].stat().st_size > size:
            return
        assert proc.poll() is None, proc.stdout.read()
        time.sleep(0.2)
    pytest.fail("the run wrote too little in time")


def test_killed_run_leaves_its_complete_chunks_readable(tmp_path):
    out = tmp_path / "killed"
    proc = _start(out)
    _wait_for_size(proc, out, 3 << 20)  # three 1 MiB chunks
    proc.kill()
    proc.wait()
    # a plain streaming MCAP reader, no project code: messages up to the cut
    count = 0
    with open(next(out.glob("*.mcap")), "rb") as f:
        try:
            for record in StreamReader(f).records:
                count += type(record).__name__ == "Message"
        except Exception:  # the cut-off record at the end
            pass
    assert count > 30
    rec = read(out)
    assert not rec.complete and rec.result == {}
    latched = 2  # the run's description and geometry, not read into series
    assert sum(len(s["t"]) for s in rec.series.values()) + len(rec.clouds) + len(rec.clock) + latched == count
    assert (out / "metadata.yaml").is_file()
    # the documented recovery step; then rosbags and mcap's indexed reader open it whole
    fixed = subprocess.run([sys.executable, "-m", "gpusph_ros.cli", "analyze", "--repair", str(out)],
                           capture_output=True, text=True, timeout=120)
    assert fixed.returncode == 0 and f"{count} messages" in fixed.stdout, fixed.stdout + fixed.stderr
    with AnyReader([out]) as reader:
        assert reader.message_count == count
        assert sum(1 for _ in reader.messages()) == count
    with open(next(out.glob("*.mcap")), "rb") as f:
        assert sum(1 for _ in make_reader(f).iter_messages()) == count
    info = yaml.safe_load((out / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["message_count"] == count
    assert read(out).result["status"] == f"killed: repaired, {count} messages recovered"
    again = subprocess.run([sys.executable, "-m", "gpusph_ros.cli", "analyze", "--repair", str(out)],
                           capture_output=True, text=True, timeout=120)
    assert again.returncode == 0 and "is whole: nothing to repair" in again.stdout, again.stdout + again.stderr


def _clock_bag(path, count: int):
    """A finished bag at ``path`` of ``count`` /clock messages 1 ms apart, in chunks of about 2 kB."""
    from gpusph_ros.output.messages import clock
    from gpusph_ros.output.recording import BagRecorder, qos_yaml

    recorder = BagRecorder(path, {"scene": "none"}, chunk_size=2048)
    recorder.add_topic("/clock", "rosgraph_msgs/msg/Clock", qos_yaml())
    for k in range(count):
        recorder.write("/clock", clock(k * 1e-3), k * 1e-3)
    recorder.close({"status": "completed"})
    return path


def test_repair_mends_a_bag_cut_at_any_point(tmp_path):
    """A bag of 600 /clock messages in chunks of about 2 kB, cut at 10 points along its length and
    right after its opening magic: --repair leaves each with the messages of its complete chunks,
    the first ones of the whole bag in order, and rosbags and mcap's indexed reader open it."""
    import shutil

    from rosgraph_msgs.msg import Clock

    from gpusph_ros.output.recording import whole_messages

    whole = _clock_bag(tmp_path / "whole", 600)
    size = (whole / "whole_0.mcap").stat().st_size
    recovered = []
    for cut in [8 + 3] + [size * k // 11 for k in range(1, 11)]:
        bag = tmp_path / f"cut_{cut}"
        shutil.copytree(whole, bag)
        os.rename(bag / "whole_0.mcap", bag / f"{bag.name}_0.mcap")
        with open(bag / f"{bag.name}_0.mcap", "r+b") as f:
            f.truncate(cut)
        held = whole_messages(bag / f"{bag.name}_0.mcap")[0]
        fixed = subprocess.run([sys.executable, "-m", "gpusph_ros.cli", "analyze", "--repair", str(bag)],
                               capture_output=True, text=True, timeout=120)
        assert fixed.returncode == 0 and f"{held} messages" in fixed.stdout, (cut, fixed.stdout + fixed.stderr)
        with AnyReader([bag]) as reader:
            assert reader.message_count == held
            stamps = [deserialize_message(raw, Clock).clock for _, _, raw in reader.messages()]
        assert [s.sec * 10 ** 9 + s.nanosec for s in stamps] == [k * 10 ** 6 for k in range(held)], cut
        with open(bag / f"{bag.name}_0.mcap", "rb") as f:
            assert sum(1 for _ in make_reader(f).iter_messages()) == held
        recovered.append(held)
    assert recovered == sorted(recovered) and recovered[0] == 0 and recovered[-1] > 450, recovered


def test_sigterm_finishes_the_file(tmp_path):
    out = tmp_path / "stopped"
    proc = _start(out)
    _wait_for_size(proc, out, 1 << 20)
    proc.send_signal(signal.SIGTERM)
    try:
        code = proc.wait(timeout=60)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGABRT)  # faulthandler prints every thread's stack
        pytest.fail("the run did not finish within 60 s of SIGTERM:\n" + proc.communicate(timeout=30)[0])
    assert code == 2, proc.stdout.read()
    with AnyReader([out]) as reader:
        assert reader.message_count > 0
    rec = read(out)
    assert rec.complete and rec.result["status"] == "interrupted"


def test_a_failed_run_keeps_what_it_recorded_and_says_why(tmp_path):
    scene = load_scene("collapse_2d")
    run = Run(scene, resolve(scene, sets=["dx=0.0076", "end_time=0.1", "dt_fixed=0.01"]))  # 200x the stable step
    result = run.execute(run.open_recording(tmp_path / "failed"))
    assert result["status"].startswith("failed: health check")
    with AnyReader([tmp_path / "failed"]) as reader:
        assert reader.message_count > 0  # output 0, the initial state
    rec = read(tmp_path / "failed")
    assert rec.complete and rec.result["status"] == result["status"]


def test_a_stop_request_ends_the_run_between_steps_and_closes_the_file(tmp_path):
    """What gpusph-run's SIGTERM handler does: ``stop`` answering true ends the run at the next
    step with status 'interrupted', the steps taken so far kept and the recording closed whole."""
    scene = load_scene("collapse_2d")
    # the eager loop, which asks before every step (a small run's replayed loop asks every 64)
    run = Run(scene, resolve(scene, sets=["dx=0.0076", "end_time=0.3", "step_graph=off"]))
    asked = []

    def stop():  # asked before every step (and after each batch): true from the 40th question on
        asked.append(True)
        return len(asked) >= 40

    result = run.execute(run.open_recording(tmp_path / "stopped"), stop=stop)
    assert result["status"] == "interrupted" and 0 < result["steps"] < 40  # no step without a question
    assert run.solver.time < 0.3
    rec = read(tmp_path / "stopped")
    assert rec.complete and rec.result["status"] == "interrupted"
    assert 0 < len(rec.clock) == run.next_output  # every output reached was recorded


def _folder_bytes(path: Path) -> int:
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())


def test_a_full_disk_closes_the_recording_whole_with_everything_written(tmp_path, monkeypatch):
    """A disk of 900 kB (this bag folder alone on it, its free space what the files leave): the
    recording closes itself before the disk is full, readable without repair by rosbags and by the
    analysis, with every message it counted; the run ends failed saying so. A write that failed on a
    full disk used to leave a file that --repair could not mend (0 of 939 messages recovered)."""
    from gpusph_ros.output import recording

    capacity = 900_000
    bag = tmp_path / "full"
    monkeypatch.setattr(recording, "free_bytes", lambda path: capacity - (_folder_bytes(bag) if bag.exists() else 0))
    scene = load_scene("collapse_2d")
    run = Run(scene, resolve(scene, sets=["dx=0.0076", "end_time=0.3", "output_rate=1000", "particle_rate=1000"]))
    result = run.execute(run.open_recording(bag))
    assert result["status"].startswith("failed: the recording could not be written") and "disk is full" in \
        result["status"], result["status"]
    assert 0.0 < run.solver.time < 0.3
    assert _folder_bytes(bag) <= capacity - recording.SPACE_MARGIN // 2  # the close fitted, with room to spare
    rec = read(bag)
    assert rec.complete and rec.result["status"].startswith("stopped: the disk is full")
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    with AnyReader([bag]) as reader:
        assert reader.message_count == info["message_count"] > 20
        clouds = [c for c in reader.connections if c.topic.endswith("/particles")]
        assert sum(1 for _ in reader.messages(connections=clouds)) >= 2


def test_a_recording_is_refused_where_the_disk_has_no_room_to_start(tmp_path, monkeypatch):
    from gpusph_ros.output import recording

    monkeypatch.setattr(recording, "free_bytes", lambda path: 100_000)
    scene = load_scene("collapse_2d")
    run = Run(scene, resolve(scene, sets=["dx=0.0076", "end_time=0.01"]))
    with pytest.raises(recording.DiskFull) as err:
        run.open_recording(tmp_path / "none")
    assert "100,000 bytes free" in str(err.value)
    assert not (tmp_path / "none").exists()  # no empty folder, no 0-byte file


def test_a_real_small_file_system_fills_and_the_recording_stays_readable(tmp_path):
    """gpusph-run into a 2 MiB tmpfs (where this machine lets a test mount one): exit 2 (failed) with the
    reason, the bag readable with everything counted."""
    mount = tmp_path / "small"
    mount.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(mount)], capture_output=True).returncode:
        pytest.skip("mounting a tmpfs is not allowed here; the injected-free-space test covers the logic")
    try:
        out = subprocess.run([str(Path(sys.executable).parent / "gpusph-run"), "collapse_2d", "--set", "dx=0.0076",
                              "--set", "end_time=0.3", "--set", "output_rate=1000", "--set", "particle_rate=1000",
                              "--set", "compression=none", "--out", str(mount / "bag"),
                              "--quiet"], capture_output=True, text=True, timeout=300)
        assert out.returncode == 2 and "disk is full" in out.stdout + out.stderr, out.stdout + out.stderr
        with AnyReader([mount / "bag"]) as reader:
            assert reader.message_count > 20
        assert read(mount / "bag").complete
    finally:
        subprocess.run(["umount", str(mount)], capture_output=True)


def test_each_body_frame_is_on_tf_static_where_tf2_msgs_is_installed():
    """On a ROS 2 install (tf2_msgs has no PyPI wheel, so not in this venv) the run's latched messages
    include /tf_static with world/<body> at the body's centre, the frame its wrench is in."""
    pytest.importorskip("tf2_msgs.msg")
    scene = load_scene("dambreak1_thesis")
    run = Run(scene, resolve(scene, sets=["dx=0.06", "end_time=0.01"]))
    transforms = dict(run.latched_messages())["/tf_static"].transforms
    assert [t.child_frame_id for t in transforms] == ["world/obstruction"]
    assert transforms[0].header.frame_id == "world"
    moved = transforms[0].transform.translation
    assert (moved.x, moved.y, moved.z) == pytest.approx((0.96, 0.3, 0.2))
    assert transforms[0].transform.rotation.w == 1.0


def test_a_chunk_that_inflates_past_its_cap_is_refused_unread(tmp_path):
    """A 2 kB chunk of zeros that says it inflates to 64 MiB (mcap allows 4 GiB; one of 512 MiB cost
    gpusph-analyze 582 MB, issue 58): the reader keeps the messages before it and says why it
    stopped, and one whose header lies is read no further than its cap."""
    path = tmp_path / "bomb.mcap"
    with open(path, "wb") as f:
        writer = Writer(f, chunk_size=1 << 20, compression=CompressionType.ZSTD)
        writer.start("ros2", "test")
        sid = writer.register_schema("rosgraph_msgs/msg/Clock", "ros2msg", b"")
        cid = writer.register_channel("/clock", "cdr", sid)
        writer.add_message(cid, log_time=10, data=np.random.default_rng(0).bytes(2 << 20), publish_time=10)
        writer.add_message(cid, log_time=20, data=bytes(64 << 20), publish_time=20)
        writer.finish()
    with open(path, "rb") as f:
        sizes = [(len(r.data), r.uncompressed_size) for r in StreamReader(f, emit_chunks=True).records
                 if isinstance(r, Chunk)]
    assert sizes[1][0] < 16 << 10 and sizes[1][1] > 64 << 20
    rec = read(path)
    assert rec.clock == [pytest.approx(1.0e-8)] and not rec.complete
    assert "inflates to 67,108,8" in rec.metadata["read_error"] and "not a recording of gpusph_ros" in \
        rec.metadata["read_error"]
    assert recording.whole_messages(path) == (1, 10, 0)
    lying = Chunk(message_start_time=0, message_end_time=0, uncompressed_size=1000, uncompressed_crc=0,
                  compression="zstd", data=zstandard.compress(bytes(64 << 20)))
    with pytest.raises(recording.ChunkTooLarge, match=f"inflates to {recording.MIN_CHUNK_CAP + 1:,}\\+ bytes"):
        list(recording.read_records(_one_chunk(lying)))


def _one_chunk(chunk):
    """An MCAP stream of its header and ``chunk``."""
    builder = RecordBuilder()
    Header(profile="ros2", library="test").write(builder)
    chunk.write(builder)
    return BytesIO(MCAP0_MAGIC + builder.end())


def test_repair_names_what_a_whole_looking_file_cannot_read(tmp_path):
    """Issue 66, item 8: a bag that ends with its footer but whose record after the header declares
    16 GiB was called whole ("nothing to repair") while neither gpusph-analyze nor rosbags could read
    it. --repair names the record and its byte offset, and keeps what stands before it."""
    bag = _clock_bag(tmp_path / "edited", 100)
    file = bag / "edited_0.mcap"
    data = bytearray(file.read_bytes())
    second = 8 + 9 + int.from_bytes(data[9:17], "little")  # the record after the magic and the header
    data[second + 1:second + 9] = (16 << 30).to_bytes(8, "little")
    file.write_bytes(bytes(data))
    fixed = subprocess.run([sys.executable, "-m", "gpusph_ros.cli", "analyze", "--repair", str(bag)],
                           capture_output=True, text=True, timeout=120)
    assert fixed.returncode == 0, fixed.stdout + fixed.stderr
    assert (f"ends whole but cannot be read: the record at byte {second:,} (opcode 0x{data[second]:02x}) declares "
            f"17,179,869,184 bytes") in fixed.stdout, fixed.stdout
    assert "0 messages" in fixed.stdout
    with AnyReader([bag]) as reader:  # what is left opens
        assert reader.message_count == 0
