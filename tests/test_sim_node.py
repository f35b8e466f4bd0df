"""sim_node as a user meets it: built by colcon, found and started as `ros2 run` does, in its own
process, and driven by a client node over ROS 2 (parameters, services, topics, recording).

The scene is DamBreak 1 at 6 cm (4,385 particles) and the 2D collapse at 2.5 mm, so the node
steps at tens of outputs a second on a CPU. The tests share one node (each starts from its
initial parameters, reset and running: fixture ``client``), but for the two that stop a node, which start
their own on DDS domains of their own; no test depends on another having run.
"""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
from rosbags.highlevel import AnyReader
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import String
from std_srvs.srv import SetBool, Trigger
from visualization_msgs.msg import MarkerArray

from gpusph_ros.analysis import bag as bag_reader
from gpusph_ros.output.messages import cloud_arrays
from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene

from ros_client import Client


def particles(scene: str, dx: float) -> int:
    """The particle count the scene builds to at dx: what the node must report and publish."""
    return len(build(load_scene(scene), dx=dx).particles)


pytestmark = pytest.mark.ros

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
DOMAIN = 101 + 3 * (os.getpid() % 33)  # DDS domains of this test run's own: DOMAIN, +1, +2
WRENCH = "/sim_node/bodies/obstruction/wrench"
PARTICLES = "/sim_node/particles"


def _t(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def _node_env(base: dict, domain: int) -> dict:
    return {**base, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
            "PYTHONUNBUFFERED": "1"}


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    """A colcon workspace with this repository as its one package, built; (root, colcon list output)."""
    ws = tmp_path_factory.mktemp("ws")
    (ws / "src").mkdir()
    (ws / "src/gpusph_ros").symlink_to(REPO)
    env = {**os.environ, "PATH": f"{BIN}:{os.environ['PATH']}"}
    listed = subprocess.run([BIN / "colcon", "list", "--base-paths", "src"], cwd=ws, env=env,
                            capture_output=True, text=True)
    assert listed.returncode == 0, listed.stderr
    built = subprocess.run([BIN / "colcon", "build", "--base-paths", "src"], cwd=ws, env=env,
                           capture_output=True, text=True)
    assert built.returncode == 0, built.stdout[-3000:] + built.stderr[-3000:]
    return ws, listed.stdout


@pytest.fixture(scope="module")
def sourced(workspace):
    """The environment after `source install/setup.bash`, as a ROS 2 user's shell has it."""
    ws, _ = workspace
    out = subprocess.run(["bash", "-c", f"source {ws}/install/setup.bash && env -0"], capture_output=True,
                         env={**os.environ, "PATH": f"{BIN}:{os.environ['PATH']}"})
    assert out.returncode == 0, out.stderr
    return dict(item.split("=", 1) for item in out.stdout.decode().split("\0") if "=" in item)


def _ros2_run_lookup(env) -> Path:
    """What `ros2 run gpusph_ros sim_node` does: the package's prefix from the ament index on
    AMENT_PREFIX_PATH, then <prefix>/lib/<package>/<executable>."""
    code = "from ament_index_python.packages import get_package_prefix as p; print(p('gpusph_ros'))"
    prefix = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert prefix.returncode == 0, prefix.stderr
    return Path(prefix.stdout.strip()) / "lib/gpusph_ros/sim_node"


def _start(command, env, log_path, domain=DOMAIN):
    log = open(log_path, "w")
    return subprocess.Popen([str(c) for c in command], env=_node_env(env, domain), stdout=log,
                            stderr=subprocess.STDOUT)


def _stop(proc, sig=signal.SIGINT, timeout=60.0) -> int:
    if proc.poll() is None:
        proc.send_signal(sig)
    try:
        return proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        raise


def _start_installed(sourced, log, domain=DOMAIN):
    """The node started from the colcon install with the shipped DamBreak 1 parameter file at a
    coarse spacing."""
    exe = _ros2_run_lookup(sourced)
    share = exe.parents[2] / "share/gpusph_ros/config"
    return _start([exe, "--ros-args", "--params-file", share / "params/dambreak1_thesis.yaml", "-p", "dx:=0.06",
                   "-p", "end_time:=30.0"], sourced, log, domain)


def _client(domain, proc, log) -> Client:
    """A client of the node on ``domain``, once the node publishes."""
    c = Client(domain)
    c.subscribe("/clock", Clock)
    c.subscribe("/diagnostics", DiagnosticArray)
    c.subscribe(PARTICLES, PointCloud2, depth=1)
    c.subscribe(WRENCH, WrenchStamped)
    try:
        c.wait_for("/clock", lambda m: len(m) > 3, timeout=300.0)
    except TimeoutError:
        c.close()
        pytest.fail(f"the node published no /clock (exit {proc.poll()}):\n" + log.read_text()[-3000:])
    return c


@pytest.fixture(scope="module")
def node(sourced, tmp_path_factory):
    """The shared node; (process, log path)."""
    log = tmp_path_factory.mktemp("node") / "sim_node.log"
    proc = _start_installed(sourced, log)
    yield proc, log
    _stop(proc)


@pytest.fixture(scope="module")
def shared_client(node):
    c = _client(DOMAIN, *node)
    yield c, c.get(*PARAMS_SET_BY_TESTS)
    c.close()


# the parameters tests change, put back by ``client`` before each test
PARAMS_SET_BY_TESTS = ("scene", "dx", "end_time", "cfl", "c0", "record_dir", "real_time_factor", "state_file")


@pytest.fixture
def client(shared_client):
    """The shared node's client, the node at its initial parameters, reset and running."""
    c, initial = shared_client
    assert c.call("set_paused", SetBool, data=True).success
    now = c.get(*initial)
    changed = {k: v for k, v in initial.items() if now[k] != v}
    if changed:
        result = c.set_together(**changed)
        assert result.successful, result.reason
    reply = c.call("reset", Trigger)
    assert reply.success, reply.message
    assert c.call("set_paused", SetBool, data=False).success
    return c


def _diagnostic(client, predicate=lambda s: True, timeout=30.0):
    """The newest solver status (a dict of its values, with level and message) that satisfies
    ``predicate``."""
    def status(msg):
        s = msg.status[0]
        return {**{kv.key: kv.value for kv in s.values}, "level": s.level, "message": s.message}

    msgs = client.wait_for("/diagnostics", lambda ms: any(predicate(status(m)) for m in ms), timeout)
    return [status(m) for m in msgs if predicate(status(m))][-1]


def _pause_and_reset(client):
    assert client.call("set_paused", SetBool, data=True).success
    reply = client.call("reset", Trigger)
    assert reply.success, reply.message
    return reply.message


# -- packaging --------------------------------------------------------------------------------
def test_colcon_lists_an_ament_python_package_and_installs_the_index_and_executable(workspace):
    ws, listed = workspace
    assert listed.split() == ["gpusph_ros", "src/gpusph_ros", "(ros.ament_python)"]
    prefix = ws / "install/gpusph_ros"
    assert (prefix / "share/ament_index/resource_index/packages/gpusph_ros").is_file()
    exe = prefix / "lib/gpusph_ros/sim_node"
    assert exe.is_file() and os.access(exe, os.X_OK)
    for cfg in ("sim_node.yaml", "params/dambreak1_thesis.yaml", "params/collapse_2d.yaml"):
        assert (prefix / "share/gpusph_ros/config" / cfg).is_file(), cfg
    # what `ros2 launch gpusph_ros sim.launch.py`, RViz's -d and Foxglove's layout import look for
    for shared in ("launch/sim.launch.py", "launch/sim.launch.xml", "rviz/sim.rviz", "foxglove/sim.json"):
        assert (prefix / "share/gpusph_ros" / shared).read_bytes() == (REPO / shared).read_bytes(), shared


def test_ros2_run_lookup_finds_the_installed_executable(workspace, sourced):
    ws, _ = workspace
    assert _ros2_run_lookup(sourced) == ws / "install/gpusph_ros/lib/gpusph_ros/sim_node"


# -- running ----------------------------------------------------------------------------------
def test_the_node_runs_and_reports_itself_on_diagnostics(client):
    # the health peaks are read at a census (every 16 steps): until the first, they read None
    status = _diagnostic(client, lambda s: s["state"] == "running" and s.get("min_density_ratio", "None") != "None")
    assert status["level"] == DiagnosticStatus.OK
    assert status["scene"] == "dambreak1_thesis" and int(status["particles"]) == particles("dambreak1_thesis", 0.06)
    assert status["device"] == "cpu" and status["precision"] == "float32"
    for key in ("simulated_time", "dt", "steps", "steps_per_s", "mipps", "real_time_factor", "error"):
        assert key in status
    # the health peaks so far: a dam break at rest or just released is inside the density bounds
    assert 0.8 <= float(status["min_density_ratio"]) <= float(status["max_density_ratio"]) <= 1.25
    assert 0.0 <= float(status["peak_clumped_fraction"]) <= 0.2
    client.clear("/clock")
    clocks = [_t(m.clock) for m in client.wait_for("/clock", lambda m: len(m) >= 3)]
    assert clocks == sorted(clocks) and clocks[-1] > 0.0
    # the cloud's QoS, reliable and depth 1 by default, can be overridden at start-up
    qos = client.get("qos_overrides./sim_node/particles.publisher.reliability",
                     "qos_overrides./sim_node/particles.publisher.depth")
    assert list(qos.values()) == ["reliable", 1]


def test_bad_parameters_are_rejected_with_a_reason_and_change_nothing(client):
    names = ("kernel", "dx", "sps", "device", "scene", "particle_fields", "autostart", "cfl")
    before = client.get(*names)
    for name, value, words in [
        ("kernel", "gauss", ["'gauss'", "quadratic, cubic_spline, wendland"]),
        ("sps", True, ["laminar"]),
        ("device", "cuda:7", ["not available"]),
        ("scene", "no_such_scene", ["dambreak1_thesis", "collapse_2d"]),
        ("particle_fields", ["vx", "speed"], ["'speed'"]),
        ("dx", 50.0, ["dx"]),
        ("cfl", 0, ["type"]),  # an integer where a double is declared
        ("autostart", False, ["read-only"]),
    ]:
        result, = client.set(**{name: value})
        assert not result.successful, name
        for word in words:
            assert word.lower() in result.reason.lower(), (name, result.reason)
    assert client.get(*names) == before


def test_a_good_change_says_when_it_applies(client):
    dx, = client.set(dx=0.05)
    assert dx.successful and "next ~/reset" in dx.reason
    cfl, = client.set(cfl=0.25)
    assert cfl.successful and "next step" in cfl.reason
    assert "dx" in _diagnostic(client, lambda s: "dx" in s["message"])["message"]
    assert f"dx = 0.05 m, {particles('dambreak1_thesis', 0.05)} particles" in _pause_and_reset(client)
    assert client.set(dx=0.06)[0].successful
    assert f"{particles('dambreak1_thesis', 0.06)} particles" in _pause_and_reset(client)


def test_a_paused_node_steps_one_output_and_the_cloud_is_the_scene(client):
    _pause_and_reset(client)
    client.clear(PARTICLES)
    client.clear("/clock")
    client.clear(WRENCH)
    reply = client.call("step", Trigger)
    assert reply.success and "t = 0.0000 s" in reply.message, reply.message
    cloud = client.wait_for(PARTICLES)[-1]
    assert _t(cloud.header.stamp) == 0.0 and cloud.header.frame_id == "world"
    assert [f.name for f in cloud.fields] == ["x", "y", "z", "vx", "vy", "vz", "density", "pressure", "kind",
                                              "spacing"]
    model = build(load_scene("dambreak1_thesis"), dx=0.06)
    arrays = cloud_arrays(cloud)
    assert cloud.width == len(model.particles)
    pos = np.stack([arrays["x"], arrays["y"], arrays["z"]], axis=1)
    np.testing.assert_allclose(pos, model.particles.pos, atol=1e-6)  # float32 of the same fill
    wrench = client.wait_for(WRENCH)[-1]
    assert _t(wrench.header.stamp) == 0.0 and wrench.header.frame_id == "world/obstruction"
    # the obstruction stands dry at t = 0: no fluid within a kernel support, no force
    assert (wrench.wrench.force.x, wrench.wrench.force.y, wrench.wrench.force.z) == (0.0, 0.0, 0.0)
    # one more step is one output interval (100 Hz), announced on /clock
    reply = client.call("step", Trigger)
    assert reply.success and "stepped to t = 0.0100 s" in reply.message, reply.message
    assert [_t(m.clock) for m in client.wait_for("/clock", lambda m: len(m) >= 2)] == [0.0, 0.01]
    assert _t(client.wait_for(WRENCH, lambda m: len(m) >= 2)[-1].header.stamp) == 0.01
    # stepping while running is refused, with what to do
    assert client.call("set_paused", SetBool, data=False).success
    reply = client.call("step", Trigger)
    assert not reply.success and "pause it first" in reply.message


def test_a_pause_right_after_a_reset_then_a_step_publishes_the_next_output(client):
    # the pause lands while the solver thread is still publishing the new run's t = 0 output:
    # the step must still produce the output after it
    assert client.call("set_paused", SetBool, data=False).success
    assert client.call("reset", Trigger).success
    assert client.call("set_paused", SetBool, data=True).success
    client.clear("/clock")
    reply = client.call("step", Trigger)
    assert reply.success and reply.message.startswith("stepped to t = "), reply.message
    t = float(reply.message.split("t = ")[1].split(" s")[0])
    assert t in [_t(m.clock) for m in client.wait_for("/clock", lambda ms: any(_t(m.clock) == t for m in ms))]


def test_pause_holds_the_simulated_time_and_resume_moves_it(client):
    assert client.call("set_paused", SetBool, data=False).success
    _diagnostic(client, lambda s: s["state"] == "running")
    reply = client.call("set_paused", SetBool, data=True)
    assert reply.success and "paused" in reply.message
    client.clear("/diagnostics")
    first = _diagnostic(client, lambda s: s["state"] == "paused")
    client.clear("/diagnostics")
    later = _diagnostic(client, lambda s: s["state"] == "paused")
    assert float(later["simulated_time"]) == float(first["simulated_time"])
    assert client.call("set_paused", SetBool, data=False).success
    t0 = float(later["simulated_time"])
    _diagnostic(client, lambda s: float(s.get("simulated_time", 0)) > t0)


def test_a_subscriber_that_joins_late_gets_the_scene_and_its_geometry(client):
    """~/scene and ~/geometry are latched (transient local): a viewer started after the node gets
    the run's description and the scene's markers at once, and the wrench is in the body's frame."""
    client.subscribe("/sim_node/scene", String, latched=True)
    client.subscribe("/sim_node/geometry", MarkerArray, latched=True)
    described = yaml.safe_load(client.wait_for("/sim_node/scene", timeout=30.0)[-1].data)
    assert described["scene_name"] == "dambreak1_thesis" and described["particles"] == particles("dambreak1_thesis",
                                                                                                  0.06)
    assert described["device"] == "cpu" and described["revision"]
    markers = client.wait_for("/sim_node/geometry", timeout=30.0)[-1].markers
    assert {m.ns for m in markers} >= {"tank", "obstacles", "probes", "labels"}
    assert all(m.header.frame_id == "world" for m in markers)
    assert client.wait_for(WRENCH)[-1].header.frame_id == "world/obstruction"


def test_save_and_load_state_go_back_to_the_same_run(client, tmp_path):
    """~/save_state keeps the run's whole state in state_file; stepping on and then ~/load_state brings
    the run back, and the next output is the one it published the first time, bit for bit."""
    _pause_and_reset(client)
    reply = client.call("save_state", Trigger)
    assert not reply.success and "state_file is empty" in reply.message
    assert client.set(state_file=str(tmp_path / "state.npz"))[0].successful
    for _ in range(3):
        assert client.call("step", Trigger).success
    reply = client.call("save_state", Trigger)
    assert reply.success and "t = 0.0200 s" in reply.message, reply.message

    def next_cloud():
        client.clear(PARTICLES)
        assert client.call("step", Trigger).success
        return client.wait_for(PARTICLES)[-1]

    first = next_cloud()
    for _ in range(2):
        assert client.call("step", Trigger).success
    reply = client.call("load_state", Trigger)
    assert reply.success and "loaded the state at t = 0.0200 s" in reply.message, reply.message
    again = next_cloud()
    assert again.header.stamp == first.header.stamp and _t(again.header.stamp) == pytest.approx(0.03)
    a, b = cloud_arrays(first), cloud_arrays(again)
    assert all(np.array_equal(a[f], b[f]) for f in a) and np.abs(a["vz"]).max() > 0.1  # the water falls
    # a state of other settings is refused with what differs
    assert client.set(dx=0.05)[0].successful
    _pause_and_reset(client)
    reply = client.call("load_state", Trigger)
    assert not reply.success and "settings dx" in reply.message, reply.message
    assert client.set(state_file="")[0].successful


def test_reset_into_another_built_in_scene(client):
    result = client.set_together(scene="collapse_2d", dx=0.0025, end_time=0.3)
    assert result.successful, result.reason
    message = _pause_and_reset(client)
    assert "collapse_2d" in message and f"{particles('collapse_2d', 0.0025)} particles" in message, message
    client.clear(PARTICLES)
    assert client.call("step", Trigger).success
    assert client.wait_for(PARTICLES)[-1].width == particles("collapse_2d", 0.0025)

    def topics():
        return {name for name, _ in client.node.get_publisher_names_and_types_by_node("sim_node", "/")}

    deadline = time.monotonic() + 20.0
    while (WRENCH in topics() or "/sim_node/probes/toe" not in topics()) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert WRENCH not in topics() and "/sim_node/probes/toe" in topics()
    result = client.set_together(scene="dambreak1_thesis", dx=0.06, end_time=30.0)
    assert result.successful, result.reason
    assert f"{particles('dambreak1_thesis', 0.06)} particles" in _pause_and_reset(client)


def test_recording_toggles_and_reads_back_with_rosbags(client, tmp_path):
    assert client.call("set_paused", SetBool, data=True).success
    reply = client.call("record", SetBool, data=True)
    assert not reply.success and "record_dir" in reply.message
    assert client.set(record_dir=str(tmp_path))[0].successful
    reply = client.call("record", SetBool, data=True)
    assert reply.success and str(tmp_path) in reply.message, reply.message
    for _ in range(3):
        assert client.call("step", Trigger).success
    reply = client.call("record", SetBool, data=False)
    assert reply.success, reply.message
    bag = Path(reply.message.split(": ", 1)[1])
    assert bag.parent == tmp_path
    counts, clouds = {}, []
    with AnyReader([bag]) as reader:
        order = []
        for connection, t, raw in reader.messages():
            counts[connection.topic] = counts.get(connection.topic, 0) + 1
            order.append(connection.topic)
            if connection.topic == PARTICLES:
                clouds.append(reader.deserialize(raw, connection.msgtype))
    assert counts["/clock"] == counts[WRENCH] == counts[PARTICLES] == 3
    # the run's description and geometry open the recording, then /clock before the outputs it stamps
    assert order[:2] == ["/sim_node/scene", "/sim_node/geometry"] and order[2] == "/clock"
    assert clouds[-1].width == particles("dambreak1_thesis", 0.06)
    assert bag_reader.read(bag).result["status"] == "stopped"
    assert client.set(record_dir="")[0].successful


def test_an_instability_gives_an_error_diagnostic_and_the_node_still_answers(client, tmp_path):
    assert client.set(record_dir=str(tmp_path))[0].successful
    reply = client.call("record", SetBool, data=True)
    assert reply.success
    bag = Path(reply.message.split("recording to ", 1)[1])
    assert client.set(c0=0.3)[0].successful  # a sound speed far below 10 sqrt(g H): density runs away
    assert client.call("set_paused", SetBool, data=False).success
    status = _diagnostic(client, lambda s: s["state"] == "failed", timeout=120.0)
    assert status["recording"] == ""  # the failure finished the bag, which says why
    recording = bag_reader.read(bag)
    assert recording.complete and recording.result["status"].startswith("failed: health check")
    assert len(recording.clock) > 0
    assert client.set(record_dir="")[0].successful
    assert status["level"] == DiagnosticStatus.ERROR
    assert "health check" in status["message"] and "failed" in status["message"]
    assert client.get("c0") == {"c0": 0.3}  # still answering
    reply = client.call("set_paused", SetBool, data=False)
    assert not reply.success and "~/reset" in reply.message
    assert client.set(c0=0.0)[0].successful
    reply = client.call("reset", Trigger)
    assert reply.success, reply.message
    assert client.call("set_paused", SetBool, data=False).success
    status = _diagnostic(client, lambda s: s["state"] == "running")
    assert status["level"] == DiagnosticStatus.OK


def test_sigint_finishes_the_recording(sourced, tmp_path):
    """A node of its own (this test stops it) on a domain of its own."""
    log = tmp_path / "sim_node.log"
    proc = _start_installed(sourced, log, DOMAIN + 1)
    try:
        client = _client(DOMAIN + 1, proc, log)
    except BaseException:
        _stop(proc)
        raise
    try:
        _record_then_sigint(proc, log, client, tmp_path)
    finally:
        client.close()
        _stop(proc)


def _record_then_sigint(proc, log, client, tmp_path):
    assert client.set(record_dir=str(tmp_path))[0].successful
    reply = client.call("record", SetBool, data=True)
    assert reply.success
    bag = Path(reply.message.split("recording to ", 1)[1])
    n = len(client.received("/clock"))
    client.wait_for("/clock", lambda m: len(m) > n + 5)
    assert _stop(proc, signal.SIGINT) == 0, log.read_text()[-3000:]
    with AnyReader([bag]) as reader:
        topics = {c.topic for c in reader.connections}
        assert sum(1 for _ in reader.messages()) > 5
    assert {"/clock", PARTICLES, WRENCH} <= topics
    recording = bag_reader.read(bag)
    assert recording.complete and recording.result["status"] == "interrupted"


def test_lifecycle_mode_without_autostart_and_sigterm_finishes_the_recording(tmp_path):
    """`sim_node` from this repository's venv, as a managed node (on a domain of its own): it waits
    unconfigured until told, records from activation because record_dir is set, and SIGTERM closes
    the bag whole."""
    from lifecycle_msgs.msg import State, Transition
    from lifecycle_msgs.srv import ChangeState, GetState

    client = Client(DOMAIN + 2)
    client.subscribe("/clock", Clock)
    client.subscribe("/diagnostics", DiagnosticArray)
    proc = _start([BIN / "sim_node", "--ros-args", "--params-file", REPO / "config/params/collapse_2d.yaml",
                   "-p", "autostart:=false", "-p", f"record_dir:={tmp_path}", "-p", "end_time:=100.0"],
                  os.environ, tmp_path / "node.log", DOMAIN + 2)
    try:
        state = client.call("get_state", GetState, timeout=120.0).current_state
        assert state.id == State.PRIMARY_STATE_UNCONFIGURED
        status = _diagnostic(client, lambda s: s["state"] == "unconfigured", timeout=60.0)
        assert status["level"] == DiagnosticStatus.WARN
        assert client.call("change_state", ChangeState,
                           transition=Transition(id=Transition.TRANSITION_CONFIGURE)).success
        assert client.call("get_state", GetState).current_state.id == State.PRIMARY_STATE_INACTIVE
        inactive = _diagnostic(client, lambda s: s["state"] == "inactive")
        assert inactive["particles"] == str(particles("collapse_2d", 0.0025))
        reply = client.call("set_paused", SetBool, data=False)
        assert not reply.success and "inactive" in reply.message
        assert client.call("change_state", ChangeState,
                           transition=Transition(id=Transition.TRANSITION_ACTIVATE)).success
        status = _diagnostic(client, lambda s: s["state"] == "running" and s["recording"], timeout=60.0)
        bag = Path(status["recording"])
        assert bag.parent == tmp_path
        n = len(client.received("/clock"))
        client.wait_for("/clock", lambda m: len(m) > n + 10)
        # at most 0.005 simulated s per wall s: the 10 ms outputs come every 2 s. The solver needs
        # about 0.3 s for one on an idle 2-core CPU, and more than 1 s when the whole suite loads
        # both cores, so the pace, not the solver, sets the interval
        assert client.set(real_time_factor=0.005)[0].successful
        time.sleep(2.5)
        client.clear("/clock")
        client.wait_for("/clock", lambda m: len(m) >= 4, timeout=60.0)
        arrivals = np.diff(client.arrivals["/clock"][:4])
        assert abs(arrivals.mean() - 2.0) < 0.3, arrivals
    finally:
        code = _stop(proc, signal.SIGTERM)
        client.close()
    assert code == 0, (tmp_path / "node.log").read_text()[-3000:]
    recording = bag_reader.read(bag)
    assert recording.complete and recording.result["status"] == "interrupted"
    assert len(recording.clock) > 10 and recording.metadata["scene_name"] == "collapse_2d"


# -- bodies driven from ROS -------------------------------------------------------------------
def test_a_paddle_driven_by_cmd_pose_follows_makes_waves_and_refuses_bad_commands(client):
    """The built-in ``paddle_2d`` flume at 4 cm, paced at 0.2 real time: a client streams cmd_pose
    at 100 Hz (wall clock), each stamped with the newest /clock, the paddle's x a 1 Hz sinusoid of 1 cm about its start
    (published axes: x along the flume, z up). The node publishes the paddle's pose and wrench at
    every output (20 Hz); the pose follows the command one or two outputs behind (the best lag of
    0-0.3 s, 5 ms apart, is at most 0.1 s: the driver's one output and the command's trip), within
    2 mm RMS there; the gauge 1 m down the flume sees waves. Then a NaN pose, one stamped 10 s ahead,
    one 2.5 s old, a non-unit quaternion and one in another frame than the world's are refused (counted
    on /diagnostics), and a 1 m jump is
    walked at no more than max_speed (0.5 m/s), the node alive and no particle lost."""
    import math
    import threading

    from geometry_msgs.msg import PointStamped, PoseStamped

    pose_topic, wrench_topic, gauge = ("/sim_node/bodies/paddle/pose", "/sim_node/bodies/paddle/wrench",
                                       "/sim_node/probes/G1")
    client.subscribe(pose_topic, PoseStamped, depth=100)
    client.subscribe(wrench_topic, WrenchStamped, depth=100)
    client.subscribe(gauge, PointStamped, depth=100)
    assert client.set_together(scene="paddle_2d", dx=0.04, end_time=60.0).successful
    _pause_and_reset(client)
    for topic in (pose_topic, wrench_topic, gauge, "/clock"):
        client.clear(topic)
    publisher = client.node.create_publisher(PoseStamped, "/sim_node/bodies/paddle/cmd_pose", 10)

    def command(x, t, q=(0.0, 0.0, 0.0, 1.0), frame="world"):
        msg = PoseStamped()
        msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), int(round((t - int(t)) * 1e9))
        msg.header.frame_id = frame
        msg.pose.position.x, msg.pose.position.z = x, 0.4
        msg.pose.orientation.x, msg.pose.orientation.y, msg.pose.orientation.z, msg.pose.orientation.w = q
        publisher.publish(msg)

    def sim_now():
        clocks = client.received("/clock")
        return _t(clocks[-1].clock) if clocks else 0.0

    def path(t):
        return 0.07 + 0.01 * math.sin(2 * math.pi * t)

    done = threading.Event()

    def stream():
        while not done.is_set():
            now = sim_now()
            if now > 0.0:
                command(path(now), now)
            time.sleep(0.01)

    streamer = threading.Thread(target=stream, daemon=True)
    streamer.start()
    # paced at a fifth of real time, as a robot's loop is paced: on an idle machine the node idles
    # between outputs, and a command's wall delay is a fifth as long in simulated time (flat out,
    # one loaded suite run starved the client and the tracking RMS read 4 mm)
    assert client.set(real_time_factor=0.2)[0].successful
    assert client.call("set_paused", SetBool, data=False).success
    try:
        client.wait_for("/clock", lambda m: m and _t(m[-1].clock) >= 2.5, timeout=240.0)
    finally:
        done.set()
        streamer.join(timeout=5.0)
        assert client.set(real_time_factor=0.0)[0].successful
    poses = client.received(pose_topic)
    t = np.array([_t(m.header.stamp) for m in poses])
    x = np.array([m.pose.position.x for m in poses])
    assert np.all(np.diff(t) > 0) and len(t) >= 45
    wrench_stamps = {_t(m.header.stamp) for m in client.received(wrench_topic)}
    assert set(t) <= wrench_stamps  # the wrench comes back with every pose
    late = t >= 1.0
    rms = {lag: float(np.sqrt(np.mean((x[late] - np.array([path(s - lag) for s in t[late]])) ** 2)))
           for lag in np.arange(0.0, 0.3001, 0.005)}
    best = min(rms, key=rms.get)
    assert best <= 0.1 + 1e-9 and rms[best] < 0.002, rms
    levels = np.array([m.point.z for m in client.received(gauge) if _t(m.header.stamp) >= 1.0])
    assert levels.max() - levels.min() > 0.004  # the waves reach the gauge (0.4 m at rest)
    # bad commands, then a jump of 1 m
    now = sim_now()
    command(float("nan"), now)
    command(0.07, now + 10.0)
    command(0.07, 1.0e-3)  # stale: stamped near t = 0, 2.5 s ago
    command(0.07, now, q=(0.0, 0.0, 0.0, 2.0))
    status = _diagnostic(client, lambda s: int(s.get("commands_refused_paddle", 0)) >= 3)
    assert status["level"] != DiagnosticStatus.ERROR
    refused = int(status["commands_refused_paddle"])
    command(0.07, sim_now(), frame="base_link")  # a pose in the robot's frame was taken as the world's
    _diagnostic(client, lambda s: int(s.get("commands_refused_paddle", 0)) > refused)
    client.clear(pose_topic)
    jump_from = sim_now()
    command(1.07, jump_from)
    client.wait_for(pose_topic, lambda m: m and _t(m[-1].header.stamp) >= jump_from + 0.4, timeout=120.0)
    poses = client.received(pose_topic)
    t = np.array([_t(m.header.stamp) for m in poses])
    x = np.array([m.pose.position.x for m in poses])
    speeds = np.abs(np.diff(x)) / np.diff(t)
    assert speeds.max() <= 0.5 + 1e-6 and x[-1] > x[0] + 0.05  # walked towards it, at the limit
    status = _diagnostic(client, lambda s: s["state"] in ("running", "paused"))
    assert int(status.get("excluded_particles", 0)) == 0


def test_a_floating_box_takes_an_external_wrench_from_cmd_wrench(client, tmp_path):
    """A 2D box floating at its draft (a scene file beside the test, 4 cm): a client holds 300 N/m
    down on it through ~/bodies/box/cmd_wrench (world frame, z up): it sinks from its draft; a wrench
    in another frame is refused and counted."""
    from geometry_msgs.msg import PoseStamped

    scene = {"name": "float", "dim": 2, "tank": [1.0, 0.6],
             "fluid": [{"name": "water", "lo": [0, 0], "hi": [1.0, 0.3]}],
             "obstacles": [{"name": "box", "lo": [0.4, 0.24], "hi": [0.6, 0.36], "displaces_fluid": True,
                            "floating": {"density": 500.0, "rotate": False, "max_force": 400.0}}]}
    path = tmp_path / "float.yaml"
    path.write_text(yaml.safe_dump(scene))
    pose_topic = "/sim_node/bodies/box/pose"
    client.subscribe(pose_topic, PoseStamped, depth=100)
    assert client.set_together(scene=str(path), dx=0.04, end_time=60.0).successful
    _pause_and_reset(client)
    client.clear(pose_topic)
    publisher = client.node.create_publisher(WrenchStamped, "/sim_node/bodies/box/cmd_wrench", 10)
    assert client.call("set_paused", SetBool, data=False).success
    start = _t(client.wait_for(pose_topic, lambda m: len(m) > 0)[-1].header.stamp)
    z0 = client.received(pose_topic)[-1].pose.position.z
    wrong = WrenchStamped()
    wrong.header.frame_id = "elsewhere"
    publisher.publish(wrong)
    deadline = time.monotonic() + 120.0
    while time.monotonic() < deadline:
        msg = WrenchStamped()  # a zero stamp: now
        msg.wrench.force.z = -300.0
        publisher.publish(msg)
        poses = client.received(pose_topic)
        if _t(poses[-1].header.stamp) >= start + 0.4:
            break
        time.sleep(0.02)
    z = client.received(pose_topic)[-1].pose.position.z
    assert z < z0 - 0.01  # pushed down by three times its weight
    status = _diagnostic(client, lambda s: int(s.get("commands_refused_box", 0)) >= 1
                         and int(s.get("commands_taken_box", 0)) >= 1)
    assert status["level"] != DiagnosticStatus.ERROR
    # a flood (as fast as this client publishes, kHz): each push is counted taken, refused or lost before
    # the node read it, where at 10 kHz 86% went uncounted; a last push shows the gap before it
    def counted(s):
        return sum(int(s.get(f"commands_{outcome}_box", 0)) for outcome in ("taken", "refused", "lost"))

    def settled():
        """The count once two fresh diagnostics agree: the pushes above all read and counted (a fixed
        second was short on a loaded machine: 31 of them were counted after it)."""
        last = None
        for _ in range(30):
            client.clear("/diagnostics")
            now = counted(_diagnostic(client))
            if now == last:
                return now
            last = now
        raise AssertionError(f"the commands' count never settled: {last}")

    before = settled()
    for _ in range(2000):
        publisher.publish(WrenchStamped())
    time.sleep(0.5)
    publisher.publish(WrenchStamped())
    flood = _diagnostic(client, lambda s: counted(s) >= before + 2001)
    assert counted(flood) == before + 2001 and int(flood.get("commands_lost_box", 0)) > 0, flood
    now = _t(client.received(pose_topic)[-1].header.stamp)
    assert client.set_together(end_time=round(now + 0.2, 2)).successful
    ended = _diagnostic(client, lambda s: s["state"] == "finished", timeout=120.0)
    taken, refused = int(ended.get("commands_taken_box", 0)), int(ended.get("commands_refused_box", 0))
    publisher.publish(WrenchStamped())
    later = _diagnostic(client, lambda s: int(s.get("commands_refused_box", 0)) > refused)
    assert int(later.get("commands_taken_box", 0)) == taken
    assert client.call("reset", Trigger).success
    _diagnostic(client, lambda s: s["state"] != "finished" and "commands_taken_box" not in s
                and "commands_refused_box" not in s)


def test_a_body_that_follows_a_tf_frame_runs_where_tf2_msgs_is_missing(client, node, tmp_path):
    """PyPI has no tf2_msgs: a scene whose driven paddle follows a TF frame (``motion.frame``)
    builds and steps, its pose published, and the log says the body takes cmd_pose and cmd_twist
    only (where tf2_msgs is installed the node follows /tf: ros/frame_follow.py)."""
    from geometry_msgs.msg import PoseStamped

    scene = tmp_path / "followed.yaml"
    scene.write_text(yaml.safe_dump({
        "name": "followed", "dim": 2, "tank": [1.2, 0.5],
        "fluid": [{"name": "water", "lo": [0.14, 0.0], "hi": [1.2, 0.3]}],
        "obstacles": [{"name": "paddle", "lo": [0.1, 0.0], "hi": [0.14, 0.5],
                       "motion": {"type": "driven", "max_speed": 0.5, "max_acceleration": 5.0,
                                  "frame": "robot/paddle"}}]}))
    pose_topic = "/sim_node/bodies/paddle/pose"
    client.subscribe(pose_topic, PoseStamped, depth=10)
    assert client.set_together(scene=str(scene), dx=0.04, end_time=1.0).successful
    _pause_and_reset(client)
    reply = client.call("step", Trigger)
    assert reply.success, reply.message
    assert client.wait_for(pose_topic)
    try:
        import tf2_msgs  # noqa: F401
    except ImportError:
        log = node[1]
        deadline = time.time() + 10.0
        while "motion.frame needs tf2_msgs" not in log.read_text() and time.time() < deadline:
            time.sleep(0.2)
        assert "paddle: motion.frame needs tf2_msgs" in log.read_text()
