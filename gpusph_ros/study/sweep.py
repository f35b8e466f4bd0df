"""Running a study's cases on Dask distributed: a local cluster sized to the machine by default
(one single-threaded worker per core, each case's solver then using cores / workers threads; or
one worker per GPU for a study on cuda), or any running cluster by its scheduler address.

Each case is one task (``case.run_case``). Cases finished in an earlier sweep (their metrics.json
is there) are not run again. A case whose run fails is a row with that status; a task whose worker
dies is retried by the scheduler on another worker, and reported as failed if workers keep dying.
"""
import dataclasses
import time

from ..sph.launch import usable_cores
from .case import finished_row, run_case


def _local_cluster(study, device: str):
    import warp as wp
    from distributed import LocalCluster

    gpus = wp.get_cuda_device_count() if device.startswith("cuda") else 0
    workers = study.workers or gpus or usable_cores()
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
    return cluster, gpus


def worker_device(gpus: int) -> str:
    """The GPU of the worker that asks: the local cluster's worker j (named j) owns cuda:j mod gpus.
    Each worker runs one case at a time (one thread), so no two runs share a GPU while another idles,
    as they could when each case was given cuda:(its index mod gpus)."""
    from distributed import get_worker

    return f"cuda:{int(get_worker().name) % gpus}"


def _on_own_gpu(case: dict, out: str, metrics, threads: int, gpus: int):
    return run_case(case, out, metrics, threads, worker_device(gpus))


def sweep(study, scheduler=None, client=None, progress=print) -> list:
    """Run every unfinished case of ``study``; the rows of all its cases, in case order."""
    from distributed import Client, as_completed

    cases = study.cases()
    rows = {c.name: finished_row(study.out, c.name) for c in cases}
    todo = [c for c in cases if rows[c.name] is None]
    device = str(study.fixed.get("device", "cpu"))
    cluster = own_client = None
    gpus = 0
    if client is None:
        if scheduler:
            own_client = client = Client(scheduler)
        else:
            cluster, gpus = _local_cluster(study, device)
            own_client = client = Client(cluster)
    try:
        workers = max(1, len(client.scheduler_info()["workers"]))
        threads = max(1, usable_cores() // workers)
        progress(f"{study.name}: {len(cases)} cases, {len(cases) - len(todo)} already finished, {len(todo)} to run "
                 f"on {workers} worker(s) -> {study.out}")
        futures = {}
        # on GPUs each worker runs its cases on its own one; else the case's solver takes the device it names
        task, last = (_on_own_gpu, gpus) if gpus else (run_case, None)  # last: its GPUs, or no device
        for case in todo:
            future = client.submit(task, dataclasses.asdict(case), str(study.out), study.metrics, threads, last,
                                   key=f"{study.name}/{case.name}", pure=False)
            futures[future] = case
        start = time.perf_counter()
        done = failed = 0
        for future in as_completed(futures):
            case = futures[future]
            try:
                row = future.result()
            except Exception as err:  # the task's worker died, repeatedly (KilledWorker), or the cluster went
                row = {"case": case.name, "scene": case.scene, "scenario": case.scenario, **case.grid,
                       "status": f"error: {type(err).__name__}: {err}"}
            rows[case.name] = row
            done += 1
            failed += row["status"] != "completed"
            elapsed = time.perf_counter() - start
            eta = elapsed / done * (len(todo) - done)
            progress(f"[{done}/{len(todo)}] {case.name}: {row['status']} ({row.get('wall_time_s', '?')} s) | "
                     f"done {done - failed}, failed {failed}, remaining {len(todo) - done}, ETA {eta:.0f} s")
    finally:
        if own_client is not None:
            own_client.close()
        if cluster is not None:
            cluster.close()
    return [rows[c.name] for c in cases]
