"""A run of a scene, headless: build, step to each output time, measure, and hand the
messages of each output step to a recorder (and, in the node, to publishers).

Outputs fall at k / output_rate for k = 0, 1, ... up to the end time; each carries /clock
first, then the measurements of the scene's probes and bodies (and an arrow marker per body), and
every ``particle_every``-th output the particle cloud. Once per run (latched, and first in a
recording): ``~/scene``, the run's description as YAML, ``~/geometry``, the scene as markers, and
the fixed bodies' frames on ``/tf_static`` where tf2_msgs is installed; a moving body's frame goes
on ``/tf`` with each output.
"""
import dataclasses
import datetime
import functools
import math
import platform
import subprocess
import time
from importlib.metadata import version
from pathlib import Path

import numpy as np
import yaml
from std_msgs.msg import String

from .drive import BodyDriver, WrenchHold
from .measure import cloud
from .measure.suite import Measurements
from .output import frames, markers, messages, state_file
from .scenes.build import build_run, priced
from .scenes.settings import check_output
from .sph import ConfigError, bodies, checkpoint, portable
from .sph.config import shown
from .sph.device import choice
from .sph.state import T

NAMESPACE = "/sim_node"
WRENCH_TIMEOUT = 0.5  # [s] of simulated time an external wrench on a floating body is held
# QoS the node offers and the recording states (rosbag2 replays with it): /clock as Gazebo's bridge
# offers it, the cloud with depth 1 so a slow subscriber gets the newest and no backlog
CLOCK_QOS = {"reliable": True, "depth": 10}
PARTICLES_QOS = {"reliable": True, "depth": 1}
# what a subscriber that joins late still gets: the last message, kept by the publisher (/tf_static's
# QoS in tf2)
LATCHED_QOS = {"reliable": True, "depth": 1, "transient_local": True}
CHECKPOINT_FORMAT = 1


@functools.lru_cache(maxsize=None)
def revision() -> str:
    """The git revision of the package's source, where it runs from a checkout."""
    try:
        out = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], cwd=Path(__file__).parent,
                             capture_output=True, text=True, timeout=5)
    except (OSError, subprocess.SubprocessError):
        return "unknown (git not found)"
    return out.stdout.strip() if out.returncode == 0 else "unknown (not a git checkout)"


def outputs_by(t: float, rate: float) -> int:
    """The outputs at or before simulated time ``t`` at ``rate`` [Hz], the first at t = 0 (to rounding)."""
    return int(np.floor(t * rate + 1e-9)) + 1


class Run:
    """One run of ``scene`` under ``run_config`` (``scenes.settings.resolve``), on one solver or, given
    ``comm`` (an MPI communicator of more than one rank), this rank's part of it (sph/exchange.py):
    every rank steps and measures together, and rank 0 (``root``) alone gets the messages. ``state``:
    on ranks, the run's state (sph/portable.py, checked) each rank takes up as it is cut."""

    def __init__(self, scene, run_config, namespace: str = NAMESPACE, frame_id: str = "world", comm=None,
                 state: dict = None):
        self.scene, self.run_config = scene, run_config
        self.output = run_config.output
        self.namespace, self.frame_id = namespace, frame_id
        self.model = build_run(scene, run_config)
        self.ranks, across, self.cut = None, None, ""
        if comm is not None and comm.size > 1:
            from .measure.ranks import Across
            from .sph.exchange import RankedRun

            problem = state is not None and portable.mismatch(self.model.config, self.model.particles, state)
            if problem:
                raise ValueError(f"checkpoint: {problem}")
            self.ranks = RankedRun(self.model, comm, state=state)
            self.solver, across, self.cut = self.ranks.solver, Across(self.ranks), self.ranks.describe()
        else:
            self.solver = self.model.solver()
        self.root = self.ranks is None or comm.rank == 0
        self.n = self.solver.n if self.ranks is None else self.ranks.n  # the run's particles
        self.measurements = Measurements(self.solver, self.model, across)
        self.packer = self._packer(cloud.FIELDS)
        self.cloud = messages.CloudBuilder(self.packer.fields, frame_id=frame_id)
        cfg, world = self.model.config, self.model.scene
        self._force_scales = {o.name: markers.force_scale(o, cfg.dim, cfg.rho0, cfg.gravity) for o in world.obstacles}
        # the stamps' origin: 0, or the wall clock now (Output.stamps), the same for the whole run
        self.time_origin_ns = time.time_ns() if self.output.stamps == "epoch" else 0
        self.next_output = 0
        self.next_fast = 0  # the index of the next wrench-rate time (Output.wrench_rate), k / rate
        self._fast_from_now()
        self.wall = 0.0
        self.torn = False  # a Ctrl-C landed inside a step: no checkpoint of this state
        # driven bodies (drive.py) by name: their body id and their driver
        self.drivers = {o.name: (self.model.bodies[o.name], BodyDriver(o.motion, cfg.dim, o.lo, o.hi, world.tank))
                        for o in world.obstacles
                        if isinstance(o.motion, bodies.Motion) and o.motion.law == "driven"}
        # floating bodies by name: their body id and the external wrench a client holds on them
        self.wrenches = {o.name: (self.model.bodies[o.name], WrenchHold(WRENCH_TIMEOUT, o.motion.max_force,
                                                                        o.motion.max_torque))
                         for o in world.obstacles if isinstance(o.motion, bodies.Floating)}
        self._applied = {}  # the wrench each floating body's solver table holds
        self.tally = self.exclusions()  # as of the last output, for a progress line on rank 0 alone

    def push(self, body: str, stamp: float, force, torque) -> tuple:
        """An external force and torque on a floating body (drive.WrenchHold: world axes, about its
        centre of mass, stamped in simulated time): (taken, what was done or why not)."""
        if body not in self.wrenches:
            return False, (f"body: {body!r} is not a floating body of the scene (floating: "
                           f"{', '.join(self.wrenches) or 'none'})")
        return self.wrenches[body][1].command(stamp, self.solver.time, force, torque)

    def stamp_time(self, stamp: "float | None") -> float:
        """A command's stamp [s of the message clock] in simulated time: the run's time origin off
        (Output.stamps); none or zero, now."""
        return self.solver.time if not stamp else stamp - self.time_origin_ns * 1.0e-9

    def command(self, body: str, kind: str, stamp: float, a, b) -> tuple:
        """A driven body's command (drive.BodyDriver.command: a ``pose`` or a ``twist`` in the
        scene's axes, stamped in simulated time): (taken, what was done or why not)."""
        if body not in self.drivers:
            return False, (f"body: {body!r} is not a driven body of the scene (driven: "
                           f"{', '.join(self.drivers) or 'none'})")
        return self.drivers[body][1].command(kind, stamp, self.solver.time, a, b)

    @property
    def n_outputs(self) -> int:
        return outputs_by(self.output.end_time, self.output.output_rate)

    def _packer(self, fields) -> cloud.CloudPacker:
        return cloud.CloudPacker(self.solver, fields, turn=frames.turn(self.model.config.dim))

    def kind_names(self) -> dict:
        """What each value of the cloud's ``kind`` field stands for."""
        names = {cloud.FLUID_KIND: "fluid", cloud.WALL_KIND: "wall"}
        return names | {cloud.FIRST_BODY_KIND + k: f"body {name}" for name, k in self.model.bodies.items()}

    def set_output(self, **changes):
        """Change ``Output`` fields mid-run. A new output rate starts its grid at the next output
        time after the present one."""
        rate, fast = self.output.output_rate, self.output.wrench_rate
        self.output = dataclasses.replace(self.output, **changes)
        if self.output.output_rate != rate and self.next_output > 0:
            self.next_output = outputs_by(self.solver.time, self.output.output_rate)
        if self.output.wrench_rate != fast:
            self._fast_from_now()

    def set_cloud(self, fields=None, frame_id=None):
        """Change the particle cloud's fields or the frame of every message."""
        self.frame_id = frame_id or self.frame_id
        if fields is not None:
            self.packer = self._packer(fields)
        self.cloud = messages.CloudBuilder(self.packer.fields, self.frame_id)

    def summary(self) -> str:
        """One line on the run: scene, spacing, particles, numerics, device, end time, output rate."""
        cfg = self.model.config
        model = "" if self.run_config.reduction.label == "full" else f" ({self.run_config.reduction.label})"
        return (f"{self.scene.name}{model}: dx = {cfg.dx:g} m, {self.n} particles "
                f"({self.model.fluid_particles} fluid), "
                f"{cfg.kernel} kernel, {cfg.viscosity} viscosity, {cfg.boundary} boundaries, {cfg.density_diffusion} "
                f"density diffusion, {cfg.precision} on {self.solver.device}"
                f"{self.device_choice and f' ({self.device_choice})'}; to t = {self.output.end_time:g} s, "
                f"outputs at {self.output.output_rate:g} Hz" + (f"; {self.cut}" if self.cut else ""))

    @property
    def device_choice(self) -> str:
        """Why ``device: auto`` chose the device the run steps on; "" where the run named it."""
        return choice(self.run_config.solver.device, str(self.solver.device))

    @property
    def particles_topic(self) -> str:
        return f"{self.namespace}/particles"

    def describe(self) -> dict:
        """What a recording's metadata says about this run."""
        cfg, solver = self.model.config, self.solver
        return {
            "scene_name": self.scene.name, "scene": self.scene.text,
            "run_config": yaml.safe_dump(self.run_config.as_dict(), sort_keys=True),
            "dx": cfg.dx, "kernel": cfg.kernel, "viscosity": cfg.viscosity, "boundary": cfg.boundary,
            "precision": cfg.precision, "device": str(solver.device), "particles": self.n,
            "fluid_particles": self.model.fluid_particles, "particles_order": "fluid first, then boundary",
            "bodies": yaml.safe_dump(self.model.bodies), "namespace": self.namespace, "frame_id": self.frame_id,
            "time_origin_ns": self.time_origin_ns,
            "axes": frames.AXES, "cloud_kinds": yaml.safe_dump(self.kind_names()),
            "versions": yaml.safe_dump({"gpusph_ros": version("gpusph_ros"), "warp": version("warp-lang"),
                                        "numpy": np.__version__, "python": platform.python_version()}),
            "revision": revision(),
            "host": platform.node(), "started_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(),
        } | ({"ranks": self.cut} if self.cut else {})

    def latched_messages(self) -> list:
        """(topic, message) pairs sent once per run: the description, the geometry, the body frames."""
        described = {k: (yaml.safe_load(v) if k in ("run_config", "versions", "bodies", "cloud_kinds") else v)
                     for k, v in self.describe().items()}
        t, world = self.solver.time, self.model.scene
        out = [(f"{self.namespace}/scene", String(data=yaml.safe_dump(described, sort_keys=False))),
               (f"{self.namespace}/geometry", markers.geometry(world, self.model.config.dx, self.frame_id, t))]
        transforms = markers.body_transforms(world, self.frame_id, t)
        if transforms is not None:
            out.append(("/tf_static", transforms))
        return self._restamped(out, t)

    def _restamped(self, pairs: list, t: float) -> list:
        if self.time_origin_ns:
            for _, msg in pairs:
                messages.restamp(msg, t, self.time_origin_ns)
        return pairs

    # -- checkpoints ---------------------------------------------------------------------------
    def checkpoint(self) -> dict:
        """All a resumed run needs to go on as this one would (sph/checkpoint.py): the solver's state,
        the outputs done, the wall time so far, the stamps' origin and the output settings. Taken
        between two steps: a run interrupted by ``stop`` is whole, one cut by Ctrl-C mid-step
        (``torn``) is not and refuses."""
        if self.torn:
            raise RuntimeError("checkpoint: the run was stopped in the middle of a step (Ctrl-C); its state "
                               "is not whole")
        # on ranks, every rank takes part and rank 0 gets it (None elsewhere): the run's state as any
        # number of ranks takes it up (sph/portable.py)
        solver = checkpoint.capture(self.solver) if self.ranks is None else self.ranks.portable()
        if solver is None:
            return None
        return {"format": CHECKPOINT_FORMAT, "solver": solver,
                "next_output": self.next_output, "wall": self.wall, "time_origin_ns": self.time_origin_ns,
                "output": dataclasses.asdict(self.output)}

    def check_state(self, state) -> tuple:
        """(next_output, wall, time origin, output settings) of ``state`` if it is ``checkpoint()`` of
        a run of this scene and settings; else ValueError, KeyError or TypeError saying what does not
        fit. Its counters are checked against each other: the outputs done are those its time has
        passed (a next output of -1e9 published 900 empty outputs a second), its output settings are
        in their ranges, its wall time finite, its stamps' origin no later than now."""
        if not isinstance(state, dict) or state.get("format") != CHECKPOINT_FORMAT:
            raise ValueError(f"checkpoint: not a run's state of format {CHECKPOINT_FORMAT}")
        fields = {f.name for f in dataclasses.fields(self.output)}
        if not isinstance(state.get("output"), dict) or set(state["output"]) != fields:
            raise ValueError(f"checkpoint: its output settings are not {', '.join(sorted(fields))}")
        if portable.is_portable(state["solver"]):  # a run on ranks took it
            problem = portable.mismatch(self.model.config, self.model.particles, state["solver"])
            t = None if problem else float(state["solver"]["counters"]["_clock"][T])
        elif self.ranks is not None:
            problem = "one solver's state, which a run on ranks takes up as it starts only (gpusph-run --resume)"
        else:
            problem = checkpoint.mismatch(self.solver, state["solver"])
            t = None if problem else state["solver"]["host"]["solver"]["time"]
        if problem:
            raise ValueError(f"checkpoint: {problem}")
        try:
            output = check_output(dataclasses.replace(self.output, **state["output"]))
        except ConfigError as err:
            raise ValueError(f"checkpoint: its output settings: {err}") from None
        next_output, wall, origin = state.get("next_output"), state.get("wall"), state.get("time_origin_ns")
        passed = outputs_by(t, output.output_rate)
        if type(next_output) is not int or next_output not in (passed - 1, passed):
            raise ValueError(f"checkpoint: its next output {shown(next_output)} is not the next after t = {t:.6g} s "
                             f"at {output.output_rate:g} Hz ({passed - 1} or {passed})")
        if not (isinstance(wall, float) and math.isfinite(wall) and wall >= 0.0):
            raise ValueError(f"checkpoint: its wall time {shown(wall)} is not a time")
        latest = time.time_ns() if output.stamps == "epoch" else 0
        if type(origin) is not int or not (0 <= origin <= latest):
            raise ValueError(f"checkpoint: its stamps' origin {shown(origin)} is not a time between 0 and now "
                             f"({output.stamps} stamps)")
        return next_output, wall, origin, output

    def restore(self, state: dict, fitted: tuple = None):
        """Continue from ``checkpoint()`` of a run of the same scene and settings: nothing changes for
        a state that does not fit. ``fitted``: what ``check_state(state)`` returned, when the caller
        has checked it already."""
        next_output, wall, origin, output = fitted or self.check_state(state)
        if not portable.is_portable(state["solver"]):
            checkpoint.put(self.solver, state["solver"])
        elif self.ranks is None:
            portable.put(self.solver, state["solver"]["particles"], state["solver"]["counters"],
                         state["solver"]["bodies"])
        # on ranks, each rank took the state up as it was built (Run's ``state``)
        self.measurements.restart()
        self.next_output, self.wall, self.time_origin_ns, self.output = next_output, wall, origin, output
        self._fast_from_now()

    def open_recording(self, path, compression: str = None, earlier: list = None):
        """A BagRecorder at ``path`` with this run's topics declared and its latched messages written
        (``earlier``: the files of the bag a resumed run continues). The MCAP writer is loaded here,
        when a recording starts: a node that never records runs without the mcap package."""
        from .output import msgdefs
        from .output.recording import BagRecorder, qos_yaml

        recorder = BagRecorder(path, self.describe(), compression=compression or self.output.compression,
                               time_origin_ns=self.time_origin_ns, earlier=earlier)
        try:
            recorder.add_topic("/clock", "rosgraph_msgs/msg/Clock", qos_yaml(**CLOCK_QOS))
            if self.output.particle_every:
                recorder.add_topic(self.particles_topic, "sensor_msgs/msg/PointCloud2", qos_yaml(**PARTICLES_QOS))
            for topic, msg in self.latched_messages():
                recorder.add_topic(topic, msgdefs.type_name_of(type(msg)), qos_yaml(**LATCHED_QOS))
                recorder.write(topic, msg, self.solver.time)
        except BaseException:
            recorder.close({"status": "failed: the recording could not be started"})
            raise
        return recorder

    def output_messages(self, index: int) -> list:
        """(topic, message) pairs of output ``index`` at the solver's current time; on ranks, rank 0's
        (every rank measures and packs, together)."""
        t = self.solver.time
        sample = self.measurements.sample()
        every = self.output.particle_every
        rows = self.cloud_rows() if every and index % every == 0 else None
        if not self.root:
            return []
        out = [("/clock", messages.clock(t))]
        out += messages.measurement_messages(t, sample, self.scene, self.namespace, self.frame_id)
        # the moving bodies' frames, where tf2_msgs is installed (a scene without one asks nothing)
        moving = markers.body_transforms(self.model.scene, self.frame_id, t, sample["poses"]) if sample["poses"] \
            else None
        if moving is not None:
            out.append(("/tf", moving))
        if self._force_scales:
            out.append((f"{self.namespace}/bodies/force_arrows",
                        markers.force_arrows(t, sample["wrenches"], self.model.scene, self._force_scales,
                                             self.frame_id)))
        if rows is not None:
            out.append((self.particles_topic, self.cloud.build(t, rows)))
        return self._restamped(out, t)

    def cloud_rows(self) -> "np.ndarray | None":
        """The particle cloud's rows (measure/cloud.py); on ranks, gathered to rank 0 (None elsewhere)
        in the order one rank packs them."""
        if self.ranks is None:
            return self.packer.pack()
        return self.ranks.rows(self.packer.pack(every=True))

    def fast_messages(self, clock: bool = True) -> list:
        """(topic, message) pairs at a wrench-rate time (``Output.wrench_rate``): each body's wrench,
        the mean over the steps since the last, and a moving body's pose and odometry, on topics of
        their own (``<name>/wrench_fast``, ...); /clock first where ``clock``."""
        t = self.solver.time
        sample = self.measurements.fast_sample()
        if not self.root:
            return []
        out = [("/clock", messages.clock(t))] if clock else []
        out += messages.body_messages(t, sample, self.model.config.dim, self.namespace, self.frame_id, messages.FAST)
        return self._restamped(out, t)

    def next_event(self) -> float:
        """The next time the run stops at [s]: its next output, or its next wrench-rate time."""
        t = self.next_output / self.output.output_rate
        rate = self.output.wrench_rate
        return min(t, self.next_fast / rate) if rate else t

    def _fast_from_now(self):
        """The wrench-rate times counted on from the present (a new rate, a restored state): the
        first is the first after now, so each message averages a whole interval."""
        if self.output.wrench_rate:
            self.measurements.start_fast()
            self.next_fast = outputs_by(self.solver.time, self.output.wrench_rate)

    def step_output(self, interrupt=None, limit: float = None):
        """Advance to the next output, the next wrench-rate time or ``limit`` (a lockstep master's
        target [s]), whichever is first, and return the messages due there, [] at a limit where none
        are (HealthError on failure); None when ``interrupt`` stopped the solver short of it
        (``Solver.advance``). Every time it stops at is a step's end: a run with other stops takes
        other steps."""
        k = self.next_output
        target = self.next_event() if limit is None else min(self.next_event(), limit)
        start = time.perf_counter()
        for name, (body, hold) in self.wrenches.items():  # the floating bodies' external wrenches to this output
            wrench = hold.wrench(self.solver.time)
            if not all(np.array_equal(a, b) for a, b in zip(wrench, self._applied.get(name, (None, None)))):
                self.solver.apply_wrench(body, *wrench)
                self._applied[name] = wrench
        if self.drivers:  # the driven bodies' segments to this output, from their last commands
            poses = self.solver.body_poses()
            for body, driver in self.drivers.values():
                self.solver.drive(body, **driver.segment(self.solver.time, max(target - self.solver.time, 1.0e-9),
                                                         poses[body]))
        try:
            (self.solver if self.ranks is None else self.ranks).advance(target, interrupt)
            if not self.solver.reached(target):
                return None
            rate, reached = self.output.wrench_rate, self.solver.reached
            msgs = []
            if reached(k / self.output.output_rate):
                msgs = self.output_messages(k)
                self.next_output += 1
            if rate and reached(self.next_fast / rate):
                msgs += self.fast_messages(clock=not msgs)
                self.next_fast += 1
        finally:  # a failed output's steps count in the wall time too (MIPPS of a failed run)
            self.wall += time.perf_counter() - start
        return msgs

    @property
    def done(self) -> bool:
        return self.next_output >= self.n_outputs

    def mipps(self) -> float:
        return self.n * self.solver.steps / max(self.wall, 1e-9) / 1e6

    def execute(self, recorder=None, progress=None, stop=None, checkpoints=None) -> dict:
        """Run to the end time, recording each output; returns the result record (status,
        wall time, steps, MIPPS). A HealthError or a neighbour-list overflow ends the run with
        status 'failed'; Ctrl-C, or ``stop`` (a callable asked between steps) answering true, with
        'interrupted'. The recording is closed either way. ``checkpoints(run)`` is called after each
        output (it decides whether one is due)."""
        status = "completed"
        try:
            while not self.done:
                k = self.next_output
                msgs = self.step_output(stop)
                if msgs is None:
                    status = "interrupted"
                    break
                for topic, msg in msgs:
                    if recorder is not None:
                        recorder.write(topic, msg, self.solver.time)
                if self.next_output == k:  # a wrench-rate time between two outputs
                    continue
                self.tally = self.exclusions()
                if checkpoints is not None:
                    checkpoints(self)
                if progress is not None:
                    progress(self)
        except RuntimeError as err:  # a health check, a neighbour-list overflow, a clock stuck below float64's step
            status = f"failed: {err}"
        except OSError as err:  # the recording's disk is full (it closed itself, readable) or went away
            status = f"failed: the recording could not be written: {err.strerror or err}"
        except KeyboardInterrupt:
            status, self.torn = "interrupted", True
        result = self.result(status)
        if recorder is not None:
            recorder.close(result)
        return result

    def exclusions(self) -> dict:
        """The fluid particles excluded at fault so far (sph.health): how many, their share of the
        fluid mass, by fault ('density_bounds 3, wall_penetration 1' or 'none'), the time of the
        first; and apart, those that left the tank over its walls and their share."""
        s = self.solver  # on ranks, every rank's counts are the run's (sph/exchange.py)
        return {"excluded_particles": s.excluded_particles, "excluded_fraction": s.excluded_fraction,
                "excluded_by_reason": s.describe_excluded(list(s.excluded.values())),
                "first_excluded_time_s": s.first_excluded_time, "left_tank_particles": s.left_tank_particles,
                "left_tank_fraction": s.left_tank_fraction}

    def result(self, status: str) -> dict:
        """The result record a recording closes with."""
        return {"status": status, "wall_time_s": round(self.wall, 3), "steps": self.solver.steps,
                "simulated_time_s": self.solver.time, "mipps": round(self.mipps(), 4), "outputs": self.next_output,
                **self.exclusions(), **self.solver.health_peaks}


CHECKPOINT_FILE = "checkpoint.npz"
# what versions before the data-only state file wrote: recognised, never loaded (state_file)
PICKLED_CHECKPOINT = "checkpoint.pkl"
# a resumed run's settings may build at most this many times its state's particles (and this many
# more) before the build is refused: the scene's price (scenes.build.priced) is exact for walls with a
# volume, an overestimate by the wall's edges otherwise, and leaves out what zones add
RESUME_PRICE_RATIO, RESUME_PRICE_SLACK = 4, 10_000


class Checkpoints:
    """A recorded run's checkpoints, in its bag folder (``checkpoint.npz``, a ``state_file``): the run's state
    (``Run.checkpoint``), what rebuilds it (``invocation``: scene, run configurations, settings) and
    how much of the recording it accounts for. Written every ``interval`` seconds of wall clock at
    an output (the recording's open chunk closed first, so that the file on disk holds every message
    the checkpoint counts) and by ``write``; replaced whole, never half-written. On ``comm``'s ranks
    every rank calls it, rank 0's clock decides when, and rank 0 (the ``recorder``'s) writes."""

    def __init__(self, folder, invocation: dict, recorder, interval: float, comm=None):
        self.path = Path(folder) / CHECKPOINT_FILE
        self.invocation, self.recorder, self.interval, self.comm = invocation, recorder, interval, comm
        self._last = time.monotonic()

    def __call__(self, run):
        due = bool(self.interval) and time.monotonic() - self._last >= self.interval
        if due if self.comm is None else self.comm.bcast(due):
            self.write(run)

    def write(self, run) -> "Path | None":
        taken = run.checkpoint()
        if self.recorder is None:  # a rank other than 0: it took part
            return None
        self.recorder.flush()
        state_file.write(self.path, "checkpoint", {
            "invocation": self.invocation, "run": taken,
            "recording": {"file": self.recorder.file_name, "messages": self.recorder.count}})
        self._last = time.monotonic()
        return self.path

    def remove(self):
        self.path.unlink(missing_ok=True)


def resume(folder, comm=None):
    """(run, recorder, invocation) continuing the recorded run in ``folder`` from its checkpoint
    (on ``comm``'s ranks, where given: Run's; rank 0 alone gets the recorder, None elsewhere):
    the run rebuilt as it was invoked and restored; the recording's file the checkpoint counted
    cut back to what it counted (a killed run wrote on after it), any later file set aside as
    ``.superseded``, and a new file ``<name>_<k>.mcap`` opened after them. ValueError, before
    anything in the folder changes, when there is nothing to resume or when the bag no longer holds
    every message the checkpoint counts (the resumed recording would have a gap)."""
    from .output.recording import bag_files, file_entries, is_whole, repair, whole_messages
    from .scenes.schema import load_scene
    from .scenes.settings import resolve

    folder = Path(folder)
    path = folder / CHECKPOINT_FILE
    if path.is_symlink():  # it resumed, then Ctrl-C could not write the checkpoint over it
        raise ValueError(f"--resume: {path} is a symbolic link; a checkpoint is a regular file only (put the file "
                         "it points to in its place)")
    if not path.is_file():
        if (folder / PICKLED_CHECKPOINT).exists():
            raise ValueError(f"--resume: {folder} holds {PICKLED_CHECKPOINT}, the checkpoint of an earlier version, "
                             "a Python pickle; this version never loads a pickle, since loading one can run any code "
                             "it carries: run the scene again")
        raise ValueError(f"--resume: {folder} has no {CHECKPOINT_FILE}: not a run stopped before its end (a "
                         "completed run removes it; checkpoint_interval 0 writes none)")
    try:
        state = state_file.read(path, "checkpoint", ("invocation", "run", "recording"))
        invocation, recording = state["invocation"], state["recording"]
        scene = load_scene(invocation["scene"])
        config = resolve(scene, files=invocation["run_config"], sets=invocation["sets"])
        taken = state["run"]["solver"]
        held = len(taken["particles"]["pos"]) if portable.is_portable(taken) else taken["host"]["solver"]["n"]
        at_most = priced(scene, config)[2]
        # a checkpoint whose settings say dx = 0.2 mm built 6.9 M particles before its arrays were refused
        if type(held) is not int or held < 1 or at_most > RESUME_PRICE_RATIO * held + RESUME_PRICE_SLACK:
            raise ValueError(f"its settings build up to {at_most:,} particles and its state holds {shown(held)}: "
                             "they are not the settings it was taken with")
        ranked = comm is not None and comm.size > 1
        if ranked and not portable.is_portable(taken):  # one solver's: its particles by id, any cut takes
            taken = state["run"]["solver"] = portable.of_solver_state(taken)
        run = Run(scene, config, comm=comm, state=taken if ranked else None)
        run.restore(state["run"])
        counted_file, counted = recording["file"], recording["messages"]
        if not isinstance(counted_file, str) or type(counted) is not int or counted < 1:
            raise ValueError(f"its recording's file {shown(counted_file)} and count {shown(counted)} are not a file "
                             "name and a count of messages")
    except (KeyError, TypeError, ValueError) as err:  # ConfigError and StateFileError are ValueErrors
        raise ValueError(f"--resume: {err}" if isinstance(err, ValueError) else
                         f"--resume: {path} is not a checkpoint this version wrote ({type(err).__name__}: {err})"
                         ) from None
    if not run.root:
        return run, None, invocation
    files = bag_files(folder)
    names = [f.name for f in files]
    if counted_file not in names:
        raise ValueError(f"--resume: {folder} lacks {counted_file}, the file its checkpoint counts")
    k = names.index(counted_file)
    for earlier in files[:k]:
        if not is_whole(earlier):
            raise ValueError(f"--resume: {earlier} is cut short: the recording before the checkpoint has lost "
                             "messages, and a resumed run would leave a gap in it; gpusph-analyze --repair mends "
                             "the bag's last file only, so the run cannot be resumed")
    whole = is_whole(files[k])
    # one pass over the file: its whole messages, the last one's time and those from before the checkpoint
    held, last, before = whole_messages(files[k], run.time_origin_ns + int(round(run.solver.time * 1e9)))
    last_t = ((last or run.time_origin_ns) - run.time_origin_ns) * 1e-9
    if held < counted:
        raise ValueError(
            f"--resume: {files[k].name} holds {held:,} whole messages, up to t = {last_t:.4f} s, of the {counted:,} "
            f"its checkpoint counts, at t = {run.solver.time:.4f} s: the file was cut after the checkpoint was "
            "written, and a resumed run would leave a gap in the recording. The run cannot be resumed from this "
            "checkpoint; gpusph-analyze --repair makes what the bag holds readable")
    if counted < before:
        raise ValueError(f"--resume: its checkpoint counts {counted:,} messages of {files[k].name}, which holds "
                         f"{before:,} from before the checkpoint's t = {run.solver.time:.4f} s: cutting the file back "
                         "to the count would lose them; the checkpoint does not belong to this recording")
    for later in files[k + 1:]:
        later.replace(later.with_name(later.name + ".superseded"))
    if not whole or held != counted:
        repair(folder, run.output.compression, keep=counted)
    recorder = run.open_recording(folder, earlier=file_entries(folder))
    return run, recorder, invocation
