"""The node's solver thread (ros/session.py) against stand-in runs: who may step when.

A stand-in run steps in a few milliseconds and logs each step with the wall time, so that the
order of steps, builds and captures can be read back; nothing here needs Warp or a DDS domain.
"""
import threading
import time

import pytest

from gpusph_ros.ros import session as session_mod
from gpusph_ros.ros.session import Session

pytestmark = pytest.mark.unit


class _Solver:
    def __init__(self):
        self.time, self.steps, self.dt, self.n = 0.0, 0, 1e-3, 1

    def reached(self, target):
        return self.time >= target - 1e-12


class _Recorder:
    def __init__(self, path):
        self.path, self.topics, self.closed = path, [], None

    def write(self, topic, msg, t, data):
        self.topics.append(topic)

    def close(self, result):
        self.closed = result

    def flush(self, due_only=True):
        pass


class StandIn:
    """A run named ``name``: each output is one step of 2 ms wall time publishing ``/<name>``."""

    def __init__(self, name, log):
        self.name, self.log = name, log
        self.solver, self.next_output, self.done = _Solver(), 1, False
        self.scene = type("Scene", (), {"text": name, "name": name})()
        self.run_config = type("Settings", (), {"as_dict": lambda _self: {}})()

    def step_output(self, interrupt, limit=None):
        self.log.append(("step", self.name, time.monotonic()))
        time.sleep(0.002)
        self.solver.time += 1e-3
        self.solver.steps += 1
        self.next_output += 1
        from std_msgs.msg import Empty
        return [(f"/{self.name}", Empty())]

    def next_event(self):
        return self.solver.time + 1e-3

    def checkpoint(self):
        self.log.append(("capture", self.name, time.monotonic()))
        time.sleep(0.05)
        self.log.append(("captured", self.name, time.monotonic()))
        return {"t": self.solver.time}

    def open_recording(self, path, compression=None):
        return _Recorder(path)

    def result(self, status):
        return {"status": status}


def _session(run):
    s = Session(publish=lambda *a: None, report=lambda *a: None)
    s.run = run
    s.set_active(True)
    return s


def test_a_save_beside_a_reset_never_lets_the_old_run_step_under_the_build(tmp_path):
    """Issue 66, item 1: a ~/save_state that finished while a ~/reset was still building released
    the solver (one boolean for both), and the old run stepped into the new run's bag. The reset's
    build and the save must each own the solver alone; no step of the old run falls inside the
    build, and the save captures one run whole."""
    log = []
    old = StandIn("old", log)
    s = _session(old)
    try:
        time.sleep(0.05)  # the old run is stepping

        def build():
            log.append(("build", "new", time.monotonic()))
            time.sleep(0.4)
            log.append(("built", "new", time.monotonic()))
            return StandIn("new", log)

        resetter = threading.Thread(target=s.replace, args=(build,))
        resetter.start()
        time.sleep(0.1)  # the build is under way
        saved = s.save_state(tmp_path / "state.gpusph")
        resetter.join()
        time.sleep(0.05)
    finally:
        s.close()
    assert saved[0], saved
    start = next(t for kind, _, t in log if kind == "build")
    end = next(t for kind, _, t in log if kind == "built")
    inside = [entry for entry in log if entry[0] in ("step", "capture") and start <= entry[2] <= end]
    assert inside == [], f"{len(inside)} uses of the solver while a reset was building, first {inside[:3]}"
    # the save waited for the reset and captured the new run, with no step inside its capture
    capture = next(t for kind, _, t in log if kind == "capture")
    captured = next(t for kind, _, t in log if kind == "captured")
    assert next(name for kind, name, _ in log if kind == "capture") == "new"
    assert not [e for e in log if e[0] == "step" and capture <= e[2] <= captured]


def test_a_bag_takes_only_the_run_it_was_opened_for(tmp_path):
    """A bag opened for one run and left open by a race (the run swapped under it) takes none of
    the next run's messages, and a reset finishes the old run's bag."""
    log = []
    s = _session(StandIn("old", log))
    try:
        s.start_recording(tmp_path)
        time.sleep(0.05)
        recorder = s.recorder
        s.replace(lambda: StandIn("new", log))
        time.sleep(0.05)
        # the old bag is finished, and holds the old run's topic only
        assert recorder.closed == {"status": "reset"}
        assert recorder.topics and set(recorder.topics) == {"/old"}
        # a bag opened now is the new run's
        s.start_recording(tmp_path)
        time.sleep(0.05)
        assert set(s.recorder.topics) == {"/new"}
    finally:
        s.close()


def test_a_request_that_waits_too_long_for_the_solver_is_refused(tmp_path, monkeypatch):
    """A save asked while a reset builds for longer than OWNER_WAIT is refused, naming the reset;
    the run that was there goes on."""
    monkeypatch.setattr(session_mod, "OWNER_WAIT", 0.1)
    log = []
    s = _session(StandIn("old", log))
    try:
        release = threading.Event()

        def build():
            release.wait(5.0)
            return StandIn("new", log)

        resetter = threading.Thread(target=s.replace, args=(build,))
        resetter.start()
        time.sleep(0.05)
        ok, why = s.save_state(tmp_path / "state.gpusph")
        release.set()
        resetter.join()
    finally:
        s.close()
    assert not ok and "busy with a reset" in why, why
    assert not (tmp_path / "state.gpusph").exists()


class SlowBatch(StandIn):
    """A stand-in whose output takes 0.3 s, the host's time moving only at its end, as a batch of
    steps on a device does (the host reads the clock once an output)."""

    def step_output(self, interrupt, limit=None):
        time.sleep(0.3)
        return super().step_output(interrupt, limit)


def test_paused_is_said_only_once_the_batch_under_way_has_ended(tmp_path):
    """A pause asked in the middle of a batch: the state reads running until the batch ends, then
    paused, and from then on the simulated time holds. (A node's /diagnostics said paused at t = 0
    and then t = 0.0016 s, its first batch slowed by a kernel compile.)"""
    s = _session(SlowBatch("a", []))
    try:
        time.sleep(0.1)  # the first batch is under way
        assert s.set_paused(True)[0]
        assert s.state == "running"
        deadline = time.monotonic() + 5.0
        while s.state != "paused" and time.monotonic() < deadline:
            time.sleep(0.01)
        held = s.run.solver.time
        assert s.state == "paused" and held > 0.0
        time.sleep(0.7)  # two batches' worth
        assert s.run.solver.time == held and s.state == "paused"
    finally:
        s.close()
