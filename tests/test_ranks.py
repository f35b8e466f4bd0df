"""One run on 2 and 3 MPI ranks steps bit for bit as on one (sph/exchange.py, issue 69 item 2).

Each case runs under ``mpiexec -n N python -m mpi4py tests/ranks_run.py``, the venv's MPICH. A rank
that raises ends the whole job (mpi4py's runner), so a failure cannot hang the suite. Rank 0 saves
the owned particles' positions, velocities and densities, in the solver's precision, with each
step's time, and the run's health census. The same scene steps as many times on one solver here
(its energy check off: a check that passes changes nothing). The comparison:
- every particle is owned by exactly one rank (the ids are the run's, once each);
- every step ends at the same time;
- the state is equal bit for bit;
- the census is the run's: its density extremes and clumped share equal, its energy to 1e-9.

The cases:
- the 2D collapse at 4 mm on 3 ranks with the slabs cut again mid-run;
- the collapse under mDBC with shifting and the walls' normal flux, and under SPS (its halo a cell
  deeper);
- a collapse in a tank periodic along the cut axis (the water crosses the period and the first and
  last ranks meet across it);
- a piston paddle and a floating box across the cuts, on the extrapolated-pressure wall (whose
  moving walls' acceleration changes hands with their particles);
- the collapse on Lennard-Jones walls, whose wall energy the census adds (each pair counted once,
  by its fluid particle's owner);
- DamBreak 1 at 5 cm in 3D, recorded by gpusph-run (below: every cloud bit for bit).
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

from gpusph_ros.scenes.build import build_run
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.scenes.settings import resolve
from gpusph_ros.sph import health

pytest.importorskip("mpi4py")
pytestmark = pytest.mark.physics

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))  # ranks_run, its state files
MPIEXEC = Path(sys.executable).parent / "mpiexec"
PERIODIC = {"name": "periodic_collapse", "dim": 2, "tank": [0.6, 0.3], "periodic": [True, False],
            "walls": "particles", "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.15, 0.15]}]}
# a piston paddle on a sinusoid pushes still water under a floating box 16 cm wide, which every cut
# of 2 or 3 ranks crosses
BODIES = {"name": "bodies_on_ranks", "dim": 2, "tank": [0.6, 0.3], "walls": "particles",
          "fluid": [{"name": "water", "lo": [0.06, 0.0], "hi": [0.6, 0.12]}],
          "obstacles": [{"name": "paddle", "lo": [0.02, 0.0], "hi": [0.05, 0.2],
                         "motion": {"type": "sinusoid", "amplitude": [0.015, 0.0], "period": 0.1, "phase_deg": -90.0}},
                        {"name": "box", "lo": [0.22, 0.08], "hi": [0.38, 0.16], "displaces_fluid": True,
                         "floating": {"density": 400.0}}]}
SCENES = {"periodic": PERIODIC, "bodies": BODIES}


def _slots(solver) -> np.ndarray:
    """The slot of each particle id."""
    slot = np.empty(solver.n, dtype=np.int64)
    slot[solver.ids.numpy()] = np.arange(solver.n)
    return slot


def _built(scene, dx: float, sets: list):
    """The particles of ``scene`` as built at ``dx`` under ``sets``."""
    sc = load_scene(scene)
    return build_run(sc, resolve(sc, sets=sets, dx=dx, end_time=10.0)).particles


def _one_rank(scene, dx: float, steps: int, sets: list) -> dict:
    sc = load_scene(scene)
    solver = build_run(sc, resolve(sc, sets=sets, dx=dx, end_time=10.0, energy_growth_ratio=0.0)).solver()
    times = [solver.step() for _ in range(steps)]
    slot = np.empty(solver.n, dtype=np.int64)
    slot[solver.ids.numpy()] = np.arange(solver.n)
    return {"times": np.array(times), **{k: getattr(solver, k).numpy()[slot] for k in ("pos", "vel", "rho")},
            **{f"peak.{k}": np.nan if v is None else v for k, v in solver.health_peaks.items()},
            "census": solver._census_host}


def _on_ranks(ranks: int, scene, dx: float, steps: int, sets: list, out: Path, *options) -> dict:
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    done = subprocess.run([str(MPIEXEC), "-n", str(ranks), sys.executable, "-m", "mpi4py", str(HERE / "ranks_run.py"),
                           str(out), str(scene), str(dx), str(steps), *sets, *options], capture_output=True,
                          text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return dict(np.load(out))


@pytest.mark.parametrize("scene, dx, steps, sets, ranks", [
    ("collapse_2d", 0.004, 150, ["boundary=mdbc", "shifting=true", "wall_flux=normal"], (2,)),
    ("collapse_2d", 0.004, 150, ["viscosity=sps"], (3,)),
    ("periodic", 0.005, 150, [], (3,)),
    ("bodies", 0.005, 150, ["boundary=adami"], (3,)),
    ("collapse_2d", 0.004, 150, ["boundary=lennard_jones"], (2,)),
])
def test_a_run_on_ranks_steps_bit_for_bit_as_on_one(scene, dx, steps, sets, ranks, tmp_path):
    name = scene
    if name in SCENES:
        scene = tmp_path / f"{name}.yaml"
        scene.write_text(yaml.safe_dump(SCENES[name]))
    one = _one_rank(scene, dx, steps, sets)
    assert np.abs(one["vel"]).max() > 0.3  # the water moves
    runs = {n: _on_ranks(n, scene, dx, steps, sets, tmp_path / f"ranks{n}.npz") for n in ranks}
    if name == "bodies":
        # the floating box moves, and a state taken on 3 ranks (its bodies' with it) goes on on 2
        box = _built(scene, dx, sets).body == 1
        assert np.abs(one["vel"][box]).max() > 1.0e-3
        state = str(tmp_path / "state.npz")
        _on_ranks(3, scene, dx, 60, sets, tmp_path / "first.npz", "--save-at", "59", "--state", state)
        resumed = _on_ranks(2, scene, dx, steps - 59, sets, tmp_path / "resumed.npz", "--resume", state)
        runs["2 from a state of 3"] = resumed | {"times": np.concatenate([one["times"][:59], resumed["times"]])}
    for n, many in runs.items():
        assert np.array_equal(many["gid"], np.arange(len(one["pos"]))), n
        assert np.array_equal(many["times"], one["times"]), n
        for key in ("pos", "vel", "rho"):
            assert many[key].dtype == one[key].dtype and np.array_equal(many[key], one[key]), (n, key)
        # the census is the run's on every rank: the density's extremes and the clumped share exact,
        # the energy (the repulsive walls' among it, each pair counted by its fluid particle's owner)
        # and its largest growth added in another order, so to round-off
        for key in ("peak_clumped_fraction", "min_density_ratio", "max_density_ratio"):
            assert many[f"peak.{key}"] == one[f"peak.{key}"], (n, key)
        assert many["peak.peak_energy_growth"] == pytest.approx(one["peak.peak_energy_growth"], abs=1e-9), n
        energy = (health.ENERGY, health.ENERGY_START, health.WORK)
        assert many["census"][list(energy)] == pytest.approx(one["census"][list(energy)], rel=1e-9, abs=1e-12), n


def test_slabs_cut_again_mid_run_keep_the_run_bit_for_bit(tmp_path):
    """The collapse on 3 ranks for 600 steps (0.11 s), the slabs cut again wherever the fullest rank
    owns more than 5% over the mean, tried at most every 40 steps: as its water runs along the tank,
    the second cut moves a cell (from cell 11 to 12, measured; issue 69 item 3), and the run steps
    as on one rank, bit for bit."""
    one = _one_rank("collapse_2d", 0.004, 600, [])
    many = _on_ranks(3, "collapse_2d", 0.004, 600, [], tmp_path / "recut.npz", "--rebalance", "0.05", "--every", "40")
    assert int(many["recuts"]) >= 1 and not np.array_equal(many["first_cuts"], many["last_cuts"])
    assert np.array_equal(many["gid"], np.arange(len(one["pos"])))
    assert np.array_equal(many["times"], one["times"])
    for key in ("pos", "vel", "rho"):
        assert np.array_equal(many[key], one[key]), key



def _gpusph_run_command(ranks: int, *arguments, quiet: bool = True) -> list:
    command = [str(Path(sys.executable).parent / "gpusph-run"), *arguments, *["--quiet"] * quiet]
    return [str(MPIEXEC), "-n", str(ranks), *command] if ranks > 1 else command


def _gpusph_run(ranks: int, out: Path, scene: str, sets: list) -> str:
    """gpusph-run of ``scene``, under ``mpiexec -n ranks`` where ranks > 1; what it printed."""
    done = subprocess.run(_gpusph_run_command(ranks, scene, "--out", str(out), *[f"--set={s}" for s in sets]),
                          capture_output=True, text=True, timeout=300, env={**os.environ, "OMP_NUM_THREADS": "1"})
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return done.stdout


@pytest.fixture(scope="module")
def one_rank_runs(tmp_path_factory):
    """gpusph-run on one rank, once a module for each scene and settings asked: its bag folder."""
    made = {}

    def run(scene: str, sets: list) -> Path:
        key = (scene, *sets)
        if key not in made:
            made[key] = tmp_path_factory.mktemp("one") / "bag"
            _gpusph_run(1, made[key], scene, sets)
        return made[key]
    return run


@pytest.mark.parametrize("scene, sets, metrics", [
    ("dambreak1_lab", ["dx=0.05", "end_time=0.3"], 8),
    ("lobovsky_2d", ["dx=0.025", "end_time=0.5", "shepard_every=40", "output_rate=200"], 4),
])
def test_gpusph_run_on_two_ranks_records_what_one_rank_records(scene, sets, metrics, tmp_path, one_rank_runs):
    """``mpiexec -n 2 gpusph-run`` (issue 69 items 4-5): the first line names the ranks and the cut,
    rank 0 records one run, and the recording is one rank's:
    - every particle cloud and every probe's, gauge's, sensor's and face load's reading bit for bit
      (a reading at a point is its owner's: measure/ranks.py). Lobovsky's wall sensors read every
      step, after the halo's refresh on ranks and after the Shepard filter on both;
    - every sum over particles (the wrench, the pressure blocks) within 1e-6 of the series' largest
      value: each rank sums its own particles, and the ranks' sums are added in another order;
    - gpusph-analyze's metrics the same (within 1e-6: the forces are sums);
    - the health census the run's: the clumped peak and the density's extremes equal, the energy's
      growth within 1e-6 (each rank's energy added in rank order)."""
    from gpusph_ros.analysis import bag
    from gpusph_ros.analysis.report import analyse

    said = _gpusph_run(2, tmp_path / "two", scene, sets).splitlines()[0]
    assert "2 ranks along x" in said and "rank 1 cells" in said, said
    one, two = bag.read(one_rank_runs(scene, sets)), bag.read(tmp_path / "two")
    assert one.clock == two.clock and len(one.clouds) == len(two.clouds) > 2
    for k in range(len(one.clouds)):
        a, b = one.cloud(k), two.cloud(k)
        assert (a.width, a.fields, a.header) == (b.width, b.fields, b.header) and bytes(a.data) == bytes(b.data), k
    assert set(one.series) == set(two.series)
    summed = ("wrench", "pressure_blocks", "force_arrows")
    for topic, series in one.series.items():
        for key, values in series.items():
            x, y = np.asarray(values, dtype=float), np.asarray(two.series[topic][key], dtype=float)
            if any(s in topic for s in summed):
                assert np.abs(x - y).max() <= 1e-6 * np.abs(x).max(), (topic, key)
            else:
                assert np.array_equal(x, y), (topic, key)
    if "sensor_1" in str(one.series):
        assert max(np.max(s["v"]) for name, s in one.series.items() if "sensor" in name) > 1000.0  # the surge hit
    for key in ("peak_clumped_fraction", "min_density_ratio", "max_density_ratio"):  # the census is the run's
        assert one.result[key] == two.result[key], key
    assert float(one.result["peak_energy_growth"]) == pytest.approx(float(two.result["peak_energy_growth"]),
                                                                      rel=1e-6, abs=1e-12)
    rows = [analyse(path, rec=rec)[0]["metrics"] for path, rec in ((one_rank_runs(scene, sets), one),
                                                                     (tmp_path / "two", two))]
    assert [m["key"] for m in rows[0]] == [m["key"] for m in rows[1]] and len(rows[0]) >= metrics
    for a, b in zip(*rows):
        assert a["value"] == pytest.approx(b["value"], rel=1e-6, abs=1e-9, nan_ok=True), a["key"]


def test_a_state_taken_on_three_ranks_goes_on_bit_for_bit_on_two_and_on_one(tmp_path):
    """The collapse on 3 ranks for 250 steps, its state (sph/portable.py) taken after 100: taken up
    on 2 ranks, and on one solver, it steps the other 150 as the run that took it, bit for bit
    (issue 69 item 4: a checkpoint does not depend on the rank count). The lists are built again
    from where the particles stood at the last build: built from where they stand now, the same
    state goes on otherwise (measured: at step 100 and 250; at 150 and 200 no particle had changed
    cell since the build)."""
    import ranks_run

    from gpusph_ros.sph import portable

    whole = _on_ranks(3, "collapse_2d", 0.004, 250, [], tmp_path / "three.npz", "--save-at", "100", "--state",
                      str(tmp_path / "state.npz"))
    two = _on_ranks(2, "collapse_2d", 0.004, 150, [], tmp_path / "two.npz", "--resume", str(tmp_path / "state.npz"))
    assert np.array_equal(two["times"], whole["times"][100:])
    for key in ("pos", "vel", "rho"):
        assert np.array_equal(two[key], whole[key]), key
    state = ranks_run.load_state(tmp_path / "state.npz")
    sc = load_scene("collapse_2d")
    for lists_from, same in (("x_build", True), ("pos", False)):
        model = build_run(sc, resolve(sc, dx=0.004, end_time=10.0, energy_growth_ratio=0.0))
        solver = model.solver()
        assert portable.mismatch(model.config, model.particles, state) == ""
        portable.put(solver, state["particles"] | {"x_build": state["particles"][lists_from]}, state["counters"],
                     state["bodies"])
        times = [solver.step() for _ in range(150)]
        slot = np.empty(solver.n, dtype=np.int64)
        slot[solver.ids.numpy()] = np.arange(solver.n)
        assert np.array_equal(times, whole["times"][100:]) or not same
        assert np.array_equal(solver.pos.numpy()[slot], whole["pos"]) == same, lists_from
        if same:
            for key in ("vel", "rho"):
                assert np.array_equal(getattr(solver, key).numpy()[slot], whole[key]), key


def test_a_state_that_is_not_the_runs_is_refused_naming_what_differs():
    """portable.mismatch reads a state from a file before any solver takes it up: one solver's own
    state (its particles by id, its counters) fits, and put back into the same solver 10 steps
    later (its slots sorted since) it steps the same 10 steps again, bit for bit; an edited one is
    refused, saying why."""
    from gpusph_ros.sph import portable

    sc = load_scene("collapse_2d")
    model = build_run(sc, resolve(sc, dx=0.01, end_time=10.0))
    solver = model.solver()
    for _ in range(5):
        solver.step()
    rows = {k: a.numpy()[_slots(solver)].copy() for k, a in portable.particle_arrays(solver).items()}
    state = {"format": portable.FORMAT, "particles": rows, "counters": portable.counters(solver), "bodies": {}}
    assert portable.mismatch(model.config, model.particles, state) == ""
    first = [solver.step() for _ in range(10)]
    ahead = {k: getattr(solver, k).numpy()[_slots(solver)].copy() for k in ("pos", "vel", "rho")}
    portable.put(solver, state["particles"], state["counters"], state["bodies"])
    assert [solver.step() for _ in range(10)] == first
    for key, values in ahead.items():
        assert np.array_equal(getattr(solver, key).numpy()[_slots(solver)], values), key

    def edited(key, change, counters=False):
        part = "counters" if counters else "particles"
        values = dict(state[part])
        values[key] = change(values[key].copy())
        return portable.mismatch(model.config, model.particles, state | {part: values})

    assert "mass is not the run's" in edited("mass", lambda a: a * 2.0)
    assert "kinds are not the run's" in edited("ptype", lambda a: np.zeros_like(a))
    assert "not a number" in edited("pos", lambda a: np.where(a == a.max(), np.nan, a))
    assert "faster than 10 sound speeds" in edited("vel", lambda a: a + 1.0e4)
    assert "pos is not (" in edited("pos", lambda a: a[:-1])
    assert "rho is not (" in edited("rho", lambda a: a.astype(np.float64))
    assert "healthy run" in edited("_steps", lambda a: a - 100, counters=True)
    assert "not a run's state" in portable.mismatch(model.config, model.particles, {"format": "x"})


@pytest.mark.parametrize("stopped, resumed", [(2, 1), (1, 2)])
def test_a_run_stopped_on_some_ranks_resumes_on_others_to_one_ranks_end(stopped, resumed, tmp_path, one_rank_runs):
    """DamBreak 1 at 5 cm under ``gpusph-run``, stopped by Ctrl-C (under ``mpiexec -n 2``, SIGINT to
    mpiexec, which sends it to every rank: every rank stops at the same step), the bag whole and the
    run's state written (on ranks by rank 0, sph/portable.py). ``gpusph-run --resume`` on the other
    count of ranks goes on from it (one solver's state taken up by ranks through
    portable.of_solver_state), and its last cloud is the uninterrupted run's, bit for bit (3 ranks to
    2 and to 1: the test above)."""
    from gpusph_ros.analysis import bag

    sets = ["dx=0.05", "end_time=0.3"]
    out = tmp_path / "stopped"
    job = subprocess.Popen(_gpusph_run_command(stopped, "dambreak1_lab", "--out", str(out),
                                               *[f"--set={s}" for s in sets], quiet=False),
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           env={**os.environ, "OMP_NUM_THREADS": "1"})
    said = ""
    while "t = 0.1" not in said:  # a progress line at t = 0.1x s (every 2 outputs in a log): then Ctrl-C
        line = job.stdout.readline()
        assert line, said
        said += line
    job.send_signal(signal.SIGINT)
    rest, why = job.communicate(timeout=60)
    said += rest
    assert job.returncode == 2 and "interrupted" in said and (out / "checkpoint.npz").is_file(), said + why
    halted = bag.read(out)
    assert halted.complete and halted.result["status"] == "interrupted"
    assert 0.0 < float(halted.result["simulated_time_s"]) < 0.3
    done = subprocess.run(_gpusph_run_command(resumed, "--resume", str(out)), capture_output=True, text=True,
                          timeout=300, env={**os.environ, "OMP_NUM_THREADS": "1"})
    assert done.returncode == 0 and "resumed at t = 0.1" in done.stdout, done.stdout + done.stderr
    one, went_on = bag.read(one_rank_runs("dambreak1_lab", sets)), bag.read(out)
    assert went_on.complete and one.clock == went_on.clock
    a, b = one.cloud(len(one.clouds) - 1), went_on.cloud(len(went_on.clouds) - 1)
    assert a.header == b.header and bytes(a.data) == bytes(b.data)


def _rank_processes(command: str) -> dict:
    """{rank: pid} of the running processes whose command line holds ``command``, started by mpiexec
    (their environment's PMI_RANK)."""
    found = {}
    for proc in Path("/proc").iterdir():
        try:
            env = dict(e.split(b"=", 1) for e in (proc / "environ").read_bytes().split(b"\0") if b"=" in e)
            cmdline = (proc / "cmdline").read_bytes()
        except (OSError, ValueError):
            continue
        if b"PMI_RANK" in env and command.encode() in cmdline:
            found[int(env[b"PMI_RANK"])] = int(proc.name)
    return found


@pytest.mark.skipif(not Path("/proc/self/environ").exists(), reason="reads the ranks' environments from /proc")
def test_a_rank_that_dies_ends_the_whole_job_at_once_with_a_message(tmp_path):
    """Rank 1 of ``mpiexec -n 2 gpusph-run`` killed (SIGKILL, no chance to say anything) once the
    run records: mpiexec ends the job within seconds (measured: at once) and says which process died
    and how; no rank is left running, none waits in a collective for the dead one."""
    out = tmp_path / "killed"
    job = subprocess.Popen(_gpusph_run_command(2, "dambreak1_lab", "--out", str(out), "--set=dx=0.05",
                                               "--set=end_time=5.0"), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True, env={**os.environ, "OMP_NUM_THREADS": "1"})
    try:
        deadline = time.monotonic() + 120
        while not (list(out.glob("*.mcap")) and len(_rank_processes(str(out))) == 2):
            assert job.poll() is None and time.monotonic() < deadline, job.communicate()
            time.sleep(0.2)
        ranks = _rank_processes(str(out))
        killed = time.monotonic()
        os.kill(ranks[1], signal.SIGKILL)
        said, _ = job.communicate(timeout=30)
    finally:
        job.kill()
    assert time.monotonic() - killed < 10 and job.returncode != 0
    assert "BAD TERMINATION" in said and "signal 9" in said, said[-2000:]
    assert _rank_processes(str(out)) == {}


@pytest.mark.parametrize("limits, check", [
    (["energy_growth_ratio=0.00002"], "energy_growth"),
    (["rho_max_ratio=1.02", "max_excluded_fraction=0.01"], "excluded_fraction"),
])
def test_a_check_on_the_whole_run_fails_every_rank_as_it_fails_one(limits, check, tmp_path):
    """The checks on the whole run's figures (sph/exchange.py): DamBreak 1 at 5 cm fails each at the
    same step, with the same message, on 2 ranks as on one, and both bags close whole with that
    status:
    - the energy check on the census of every rank (Solver.each_census), with a slack of 2e-5 M g H;
    - the excluded fraction on every rank's exclusions added up each step (Solver.each_total): with
      the density bounded at 1.02 rho0 the impact excludes fluid from 0.19 s, and past 1% of its mass
      (step 195) the run fails. When each rank checked its own share, rank 1 alone failed, later."""
    from gpusph_ros.analysis import bag

    status = []
    for ranks in (1, 2):
        out = tmp_path / f"bag{ranks}"
        done = subprocess.run(_gpusph_run_command(ranks, "dambreak1_lab", "--out", str(out), "--set=dx=0.05",
                                                  "--set=end_time=0.3", *[f"--set={s}" for s in limits]),
                              capture_output=True, text=True, timeout=300, env={**os.environ, "OMP_NUM_THREADS": "1"})
        assert done.returncode == 2, done.stdout + done.stderr
        rec = bag.read(out)
        assert rec.complete
        status.append(rec.result["status"])
    assert status[0] == status[1] and f"health check '{check}' failed at step" in status[0], status
