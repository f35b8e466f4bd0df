"""Sweeps on Dask distributed (gpusph_ros.study.sweep and .case): a 4-case study on a local
cluster of 2 worker processes, a case made to fail, a worker killed mid-study, and a rerun that
runs nothing again. DamBreak 1 at 6 cm (4,385 particles) for 0.2-0.3 s keeps each case seconds long."""
import os
import signal
import threading
import time

import pytest
import yaml
from distributed import Client, LocalCluster

from gpusph_ros.scenes.build import build
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.study import charts, table
from gpusph_ros.study.schema import load_study
from gpusph_ros.study.sweep import sweep, worker_device

pytestmark = pytest.mark.study


def _study(tmp_path, end_time, c0s):
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump({
        "name": "small", "scenes": ["dambreak1_thesis"],
        "scenarios": {"defaults": {}, "quadratic": {"kernel": "quadratic"}},
        "grid": {"dx": [0.06], "c0": c0s}, "set": {"end_time": end_time},
        "metrics": ["peak_velocity", "velocity_rms", "peak_force_body"], "out": str(tmp_path / "out")}))
    return load_study(path)


@pytest.fixture(scope="module")
def cluster():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as c:
        yield c


def test_a_four_case_study_with_a_failing_case_completes_and_is_tabulated(cluster, tmp_path, reference_data):
    # c0 = 0.3 m/s is far below 10 sqrt(g H): the density check stops those runs at once
    study = _study(tmp_path, 0.2, [0.0, 0.3])
    lines = []
    with Client(cluster) as client:
        rows = sweep(study, client=client, progress=lines.append)
    assert [r["case"] for r in rows] == [c.name for c in study.cases()]
    status = {r["case"]: r["status"] for r in rows}
    assert [s for n, s in status.items() if "c0=0.3" not in n] == ["completed", "completed"]
    assert all(s.startswith("failed: health check") for n, s in status.items() if "c0=0.3" in n)
    assert "done 2, failed 2, remaining 0" in lines[-1]
    ok = [r for r in rows if r["status"] == "completed"]
    built = len(build(load_scene("dambreak1_thesis"), dx=0.06).particles)
    for r in ok:
        assert r["particles"] == built and r["steps"] > 0 and r["wall_time_s"] > 0 and r["mipps"] > 0
        assert r["particle_steps"] == r["particles"] * r["steps"]
        assert r["peak_velocity_experiment"] == 2.21 and r["peak_velocity_error_pct"] is not None
        assert r["device"] == "cpu" and r["precision"] == "float32"
        assert (tmp_path / "out/cases" / r["case"] / "bag/metadata.yaml").is_file()
    written = table.write(rows, study.out) + charts.write(rows, study.metrics, study.out / "charts", reference_data)
    assert all(p.is_file() for p in written) and len(written) == 2 + 3 * 3  # a table twice, 3 charts a metric
    # a rerun runs nothing: every case has finished (completed or failed)
    lines.clear()
    with Client(cluster) as client:
        again = sweep(study, client=client, progress=lines.append)
    assert again == rows and "4 already finished, 0 to run" in lines[0] and len(lines) == 1


def test_a_worker_killed_mid_study_leaves_every_case_done_or_reported(cluster, tmp_path):
    study = _study(tmp_path, 0.3, [0.0])  # four healthy cases: four kernel / viscosity choices
    study.scenarios["wendland"] = {"kernel": "wendland"}
    study.scenarios["laminar"] = {"viscosity": "laminar"}
    assert len(study.cases()) == 4
    result = {}
    with Client(cluster) as client:
        runner = threading.Thread(target=lambda: result.update(rows=sweep(study, client=client, progress=print)))
        runner.start()
        deadline = time.monotonic() + 120.0
        busy = {}
        while not any(busy.values()) and time.monotonic() < deadline:
            busy = client.processing()
            time.sleep(0.1)
        time.sleep(1.0)  # inside a case
        pids = client.run(os.getpid)
        victim = next(addr for addr, keys in client.processing().items() if keys)
        os.kill(pids[victim], signal.SIGKILL)
        runner.join(timeout=300.0)
    assert not runner.is_alive()
    rows = result["rows"]
    assert len(rows) == 4
    assert all(r["status"] == "completed" or r["status"].startswith("error") for r in rows)
    assert sum(r["status"] == "completed" for r in rows) >= 3  # the killed case is retried on a live worker
    with Client(cluster) as client:
        lines = []
        sweep(study, client=client, progress=lines.append)
    finished = sum(r["status"] == "completed" for r in rows)
    assert f"{finished} already finished" in lines[0]


def test_each_local_worker_owns_one_gpu(cluster):
    # a study on cuda runs on one worker per GPU, each on its own: worker j takes cuda:j whatever
    # case it is given (cases were given cuda:(index mod GPUs) before, so two could share a GPU)
    with Client(cluster) as client:
        workers = sorted(client.scheduler_info()["workers"])
        owned = {w: {client.submit(worker_device, 2, workers=[w], pure=False).result() for _ in range(3)}
                 for w in workers}
    assert sorted(d for devices in owned.values() for d in devices) == ["cuda:0", "cuda:1"]
