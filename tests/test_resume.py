"""Checkpoint and resume (`gpusph-run --resume DIR`): a run stopped, or killed, and resumed records
what the same run never stopped records, bit for bit on the CPU, and its bag (files _0, _1, ...)
reads whole with rosbags and the analysis."""
import copy
import os
import pickle
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from gpusph_ros.analysis.bag import read
from gpusph_ros.output.messages import cloud_arrays
from gpusph_ros.runner import CHECKPOINT_FILE, PICKLED_CHECKPOINT, Checkpoints, Run, resume
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.scenes.settings import resolve

pytestmark = pytest.mark.ros

REPO = Path(__file__).resolve().parents[1]
# collapse_2d: 1,059 particles, about 1,650 steps, on the eager loop, which asks a stop before every
# step (a small run's replayed loop asks every 64, and not at all where an output comes first)
SETS = ["dx=0.004", "end_time=0.3", "particle_rate=50", "step_graph=off"]


def _same_recordings(a, b):
    """Every measurement, clock tick and cloud of recording ``a`` is in ``b``, equal; ``b`` may hold
    the latched messages once more (a resumed file opens with them)."""
    ra, rb = read(a), read(b)
    assert rb.complete and rb.result["status"] == ra.result["status"] == "completed"
    assert rb.result["steps"] == ra.result["steps"]
    assert set(ra.series) == set(rb.series)
    for topic, series in ra.series.items():
        for key, values in series.items():
            assert np.array_equal(values, rb.series[topic][key]), (topic, key)
    assert ra.clock == rb.clock
    assert [t for t, _ in ra.clouds] == [t for t, _ in rb.clouds]
    for k in range(len(ra.clouds)):
        ca, cb = cloud_arrays(ra.cloud(k)), cloud_arrays(rb.cloud(k))
        assert all(np.array_equal(ca[f], cb[f]) for f in ca), k
    return ra, rb


def test_a_run_stopped_between_steps_and_resumed_equals_one_never_stopped(tmp_path):
    scene = load_scene("collapse_2d")
    whole = Run(scene, resolve(scene, sets=SETS))
    whole.execute(whole.open_recording(tmp_path / "whole"))
    invocation = {"scene": "collapse_2d", "run_config": [], "sets": SETS}
    first = Run(scene, resolve(scene, sets=SETS))
    recorder = first.open_recording(tmp_path / "stopped")
    asked = {"n": 0}

    def stop():  # between two steps, 700 steps in, inside an output interval
        asked["n"] += 1
        return asked["n"] > 700

    assert first.execute(recorder, stop=stop)["status"] == "interrupted"
    assert 0.0 < first.solver.time < 0.3
    Checkpoints(tmp_path / "stopped", invocation, recorder, 0.0).write(first)
    second, recorder, _ = resume(tmp_path / "stopped")
    assert second.solver.time == first.solver.time and second.next_output == first.next_output
    assert second.execute(recorder)["status"] == "completed"
    a, b = whole.solver.snapshot(), second.solver.snapshot()
    assert all(np.array_equal(a[k], b[k]) for k in a)  # the final state, bit for bit
    _same_recordings(tmp_path / "whole", tmp_path / "stopped")
    assert sorted(p.name for p in (tmp_path / "stopped").glob("*.mcap")) == ["stopped_0.mcap", "stopped_1.mcap"]
    with AnyReader([tmp_path / "whole"]) as reader:
        n = reader.message_count
    with AnyReader([tmp_path / "stopped"]) as reader:  # metadata.yaml lists both files
        assert reader.message_count == sum(1 for _ in reader.messages()) == n + 2  # the latched pair again


def _cli(*args, **kw):
    return subprocess.run([sys.executable, "-m", "gpusph_ros.cli", "run", *args], capture_output=True, text=True,
                          cwd=REPO, timeout=300, **kw)


def test_a_killed_run_resumes_from_its_last_checkpoint_and_the_file_is_cut_back_to_it(tmp_path):
    """SIGKILL after a checkpoint and more outputs: --resume cuts the file back to what the checkpoint
    counted and goes on; the recording equals the uninterrupted run's."""
    sets = [a for s in SETS + ["checkpoint_interval=0.5", "end_time=0.6"] for a in ("--set", s)]
    whole = _cli("collapse_2d", *sets, "--quiet", "--out", str(tmp_path / "whole"))
    assert whole.returncode == 0, whole.stdout + whole.stderr
    assert not (tmp_path / "whole" / CHECKPOINT_FILE).exists()  # a completed run removes it
    out = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-m", "gpusph_ros.cli", "run", "collapse_2d", *sets, "--quiet",
                             "--out", str(out)], cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 240
    while not (out / CHECKPOINT_FILE).exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.3)  # more outputs after the checkpoint, which the resumed run must not repeat
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert (out / CHECKPOINT_FILE).exists(), "the run ended before its first checkpoint"
    resumed = _cli("--resume", str(out), "--quiet")
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    assert "resumed at t = " in resumed.stdout
    _same_recordings(tmp_path / "whole", out)


def test_resume_refuses_what_it_cannot_continue(tmp_path):
    out = _cli("--resume", str(tmp_path))
    assert out.returncode == 1 and f"has no {CHECKPOINT_FILE}" in out.stderr, out.stderr
    (tmp_path / CHECKPOINT_FILE).write_bytes(b"not a checkpoint")
    out = _cli("--resume", str(tmp_path))
    assert out.returncode == 1 and "not a gpusph_ros state file" in out.stderr and "Traceback" not in out.stderr, \
        out.stderr
    out = _cli("--resume", str(tmp_path), "--set", "dx=0.01")
    assert out.returncode == 2 and "--resume DIR alone" in out.stderr, out.stderr
    # a checkpoint that is a link to one elsewhere: refused before anything changes, where it resumed and
    # Ctrl-C then ended on a traceback, writing no checkpoint (issue 58)
    real = tmp_path / "real"
    _stopped_run(real)
    linked = tmp_path / "linked"
    shutil.copytree(real, linked)
    (linked / CHECKPOINT_FILE).unlink()
    (linked / CHECKPOINT_FILE).symlink_to(real / CHECKPOINT_FILE)
    before = sorted(p.name for p in linked.iterdir())
    out = _cli("--resume", str(linked))
    assert out.returncode == 1 and "is a symbolic link" in out.stderr and "Traceback" not in out.stderr, out.stderr
    assert sorted(p.name for p in linked.iterdir()) == before


class _Payload:
    """A pickle that runs a shell command when it is loaded."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return os.system, (f"touch {self.marker}",)


def _stopped_run(folder, stop_after=700):
    """A recorded run of collapse_2d stopped between two steps with its checkpoint written; the run."""
    scene = load_scene("collapse_2d")
    run = Run(scene, resolve(scene, sets=SETS))
    recorder = run.open_recording(folder)
    asked = {"n": 0}

    def stop():
        asked["n"] += 1
        return asked["n"] > stop_after

    assert run.execute(recorder, stop=stop)["status"] == "interrupted"
    Checkpoints(folder, {"scene": "collapse_2d", "run_config": [], "sets": SETS}, recorder, 0.0).write(run)
    return run


def test_a_checkpoint_carrying_code_or_cut_short_is_refused_and_runs_nothing(tmp_path):
    """A pickle placed where --resume reads (the new checkpoint's name or the old one's) does nothing
    and is refused saying why; so is the old format's own file, and a checkpoint cut short."""
    marker = tmp_path / "ran"
    payload = pickle.dumps({"invocation": _Payload(marker)}, protocol=pickle.HIGHEST_PROTOCOL)
    for name, words in ((CHECKPOINT_FILE, "a Python pickle"), (PICKLED_CHECKPOINT, "never loads a pickle")):
        folder = tmp_path / name.replace(".", "_")
        folder.mkdir()
        (folder / name).write_bytes(payload)
        out = _cli("--resume", str(folder))
        assert out.returncode == 1 and words in out.stderr and "Traceback" not in out.stderr, out.stderr
        assert not marker.exists()
    folder = tmp_path / "cut"
    _stopped_run(folder)
    data = (folder / CHECKPOINT_FILE).read_bytes()
    (folder / CHECKPOINT_FILE).write_bytes(data[:len(data) // 2])
    out = _cli("--resume", str(folder))
    assert out.returncode == 1 and "cut short or damaged" in out.stderr and "Traceback" not in out.stderr, out.stderr


def test_a_bag_cut_after_its_checkpoint_is_not_resumed_with_a_gap(tmp_path):
    """The bag's file halved after the checkpoint: the resumed recording would jump in /clock from
    where the file now ends to the checkpoint's time. --resume refuses, saying so, and leaves the
    folder as it was; --repair then makes what the bag holds readable."""
    folder = tmp_path / "halved"
    run = _stopped_run(folder)
    mcap = folder / "halved_0.mcap"
    size = mcap.stat().st_size
    with open(mcap, "r+b") as f:
        f.truncate(size // 2)
    before = sorted((p.name, p.stat().st_size) for p in folder.iterdir())
    with pytest.raises(ValueError, match="would leave a gap in the recording") as err:
        resume(folder)
    assert f"at t = {run.solver.time:.4f} s" in str(err.value)
    assert sorted((p.name, p.stat().st_size) for p in folder.iterdir()) == before
    out = _cli("--resume", str(folder))
    assert out.returncode == 1 and "cannot be resumed" in out.stderr and "Traceback" not in out.stderr, out.stderr
    repaired = subprocess.run([sys.executable, "-m", "gpusph_ros.cli", "analyze", "--repair", str(folder)],
                              capture_output=True, text=True, cwd=REPO, timeout=120)
    assert repaired.returncode == 0 and "repaired" in repaired.stdout, repaired.stdout + repaired.stderr
    clock = read(folder).clock
    assert len(clock) == 0 or (np.diff(clock) > 0).all()  # what is left has no gap and no jump back


def test_a_run_of_a_scene_file_resumes_from_another_folder(tmp_path):
    """The invocation keeps a scene file by its absolute path: --resume from elsewhere finds it."""
    scene = tmp_path / "my_collapse.yaml"
    scene.write_text((REPO / "config/scenes/collapse_2d.yaml").read_text().replace("name: collapse_2d",
                                                                                 "name: my_collapse"))
    work = tmp_path / "work"
    work.mkdir()
    sets = [a for s in ["dx=0.01", "end_time=1.0"] for a in ("--set", s)]
    proc = subprocess.Popen([sys.executable, "-m", "gpusph_ros.cli", "run", "my_collapse.yaml", *sets, "--quiet",
                             "--out", str(work / "bag")], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    while not (work / "bag" / "metadata.yaml").exists() and proc.poll() is None:
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    out = proc.communicate(timeout=120)[0]
    if "completed" in out:
        pytest.skip("the run ended before the stop arrived")  # a 0.2 s run on a fast machine
    assert "checkpoint: " in out, out
    resumed = subprocess.run([sys.executable, "-m", "gpusph_ros.cli", "run", "--resume", str(work / "bag"), "--quiet"],
                             cwd=work, capture_output=True, text=True, timeout=300, env={**os.environ,
                                                                                        "PYTHONPATH": str(REPO)})
    assert resumed.returncode == 0 and "my_collapse" in resumed.stdout, resumed.stdout + resumed.stderr


def test_a_checkpoint_with_edited_numbers_is_refused_and_the_folder_left_as_it_was(tmp_path):
    """A next output of -1e9 published 900 empty outputs a second, an output rate of 1e12 likewise,
    a stamps' origin of 1e30 made every output fail, a NaN time ran from t = nan s, and a message
    count of 0 or -5 emptied the bag's file: each is refused by name, before the folder changes."""
    from gpusph_ros.output import state_file

    folder = tmp_path / "edited"
    _stopped_run(folder)
    path = folder / CHECKPOINT_FILE
    good = state_file.read(path, "checkpoint")
    before = sorted((p.name, p.stat().st_size) for p in folder.iterdir() if p.name != CHECKPOINT_FILE)

    def edit(change):
        state = copy.deepcopy(good)
        change(state)
        return state

    def time_nan(s):
        s["run"]["solver"]["host"]["solver"]["time"] = float("nan")

    cases = [(lambda s: s["run"].update(next_output=-1_000_000_000), "next output -1000000000 is not"),
             (lambda s: s["run"]["output"].update(output_rate=1e12), "output_rate"),
             (lambda s: s["run"].update(time_origin_ns=1e30), "stamps' origin 1e\\+30"),
             (lambda s: s["run"].update(wall=float("nan")), "wall time nan"),
             (time_nan, "solver value time is not a value"),
             (lambda s: s["recording"].update(messages=0), "count 0 are not"),
             (lambda s: s["recording"].update(messages=-5), "count -5 are not"),
             (lambda s: s["recording"].update(messages=3), "would lose them")]
    for change, why in cases:
        state_file.write(path, "checkpoint", edit(change))
        with pytest.raises(ValueError, match=why):
            resume(folder)
        assert sorted((p.name, p.stat().st_size) for p in folder.iterdir() if p.name != CHECKPOINT_FILE) == before
    state_file.write(path, "checkpoint", good)
    run, recorder, _ = resume(folder)  # the checkpoint as written still resumes
    recorder.close({"status": "stopped"})


def test_a_checkpoint_whose_settings_build_far_more_particles_is_refused_before_the_build(tmp_path):
    # its settings at dx = 0.2 mm built 6.9 M particles (4 GB, 19 s) before its arrays were refused
    from gpusph_ros.output import state_file

    folder = tmp_path / "fine"
    _stopped_run(folder)
    path = folder / CHECKPOINT_FILE
    state = state_file.read(path, "checkpoint")
    state["invocation"]["sets"] = [s if not s.startswith("dx=") else "dx=0.0002" for s in SETS]
    state_file.write(path, "checkpoint", state)
    start = time.perf_counter()
    with pytest.raises(ValueError, match=r"its settings build up to [\d,]+ particles and its state holds \d+"):
        resume(folder)
    assert time.perf_counter() - start < 10.0
