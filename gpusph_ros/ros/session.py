"""The node's solver thread: steps a ``Run`` from output to output, serialises each output's
messages once for the publishers and the recording, keeps to a real-time factor, and stops
between two steps for a pause, a step request, a reset, a live parameter change or shut-down.

ROS callbacks run in other threads and only set flags and wait briefly: the solver asks
``_interrupted`` before every step of its eager loop, so nothing waits longer than one step (every
64 steps of a replayed loop: a GPU, or one CPU thread; sph/graph.py). All Warp work runs
in this thread, except what a service does while it owns the solver (a reset's build, a capture,
a restore): one service at a time owns it (``_held``), the others wait their turn up to
``OWNER_WAIT`` and are then refused, and the thread steps only while nobody owns it. A bag takes
only the messages of the run it was opened for. Whatever a step raises ends the run as a failure
the node reports; the thread never dies of it.
"""
import collections
import datetime
import gc
import threading
import time
from pathlib import Path

from rclpy.serialization import serialize_message

from ..output import state_file
from ..sph import HealthError, NeighbourOverflow
from .node_params import LIVE_SETTINGS

NODE_STATE = "node state"  # the kind of state file ~/save_state writes (a gpusph-run checkpoint is another)
MAX_TARGETS = 1000  # lockstep targets waiting at once; past them a request is refused (a flood of them)
OWNER_WAIT = 120.0  # [s] the longest a service waits for another to give the solver back (a large reset's build)


class Busy(RuntimeError):
    """Another service owned the solver for longer than ``OWNER_WAIT``: the request is refused."""


class Session:
    """``publish(topic, message, data)`` sends one output message (``data``: its CDR bytes);
    ``report(level, text)`` tells the node of a failure or the end of the run; under lockstep,
    ``reached(target, t)`` answers a target with the fluid's time. All are called from the solver
    thread."""

    def __init__(self, publish, report, reached=None):
        self._publish, self._report, self._reached = publish, report, reached
        self._cond = threading.Condition()
        # re-entrant: a reset or a load finishes the old run's bag and swaps the run under it, so
        # that no ~/record between the two opens a bag for the run that is going
        self._record_lock = threading.RLock()
        self._recording_run = None  # the run the open bag belongs to
        self._owner = threading.Lock()  # held by the one service that owns the solver (_held)
        self._owner_what = ""
        self.run = None
        self.active = False  # the lifecycle state allows stepping
        self.paused = False
        self.failure = ""  # why the solver stopped; "" while healthy
        self.real_time_factor = 0.0
        self.recorder = None
        self._step_to = -1  # a paused solver still produces outputs up to this index (~/step)
        self._published = -1  # index of the last output handed to the publishers
        self._busy = self._hold = self._closing = False
        self._pending = {}
        self._stepper = False  # a ~/step is waiting for its output
        self._generation = 0  # bumped when what a waiting ~/step aims at changes (outputs, run, close)
        self._pace = None  # (wall, simulated time) the real-time factor counts from
        # clock: follow (sim_node): the followed clock's last time, None before its first message or
        # when not following; the fluid never steps past it
        self.following = False
        self._limit = None
        self.max_lag = 0.1
        self._fluid_t = 0.0  # the fluid's time at its last output
        self._lag_worst = 0.0
        self._lag_over = 0  # clock messages with the fluid more than max_lag behind, after the warning
        self._lag_warned = False
        self._window = None
        # clock: lockstep (sim_node): the times a master asked the fluid to reach, answered in order;
        # the fluid steps only towards the first, and lands on it
        self.lockstep = False
        self._targets = collections.deque()
        self.lockstep_refused = 0  # targets refused past MAX_TARGETS (each answered with "refused")
        self.lockstep_lost = 0  # targets the middleware dropped before the node read them
        self._thread = threading.Thread(target=self._loop, name="solver", daemon=True)
        self._thread.start()

    # -- state ----------------------------------------------------------------------------------
    @property
    def state(self) -> str:
        run = self.run
        if self._closing:
            return "shut down"
        if run is None:
            return "unconfigured"
        if self.failure:
            return "failed"
        if run.done:
            return "finished"
        if self._stepping():
            return "stepping"
        if not self.active:
            return "inactive"
        # paused once the solver has stopped: a batch of steps already under way ends first, and
        # its time (read by the host at its end) must not move after "paused" was said
        return "paused" if self.paused and not self._busy else "running"

    def _stepping(self) -> bool:
        return self.run is not None and self.run.next_output <= self._step_to

    def _can_advance(self) -> bool:
        run = self.run
        if run is None or self.failure or run.done or self._hold:
            return False
        if self.following:
            # the next output only once the followed clock has reached it (a ~/step's too)
            limit = self._limit
            if limit is None or run.next_event() > limit + 1e-9:
                return False
        if self.lockstep:
            return bool(self._targets) and not run.solver.reached(self._targets[0]) and self.active and not self.paused
        return self._stepping() or (self.active and not self.paused)

    def _answerable(self) -> bool:
        """Whether the first lockstep target is due an answer: reached, or out of reach (the run
        failed or is at its end)."""
        run = self.run
        return (bool(self._targets) and run is not None and not self._hold
                and (self.failure != "" or run.done or run.solver.reached(self._targets[0])))

    def _interrupted(self) -> bool:
        return (self._closing or self._hold or bool(self._pending)
                or not (self._stepping() or (self.active and not self.paused)))

    def stats(self) -> dict:
        """Figures for /diagnostics; rates over the time since the previous call."""
        run = self.run
        out = {"state": self.state, "error": self.failure,
               "recording": str(self.recorder.path) if self.recorder else ""}
        if self.following:
            limit = self._limit
            out.update(clock_followed=-1.0 if limit is None else limit,
                       clock_lag=0.0 if limit is None else max(limit - self._fluid_t, 0.0),
                       clock_lag_worst=self._lag_worst, clock_lag_over=self._lag_over)
        if self.lockstep:
            out.update(lockstep_waiting=len(self._targets), lockstep_refused=self.lockstep_refused,
                       lockstep_lost=self.lockstep_lost)
        if run is None:
            return out
        solver, now = run.solver, time.perf_counter()
        window, self._window = self._window, (now, solver.steps, solver.time, run)
        steps_per_s = rtf = 0.0
        if window is not None and window[3] is run and now > window[0]:
            steps_per_s = (solver.steps - window[1]) / (now - window[0])
            rtf = (solver.time - window[2]) / (now - window[0])
        out.update(scene=run.scene.name, simulated_time=solver.time, dt=solver.dt, particles=solver.n,
                   steps=solver.steps, steps_per_s=steps_per_s, mipps=steps_per_s * solver.n / 1e6,
                   real_time_factor=rtf, device=str(solver.device), device_choice=run.device_choice,
                   precision=run.model.config.precision,
                   end_time=run.output.end_time, **run.exclusions(), **solver.health_peaks)
        return out

    # -- the thread ----------------------------------------------------------------------------
    def _loop(self):
        while True:
            answers = []
            with self._cond:
                while True:
                    if self._closing:
                        return
                    if not self._hold:
                        try:
                            self._apply_pending()
                        except Exception as err:  # a refused change ends the run, not the thread
                            self.failure = f"a live change failed: {type(err).__name__}: {err}"
                            self._report("error", self.failure)
                    while self._answerable():
                        answers.append((self._targets.popleft(), self.run.solver.time))
                    if answers or self._can_advance():
                        break
                    self._cond.wait()
                if answers:  # sent outside the lock, then look again
                    run = None
                else:
                    run, self._busy = self.run, True
                    limit = self._targets[0] if self.lockstep else None
            if run is None:
                for target, t in answers:
                    try:
                        self._reached(target, t)
                    except Exception as err:  # a publisher torn down: the thread goes on
                        self._report("error", f"~/reached for t = {target:.6f} s was not sent: "
                                              f"{type(err).__name__}: {err}")
                continue
            try:
                self._advance(run, limit)
            finally:
                with self._cond:
                    self._busy = False
                    self._cond.notify_all()

    def _apply_pending(self):
        changes, self._pending = self._pending, {}
        run = self.run
        if "real_time_factor" in changes:
            self.real_time_factor = changes.pop("real_time_factor")
            self._pace = None
        if "max_lag" in changes:
            self.max_lag = changes.pop("max_lag")
        if run is None:
            return
        numerics = {k: v for k, v in changes.items() if LIVE_SETTINGS[k] == "solver"}
        if numerics:
            run.solver.reconfigure(**numerics)
        output = {k: v for k, v in changes.items() if LIVE_SETTINGS[k] == "output"}
        if output:
            run.set_output(**output)
            # a ~/step waiting for an output of the old grid answers now; a paused solver stops
            self._step_to, self._generation = -1, self._generation + 1
            self._cond.notify_all()
        if "particle_fields" in changes or "frame_id" in changes:
            run.set_cloud(changes.get("particle_fields"), changes.get("frame_id"))
        if "frame_id" in changes:  # the geometry and the body frames, in the new frame
            self._emit(run, run.latched_messages(), run.solver.time)

    def _advance(self, run, limit=None):
        try:
            msgs = run.step_output(self._interrupted, limit)
        except Exception as err:  # HealthError, NeighbourOverflow, a stuck clock, a device error
            if not isinstance(err, (HealthError, NeighbourOverflow)):
                err = f"{type(err).__name__}: {err}"
            with self._cond:
                self.failure, self.paused, self._step_to = str(err), True, -1
            self.stop_recording(f"failed: {err}")
            self._report("error", f"the solver stopped at t = {run.solver.time:.4f} s: {err}; the node is paused "
                                  f"and still serving; ~/reset rebuilds the scene")
            return
        if msgs is None:
            return
        t = run.solver.time
        try:
            self._emit(run, msgs, t)
        except Exception as err:  # a full disk, a publisher torn down: the run goes on, the bag is finished
            self.stop_recording(f"failed: the recording could not be written: {type(err).__name__}: {err}")
            self._report("error", f"the output at t = {t:.4f} s was not sent or recorded: {type(err).__name__}: "
                                  f"{err}; the recording (if any) is finished")
        with self._cond:
            self._published = run.next_output - 1
            self._fluid_t = t
            self._cond.notify_all()
        if run.done:
            self.stop_recording("completed")
            self._report("info", f"reached end_time = {run.output.end_time:g} s after {run.solver.steps} steps")
        self._keep_pace(t)

    def _emit(self, run, msgs, t):
        """Publish ``run``'s messages at ``t``, and record them where the open bag is ``run``'s."""
        with self._record_lock:
            recorder = self.recorder if self._recording_run is run else None
            for topic, msg in msgs:
                data = serialize_message(msg)  # once, for the publisher and the file
                self._publish(topic, msg, data)
                if recorder is not None:
                    recorder.write(topic, msg, t, data)

    def _keep_pace(self, t):
        rtf = self.real_time_factor
        if rtf <= 0.0:
            return
        now = time.monotonic()
        if self._pace is None:
            self._pace = (now, t)
        due = self._pace[0] + (t - self._pace[1]) / rtf
        if due < now - 1.0:  # more than a second behind: keep the pace from here, owe nothing
            self._pace = (now, t)
        with self._cond:
            while not self._interrupted() and time.monotonic() < due:
                self._cond.wait(due - time.monotonic())

    # -- requests from ROS callbacks -----------------------------------------------------------
    def clock_to(self, t: float) -> bool:
        """The followed clock reads ``t`` [s]: the fluid may advance to it. False, and nothing
        changed, where it went back (a simulator's reset): the caller resets the run."""
        with self._cond:
            if self._limit is not None and t < self._limit - 1e-9:
                return False
            self._limit = t
            lag = t - self._fluid_t
            self._lag_worst = max(self._lag_worst, lag)
            if lag > self.max_lag and self.run is not None and not self.run.done:
                if self._lag_warned:
                    self._lag_over += 1
                else:
                    self._lag_warned = True
                    warn = (f"the fluid is {lag:.3f} s behind the followed /clock (max_lag {self.max_lag:g} s); "
                            "/diagnostics counts each clock message after this with it further behind")
                    threading.Thread(target=self._report, args=("warn", warn), daemon=True).start()
            self._cond.notify_all()
        return True

    def advance_to(self, target: float) -> str:
        """clock: lockstep: the fluid is to reach ``target`` [s] and say so (``reached``), after the
        targets before it; "" or why it is refused. A target the fluid has passed is answered at
        once with its time, one past the end time or after a failure with where it stopped."""
        with self._cond:
            if len(self._targets) >= MAX_TARGETS:
                self.lockstep_refused += 1
                return (f"{MAX_TARGETS} targets are waiting already; wait for their answers on ~/reached before "
                        "sending more")
            self._targets.append(target)
            self._cond.notify_all()
        return ""

    def restart_clock(self, t: float):
        """Follow the clock afresh from ``t`` (after the reset its going back asked for)."""
        with self._cond:
            self._limit, self._fluid_t, self._lag_worst = t, 0.0, 0.0
            self._lag_over, self._lag_warned = 0, False
            self._cond.notify_all()

    def change(self, **changes):
        """Live changes (node_params.LIVE_SETTINGS), applied by the solver thread before its next step."""
        with self._cond:
            self._pending.update(changes)
            self._cond.notify_all()

    def set_active(self, active: bool):
        with self._cond:
            self.active = active
            self._pace = None
            self._cond.notify_all()

    def set_paused(self, paused: bool) -> tuple:
        """(success, message)."""
        with self._cond:
            run = self.run
            if run is None:
                return False, "no scene is loaded: configure the node (or call ~/reset)"
            if not paused and self.failure:
                return False, f"the run failed ({self.failure}); ~/reset rebuilds the scene"
            if not paused and not self.active:
                return False, "the node is inactive: activate it (ros2 lifecycle set /sim_node activate)"
            self.paused, self._pace = paused, None
            self._cond.notify_all()
            t = run.solver.time
            if paused:
                return True, f"paused at t = {t:.4f} s (the solver stops before its next step)"
            if run.done:
                return True, (f"resumed, but the run is at end_time = {run.output.end_time:g} s; "
                              "raise end_time or ~/reset")
            return True, f"running from t = {t:.4f} s"

    def step(self, timeout: float) -> tuple:
        """Advance one output interval while paused; waits up to ``timeout`` s for it while the
        solver works towards it, and answers at once when the target goes away (the output rate
        changed, a reset, a failure, shut-down). One ~/step waits at a time."""
        with self._cond:
            run = self.run
            if self._closing:
                return False, "the node is shut down"
            if self._stepper:
                return False, "a step is already under way; wait for its answer (or watch /clock)"
            if run is None:
                return False, "no scene is loaded: configure the node (or call ~/reset)"
            if self.failure:
                return False, f"the run failed ({self.failure}); ~/reset rebuilds the scene"
            if run.done:
                return False, f"the run is at end_time = {run.output.end_time:g} s; raise end_time or ~/reset"
            if self.lockstep:
                return False, "clock: lockstep moves the fluid only to the times sent on ~/advance_to"
            if self.active and not self.paused:
                return False, "the solver is running; pause it first (~/set_paused true)"
            aim = max(run.next_output, self._step_to + 1) / run.output.output_rate
            if self.following and (self._limit is None or aim > self._limit + 1e-9):
                # a stopped clock would hold the call for its whole wait and then say "still running"
                # while nothing ran: answered at once, and nothing is asked of the solver
                clock = "sent nothing yet" if self._limit is None else f"reads t = {self._limit:.4f} s"
                return False, (f"waiting for /clock: the next output, t = {aim:.4f} s, is past the followed "
                               f"clock, which {clock}; step again once it has passed it")
            # the output after those already asked for; run.next_output has already moved past
            # an output the solver thread is still publishing
            k = self._step_to = max(run.next_output, self._step_to + 1)
            generation, self._stepper = self._generation, True
            self._cond.notify_all()
            deadline = time.monotonic() + timeout
            try:
                while (self._published < k and not self.failure and run is self.run and not self._closing
                       and generation == self._generation and time.monotonic() < deadline):
                    self._cond.wait(max(0.0, deadline - time.monotonic()))
            finally:
                self._stepper = False
            target = k / run.output.output_rate
            if self.failure:
                return False, f"the step failed: {self.failure}"
            if self._closing:
                return False, "the node shut down while stepping"
            if run is not self.run:
                return False, "a reset replaced the run while stepping; step again"
            if generation != self._generation:
                return False, (f"the output settings changed while stepping; the solver stopped at "
                               f"t = {run.solver.time:.4f} s; step again")
            if self._published < k:
                return True, f"stepping to t = {target:.4f} s (still running after {timeout:g} s; watch /clock)"
            return True, f"stepped to t = {run.solver.time:.4f} s ({run.solver.steps} steps in all)"

    def replace(self, build):
        """Stop the solver between two steps, build a new run with ``build()`` and make it
        current (paused or running as before). If ``build`` raises, the old run stays."""
        def swap(_):
            run = build()
            with self._record_lock:
                self.stop_recording("reset")
                with self._cond:
                    self.run, self.failure, self._step_to, self._published, self._pending = run, "", -1, -1, {}
                    self._fluid_t = run.solver.time
                    self._generation += 1
                    self._pace = self._window = None
            return run

        run = self._held(swap, "a reset")
        # the old run's solver holds cycles (its step hooks, its captured loop), so only the cyclic
        # collector frees its arrays and its launch threads: a soak of resets held up to 70 threads
        # and their runs' memory until it ran, and on a GPU that memory is the next build's
        gc.collect()
        return run

    def _held(self, work, what: str):
        """``work(run)`` with the solver held between two steps, owned by this caller alone (``what``
        it does, for the refusal of the next one); what it returns. Raises ``Busy`` after waiting
        ``OWNER_WAIT`` for another owner: a second owner's work must not run beside the first's, nor
        may the first, finishing, let the solver step under the second's (a reset's build)."""
        if not self._owner.acquire(timeout=OWNER_WAIT):
            raise Busy(f"the solver is busy with {self._owner_what or 'another request'} for more than "
                       f"{OWNER_WAIT:g} s; try again")
        try:
            self._owner_what = what
            with self._cond:
                self._hold = True
                self._cond.notify_all()
                while self._busy:
                    self._cond.wait()
            try:
                return work(self.run)
            finally:
                with self._cond:
                    self._hold = False
                    self._cond.notify_all()
        finally:
            self._owner_what = ""
            self._owner.release()

    def save_state(self, path) -> tuple:
        """(success, message): the run's whole state (``Run.checkpoint``), with the scene and
        settings it belongs to, written to ``path`` between two steps."""
        if self.run is None:
            return False, "no scene is loaded: configure the node (or call ~/reset)"
        if self.failure:
            return False, f"the run failed ({self.failure}); its state is not kept; ~/reset or ~/load_state"
        try:
            state = self._held(lambda run: {"scene": run.scene.text, "settings": run.run_config.as_dict(),
                                            "run": run.checkpoint(), "t": run.solver.time}, "a save")
        except Busy as err:
            return False, f"not saved: {err}"
        try:
            written = state_file.write(path, NODE_STATE, state)
        except state_file.StateFileError as err:
            return False, f"not saved: {err}"
        return True, f"saved the state at t = {state['t']:.4f} s to {written}"

    def load_state(self, path) -> tuple:
        """(success, message): the run goes on from the state ``save_state`` wrote to ``path``, if it
        is of the same scene and settings; a recording under way is finished first (its time would
        go back). Nothing changes when the file is not such a state."""
        if self.run is None:
            return False, "no scene is loaded: configure the node (or call ~/reset)"
        path = Path(path).expanduser()
        try:
            state = state_file.read(path, NODE_STATE, ("scene", "settings", "run", "t"))
        except state_file.StateFileError as err:
            return False, f"cannot read a state: {err}"
        scene, settings = state["scene"], state["settings"]
        if not (isinstance(scene, str) and isinstance(settings, dict) and isinstance(state["t"], float)):
            return False, f"cannot read a state: {path} holds no scene text, settings and time"
        run = self.run
        present = run.run_config.as_dict()
        if scene != run.scene.text or settings != present:
            differ = sorted(k for k in set(settings) | set(present) if settings.get(k) != present.get(k))
            what = "a different scene file" if scene != run.scene.text else "settings " + ", ".join(differ)
            return False, (f"the state in {path} is of {what}; set the parameters it was saved with and "
                           "~/reset, then load it")

        def load(run):
            fitted = run.check_state(state["run"])
            with self._record_lock:  # its time would go back: the bag under way is finished first
                self.stop_recording("stopped: a saved state was loaded")
                run.restore(state["run"], fitted)
                with self._cond:
                    self.failure, self._step_to, self._published = "", -1, run.next_output - 1
                    self._generation += 1
                    self._pace = self._window = None

        try:
            self._held(load, "a load")
        except Busy as err:
            return False, f"not loaded: {err}"
        except (KeyError, TypeError, ValueError) as err:  # checked before the run changes
            return False, f"cannot load the state in {path}: {err}"
        return True, f"loaded the state at t = {self.run.solver.time:.4f} s from {path}; {self.state}"

    def clear(self):
        """Drop the run (lifecycle cleanup)."""
        def drop(_):
            with self._record_lock:
                self.stop_recording("stopped")
                with self._cond:
                    self.run, self.failure = None, ""

        self._held(drop, "a cleanup")

    def close(self, status: str = "interrupted"):
        """Stop the thread (between two steps) and finish the recording."""
        with self._cond:
            self._closing = True
            self._generation += 1
            self._cond.notify_all()
        self._thread.join()
        self.stop_recording(status)

    # -- recording -----------------------------------------------------------------------------
    def start_recording(self, directory, compression: str = None) -> Path:
        """Start a new bag under ``directory`` (``<scene>_<UTC time>``), its chunks compressed with
        ``compression`` (the run's own by default); returns its path."""
        with self._record_lock:
            if self.recorder is not None:
                return self.recorder.path
            run = self.run
            stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y_%m_%d-%H_%M_%S_%f")
            self.recorder = run.open_recording(Path(directory).expanduser() / f"{run.scene.name}_{stamp}", compression)
            self._recording_run = run
            return self.recorder.path

    def stop_recording(self, status: str):
        """Finish the recording, if any, with the run's result under ``status``; returns its path."""
        with self._record_lock:
            recorder, self.recorder, self._recording_run = self.recorder, None, None
            if recorder is None:
                return None
            try:
                recorder.close(self.run.result(status) if self.run is not None else {"status": status})
            except OSError as err:  # what could be written stays readable (gpusph-analyze --repair)
                self._report("error", f"the recording {recorder.path} could not be finished: {err}")
            return recorder.path

    def flush_recording(self):
        """Close the recording's open chunk if it is due (a paused node writes nothing, and a
        kill must not take what it wrote before)."""
        with self._record_lock:
            if self.recorder is not None:
                try:
                    self.recorder.flush(due_only=True)
                except OSError as err:
                    self._report("error", f"the recording {self.recorder.path} could not be flushed: {err}")
