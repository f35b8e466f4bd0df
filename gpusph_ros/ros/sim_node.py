"""sim_node: the solver live in ROS 2.

    ros2 run gpusph_ros sim_node [--ros-args --params-file FILE -p name:=value ...]

A lifecycle (managed) node and a thin shell over ``runner.Run``: the parameters (``node_params``)
describe a run, configuring builds it, activating steps it in its own thread (``session``), and
each output goes out on the node's topics and, while recording, into a rosbag2/MCAP bag. With
``autostart`` (the default) the node configures and activates itself.

Topics: ``~/particles`` (PointCloud2: x, y, z, then ``particle_fields``, float32), ``~/bodies/<name>/
wrench`` (WrenchStamped, force on the body's particles and torque about the body's centre, in the
body's frame ``<frame_id>/<name>``), ``~/bodies/force_arrows`` (markers), ``~/bodies/<name>/
pressure_blocks/dNNNmm`` (the thesis's pressure-block force), ``~/probes/<name>`` (Vector3Stamped
velocity, FluidPressure, PointStamped surface level), ``/clock`` (before the outputs it stamps),
``/diagnostics`` (1 Hz), a moving body's ``~/bodies/<name>/pose`` (PoseStamped) and ``/odom``
(Odometry) (and, at ``wrench_rate``, ``wrench_fast``, ``pose_fast`` and ``odom_fast``), under ``clock:
lockstep`` ``~/reached`` (std_msgs/Header) answering ``~/advance_to``, and latched (transient local)
``~/scene``, ``~/geometry`` and, where tf2_msgs is
installed, ``/tf_static`` (the fixed bodies' frames; a moving body's go on ``/tf``). z is up in
every scene (``output.frames``); every stamp is simulated time.
Services (std_srvs): ``~/reset``, ``~/set_paused``, ``~/step``, ``~/record``, ``~/save_state`` and
``~/load_state`` (the run's whole state to and from ``state_file``).

No client can stop the node: every callback (services, parameter checks, lifecycle transitions,
timers) answers whatever the layers below raise with a reason, logs it once, and turns an
unexpected error into an ERROR diagnostic; services run side by side and a ~/step waits only for
the solver; after shut-down every service refuses, naming the state.
"""
import collections
import functools
import math
import os
import sys
import threading
import time

import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseStamped, TwistStamped, WrenchStamped
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, SetParametersResult
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor, ShutdownException, SingleThreadedExecutor
from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.qos_overriding_options import QoSOverridingOptions
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import Header
from std_srvs.srv import SetBool, Trigger

from .. import __version__
from ..drive import QUATERNION_TOLERANCE
from ..output import frames, messages
from ..runner import CLOCK_QOS, LATCHED_QOS, PARTICLES_QOS, Run
from ..sph import ConfigError
from ..sph.bodies import quaternion_matrix
from ..sph.config import shown
from . import frame_follow, node_params
from .frame_follow import FrameFollower
from .node_params import PARAMS
from .session import MAX_TARGETS, Session

STEP_WAIT = 30.0  # [s] the longest ~/step waits for its output before it answers
# [s] of wall time between two resets a followed /clock asks for by going back: two publishers that
# disagree, or a clock going back and forth, reset the run at each message (45 resets and 59 bag
# folders in 7 s); a clock that goes back sooner is counted and the reset waits for the next message
# after the interval, so at most one run, and one bag, starts every CLOCK_RESET_INTERVAL
CLOCK_RESET_INTERVAL = 5.0
COMMAND_DEPTH = 10  # the commands a body's subscription holds until the commands thread takes them
# ~/advance_to requests and ~/reached answers held for a slow reader (clock: lockstep): room for twice
# the targets the session takes at once, so that a burst the session refuses in part is still read
# whole and each of its targets answered (a depth of 100 lost the middle of a burst of 500 unanswered)
LOCKSTEP_DEPTH = 2 * MAX_TARGETS
REFUSED = "refused"  # a ~/reached answer's frame_id for a target refused (its stamp is the target's)


def _qos(reliable: bool, depth: int, transient_local: bool = False) -> QoSProfile:
    reliability = ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT
    durability = DurabilityPolicy.TRANSIENT_LOCAL if transient_local else DurabilityPolicy.VOLATILE
    return QoSProfile(depth=depth, reliability=reliability, durability=durability)


def _service(method):
    """A service callback that always answers: refused after shut-down, and whatever it raises
    becomes the reply's reason (and an ERROR diagnostic, until a later request succeeds: a good
    ~/load_state after a failed one left /diagnostics at ERROR)."""
    @functools.wraps(method)
    def call(self, request, response):
        if self.session.state == "shut down":
            response.success, response.message = False, "the node is shut down (lifecycle state finalized)"
            return response
        try:
            response = method(self, request, response)
        except Exception as err:  # the node outlives any one request
            response.success, response.message = False, self._internal(method.__name__.strip("_"), err)
            return response
        if response.success:
            self.internal_error = ""
        return response
    return call


def _transition(method):
    """A lifecycle callback whose failure is FAILURE with the reason logged, never an exit."""
    @functools.wraps(method)
    def call(self, state):
        try:
            return method(self, state)
        except Exception as err:
            self._internal(method.__name__, err)
            return TransitionCallbackReturn.FAILURE
    return call


def _quiet(method):
    """A callback with no one to answer (a timer, the post-set hook): errors are logged once."""
    @functools.wraps(method)
    def call(self, *args):
        try:
            return method(self, *args)
        except Exception as err:
            self._internal(method.__name__.strip("_"), err)
    return call


def _descriptor(p) -> ParameterDescriptor:
    text = f"{p.description}. Applies {node_params.applies_text(p.name)}."
    if p.choices:
        text += " One of: " + ", ".join(p.choices) + "."
    d = ParameterDescriptor(description=text, read_only=p.applies == node_params.STARTUP)
    if p.lo is not None:
        d.floating_point_range = [FloatingPointRange(from_value=float(p.lo), to_value=float(p.hi), step=0.0)]
    return d


class SimNode(LifecycleNode):
    def __init__(self, **kwargs):
        super().__init__("sim_node", **kwargs)
        for p in PARAMS:
            self.declare_parameter(p.name, p.default, _descriptor(p))
        # a -p the node declares no parameter for would be ignored without a word: said at start-up
        # and on /diagnostics
        self.unknown_parameters = node_params.undeclared(
            name for name in self._parameter_overrides
            if not self.has_parameter(name) and not name.startswith("qos_overrides."))
        for line in self.unknown_parameters:
            self.get_logger().error(f"parameter {line}")
        self.namespace = self.get_fully_qualified_name()
        self._fixed_pubs = {
            f"{self.namespace}/particles": self.create_publisher(
                PointCloud2, "~/particles", _qos(**PARTICLES_QOS),
                qos_overriding_options=QoSOverridingOptions.with_default_policies()),
        }
        if self.value("clock") == "publish":  # follow, lockstep: another node's; none: no one's
            self._fixed_pubs["/clock"] = self.create_publisher(Clock, "/clock", _qos(**CLOCK_QOS))
        self._topic_pubs = dict(self._fixed_pubs)
        self._diag_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self.awaiting_reset = set()  # parameters changed since the last build that need one
        self._command_subs = {}  # the driven bodies' command subscriptions, (body, kind) -> subscription
        self._follower = None  # the driven bodies that follow TF frames (frame_follow.py)
        self.commands = collections.Counter()  # (body, "taken" / "refused" / "lost") -> commands
        self._sequence = {}  # (body, kind) -> the last publication sequence number read
        self._commands_lock = threading.Lock()
        # the driven bodies' commands come to a node of their own, spun by one thread that takes and
        # handles each message in turn: under this node's multi-threaded executor a 100 Hz stream
        # kept its threads spinning on the GIL between handing a message on and taking it, and the
        # solver thread stalled (0 steps/s against 480 without)
        self._commands_node = rclpy.create_node(f"{self.get_name()}_commands", namespace=self.get_namespace(),
                                                context=self.context)
        self._executors = [SingleThreadedExecutor(context=self.context)]  # the commands', the lockstep's
        self._executors[0].add_node(self._commands_node)
        threading.Thread(target=self._spin, args=(self._executors[0],), daemon=True, name="commands").start()
        # the last unexpected error a callback caught, until the next build or a request that succeeds
        self.internal_error = ""
        self.clock_refused = self.clock_resets_deferred = 0  # clock: follow
        self._logged = set()
        self._reset_lock = threading.Lock()
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self.session = Session(self._publish, self._report, self._reached)
        self.session.max_lag = self.value("max_lag")
        if self.value("clock") == "lockstep":
            self.session.lockstep = True
            self._reached_pub = self.create_publisher(Header, "~/reached", _qos(True, LOCKSTEP_DEPTH))
            self._lockstep_seq = None
            # a reader that keeps every target it receives (KEEP_ALL: a full queue holds the master's
            # writer back rather than drop), on a thread of its own: on the commands' thread, behind
            # bursts of body commands, a queue of 2,000 lost 239 of 127,394 targets in the soak
            self._lockstep_node = rclpy.create_node(f"{self.get_name()}_lockstep", namespace=self.get_namespace(),
                                                    context=self.context)
            self._advance_sub = self._lockstep_node.create_subscription(
                Header, f"{self.namespace}/advance_to", self._advance_to,
                QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE))
            self._executors.append(SingleThreadedExecutor(context=self.context))
            self._executors[-1].add_node(self._lockstep_node)
            threading.Thread(target=self._spin, args=(self._executors[-1],), daemon=True, name="lockstep").start()
        if self.value("clock") == "follow":
            # on the commands' node: its one thread takes each tick in turn, off the services' threads
            self.session.following = True
            self._clock_reset_at = -math.inf
            self._commands_node.create_subscription(Clock, "/clock", self._clock_tick, _qos(**CLOCK_QOS))
        # services run side by side (a waiting ~/step blocks no ~/set_paused) and apart from the
        # parameter services; the session serialises what must be serialised
        services = ReentrantCallbackGroup()
        self.create_service(Trigger, "~/reset", self._reset, callback_group=services)
        self.create_service(SetBool, "~/set_paused", self._set_paused, callback_group=services)
        self.create_service(Trigger, "~/step", self._step, callback_group=services)
        self.create_service(SetBool, "~/record", self._record, callback_group=services)
        self.create_service(Trigger, "~/save_state", self._save_state, callback_group=services)
        self.create_service(Trigger, "~/load_state", self._load_state, callback_group=services)
        self.create_timer(1.0, self._tick)
        self.get_logger().info(f"gpusph_ros {__version__}")
        if self.value("autostart"):
            self.trigger_configure()
            if self.session.run is not None:
                self.trigger_activate()

    def value(self, name):
        return self.get_parameter(name).value

    def _spin(self, executor):
        try:
            executor.spin()
        except (ExternalShutdownException, ShutdownException):  # the context is going: so is the thread
            pass
        except Exception:
            # SIGTERM shuts the context down under the wait: 1 in 14 printed "RCLError: failed to
            # initialize wait set" from this thread; an error while the context still runs is real
            if self.context.ok():
                raise

    def destroy_node(self):
        for executor in self._executors:
            executor.shutdown(timeout_sec=2.0)
        for helper in (self._commands_node, getattr(self, "_lockstep_node", None)):
            if helper is not None:
                helper.destroy_node()
        return super().destroy_node()

    def _internal(self, what: str, err: BaseException) -> str:
        """Log an unexpected error once (by its text) and keep it for /diagnostics; the reason."""
        reason = f"{what} failed: {type(err).__name__}: {shown(str(err))}"
        self.internal_error = reason
        if reason not in self._logged:
            self._logged.add(reason)
            self.get_logger().error(reason)
        return reason

    def values(self) -> dict:
        return {p.name: self.value(p.name) for p in PARAMS}

    # -- parameters ----------------------------------------------------------------------------
    def _check_parameters(self, parameters) -> SetParametersResult:
        changes = {p.name: p.value for p in parameters if p.name in node_params.BY_NAME}
        if not changes:
            return SetParametersResult(successful=True)
        if self.session.state == "shut down":  # as the services: nothing more is taken
            return SetParametersResult(successful=False, reason=f"{', '.join(changes)}: the node is shut down "
                                                                "(lifecycle state finalized); start a new one")
        try:
            reason = node_params.check({**self.values(), **changes}, changed=changes)
        except Exception as err:  # a scene file no check foresaw: refused, never an exit
            reason = self._internal(f"checking {', '.join(changes)}", err)
        if reason:
            self.get_logger().warning(f"rejected {', '.join(changes)}: {reason}")
            return SetParametersResult(successful=False, reason=reason)
        self.internal_error = ""  # as after a service that succeeds: a check that raised is past
        return SetParametersResult(successful=True)

    def set_parameters_atomically(self, parameter_list):
        """As Node's, and a successful change's reply says when it takes effect (rclpy keeps only
        a failed callback's reason, so the note is added here, where the parameter service asks)."""
        result = super().set_parameters_atomically(parameter_list)
        names = [p.name for p in parameter_list if p.name in node_params.BY_NAME]
        if result.successful and names:
            result.reason = "; ".join(f"{name} applies {node_params.applies_text(name)}" for name in names)
        return result

    @_quiet
    def _apply_parameters(self, parameters):
        changes = {p.name: p.value for p in parameters if p.name in node_params.BY_NAME}
        live = {k: v for k, v in changes.items() if node_params.BY_NAME[k].applies == node_params.LIVE}
        self.awaiting_reset |= {k for k in changes if node_params.BY_NAME[k].applies == node_params.RESET}
        if self.session.run is not None and live:
            self.session.change(**node_params.live_settings({**self.values(), **live}, live))
        if "record_dir" in changes and not changes["record_dir"]:
            self.session.stop_recording("stopped")
        if self.awaiting_reset & set(changes):
            self.get_logger().info(f"{', '.join(sorted(self.awaiting_reset))} changed: applies at the next ~/reset")

    # -- building ------------------------------------------------------------------------------
    def _build(self) -> Run:
        values = self.values()
        scene, config = node_params.run_settings(values)
        run = Run(scene, config, namespace=self.namespace, frame_id=values["frame_id"])
        run.set_cloud(fields=values["particle_fields"])
        self._make_publishers(run)
        self._make_commands(run)
        return run

    def _make_commands(self, run):
        """For each driven body of the scene, ``~/bodies/<name>/cmd_pose`` (PoseStamped) and
        ``~/bodies/<name>/cmd_twist`` (TwistStamped); for each floating one ``~/bodies/<name>/
        cmd_wrench`` (WrenchStamped, world axes, about its centre of mass); the previous scene's go."""
        for sub in self._command_subs.values():
            self._commands_node.destroy_subscription(sub)
        self._command_subs = {}
        for name in run.drivers:
            for kind, msg_type in (("pose", PoseStamped), ("twist", TwistStamped)):
                self._command_subs[(name, kind)] = self._commands_node.create_subscription(
                    msg_type, f"{self.namespace}/bodies/{name}/cmd_{kind}",
                    functools.partial(self._command, name, kind), COMMAND_DEPTH)
        for name in run.wrenches:
            self._command_subs[(name, "wrench")] = self._commands_node.create_subscription(
                WrenchStamped, f"{self.namespace}/bodies/{name}/cmd_wrench",
                functools.partial(self._command, name, "wrench"), COMMAND_DEPTH)
        self._sequence = {}
        self._follow(run)

    def _follow(self, run):
        """The driven bodies that follow a TF frame (``motion.frame``): ``/tf`` and ``/tf_static``
        (frame_follow.py), where tf2_msgs is installed; where it is not, they take cmd_pose and
        cmd_twist only, which the log says."""
        follows = {o.name: o.motion.frame for o in run.model.scene.obstacles
                   if o.name in run.drivers and o.motion.frame}
        self._follower = FrameFollower(follows, run.frame_id) if follows else None
        if not follows:
            return
        try:
            from tf2_msgs.msg import TFMessage
        except ImportError:
            self.get_logger().error(f"{', '.join(follows)}: motion.frame needs tf2_msgs (ros-jazzy-tf2-msgs), "
                                    "which is not installed; these bodies take cmd_pose and cmd_twist only")
            return
        for topic, static in (("/tf", False), ("/tf_static", True)):
            self._command_subs[("tf", topic)] = self._commands_node.create_subscription(
                TFMessage, topic, functools.partial(self._transforms, static),
                _qos(reliable=True, depth=100, transient_local=static))

    def _transforms(self, static: bool, msg):
        """A TF message: each driven body whose frame it moves takes the frame's pose as a pose
        command (frame_follow.py), counted and logged as a cmd_pose is."""
        try:
            run, follower = self.session.run, self._follower
            if run is None or follower is None:
                return
            for body, result in follower.take(msg.transforms, static):
                if self._ended(body, f"frame {follower.bodies[body]!r} on /tf"):
                    continue
                taken, why = frame_follow.command(run, body, result)
                self._count(body, f"frame {follower.bodies[body]!r} on /tf", taken, why)
        except Exception as err:  # a message the layers below did not foresee: logged, never an exit
            self._internal("/tf", err)

    def _command(self, body: str, kind: str, msg, info):
        """A driven body's command or a floating body's external wrench (drive.py), in the published
        axes and stamped in simulated time (a zero stamp: now); a refusal (a body the present scene
        does not have among them too) is logged with its reason, at most once a second, and so are
        the commands dropped before the node read them (``_lost``)."""
        try:
            self._lost(body, kind, info)
            run = self.session.run
            if run is None:
                return
            if self._ended(body, kind):
                return
            dim = run.model.config.dim
            stamp = run.stamp_time(msg.header.stamp.sec + msg.header.stamp.nanosec * 1.0e-9)
            if msg.header.frame_id not in ("", run.frame_id):  # a pose in base_link was taken as the world's
                self._count(body, kind, False, f"{kind}: frame {shown(msg.header.frame_id)}; expected the world "
                                               f"frame {run.frame_id!r} (or none)")
                return
            if kind == "wrench":
                f, m = msg.wrench.force, msg.wrench.torque
                taken, why = run.push(body, stamp, frames.scene_vector(dim, (f.x, f.y, f.z)),
                                      frames.scene_vector(dim, (m.x, m.y, m.z), axial=True))
                self._count(body, kind, taken, why)
                return
            if kind == "pose":
                p, q = msg.pose.position, msg.pose.orientation
                a, b = frames.scene_vector(dim, (p.x, p.y, p.z)), np.array([q.x, q.y, q.z, q.w])
                if np.all(np.isfinite(b)) and abs(np.linalg.norm(b) - 1.0) <= QUATERNION_TOLERANCE:
                    b = frames.scene_rotation(dim, quaternion_matrix(b / np.linalg.norm(b)))
            else:
                v, w = msg.twist.linear, msg.twist.angular
                a, b = frames.scene_vector(dim, (v.x, v.y, v.z)), frames.scene_vector(dim, (w.x, w.y, w.z), axial=True)
            taken, why = run.command(body, kind, stamp, a, b)
            self._count(body, kind, taken, why)
        except Exception as err:  # a command the layers below did not foresee: logged, never an exit
            self._internal(f"~/bodies/{body}/cmd_{kind}", err)

    def _lost(self, body: str, kind: str, info):
        """Count the commands of one publisher that never reached the callback: its sequence numbers
        skip them (the subscription holds 10; at 10 kHz 86% went unseen and uncounted). Counted only
        while one publisher sends on the topic: two number their messages apart."""
        seq = info.get("publication_sequence_number") if isinstance(info, dict) else None
        if not seq:  # a middleware that does not number them
            return
        sub = self._command_subs.get((body, kind))
        last, self._sequence[(body, kind)] = self._sequence.get((body, kind)), seq
        if last is None or seq <= last + 1 or sub is None or sub.get_publisher_count() != 1:
            return
        with self._commands_lock:
            self.commands[(body, "lost")] += seq - last - 1
        self.get_logger().warning(f"~/bodies/{body}/cmd_{kind}: {seq - last - 1} commands were dropped before the "
                                  f"node read them: they came faster than it takes them (a queue of "
                                  f"{COMMAND_DEPTH})", throttle_duration_sec=1.0)

    def _ended(self, body: str, kind: str) -> bool:
        """Whether the run can no longer take a command (failed, finished, shut down): then it is
        counted as refused, with the reason (they were counted as taken after the run ended)."""
        state = self.session.state
        if state in ("running", "paused", "stepping", "inactive"):
            return False
        self._count(body, kind, False, f"{kind}: the run is {state}; ~/reset starts it again")
        return True

    def _count(self, body: str, kind: str, taken: bool, why: str):
        """A command taken or refused, counted for /diagnostics; a refusal or a clamp logged (``kind``:
        pose, twist, wrench, or where a frame's pose came from)."""
        with self._commands_lock:
            self.commands[(body, "taken" if taken else "refused")] += 1
        if not taken or why != "taken":
            where = f"~/bodies/{body}/cmd_{kind}" if kind in ("pose", "twist", "wrench") else f"{body}: {kind}"
            self.get_logger().warning(f"{where}: {why}", throttle_duration_sec=1.0)

    def _make_publishers(self, run):
        """One publisher per topic of the scene's outputs (found from the outputs at t = 0);
        those of the previous scene that this one lacks are removed."""
        latched = run.latched_messages()
        outputs = run.output_messages(0) + (run.fast_messages(clock=False) if run.output.wrench_rate else [])
        wanted = {topic: (type(msg), 10) for topic, msg in outputs
                  if topic != "/clock"}  # /clock's is fixed (clock: publish) or none (follow, none)
        wanted |= {topic: (type(msg), _qos(**LATCHED_QOS)) for topic, msg in latched}
        for topic in list(self._topic_pubs):
            if topic not in self._fixed_pubs and topic not in wanted:
                self.destroy_publisher(self._topic_pubs.pop(topic))
        for topic, (msg_type, qos) in wanted.items():
            if topic not in self._topic_pubs:
                self._topic_pubs[topic] = self.create_publisher(msg_type, topic, qos)
        for topic, msg in latched:  # a subscriber that joins later gets them from the publisher
            self._send(self._topic_pubs[topic], msg)

    def _load(self) -> str:
        """Build the run from the parameters; a one-line account of it."""
        run = self.session.replace(self._build)
        self.session.real_time_factor = self.value("real_time_factor")
        self.awaiting_reset.clear()
        self.internal_error = ""
        with self._commands_lock:  # a new run's commands are counted from none
            self.commands.clear()
        text = run.summary()
        self.get_logger().info(text)
        for warning in run.scene.warnings:
            self.get_logger().warning(f"scene: {warning}")
        return text

    def _start_recording(self, directory):
        return self.session.start_recording(directory, self.value("compression"))

    def _maybe_record(self) -> str:
        directory = self.value("record_dir")
        if not directory or self.session.run is None:
            return ""
        try:
            return f"; recording to {self._start_recording(directory)}"
        except OSError as err:  # checked when set, but a folder can go away or fill up
            return f"; not recording: cannot write under {directory} ({err.strerror or err})"

    # -- lifecycle -----------------------------------------------------------------------------
    def _LifecycleNodeMixin__on_change_state(self, request, response):
        """The ~/change_state service. rclpy's own raises RCLError on a transition the current state
        does not allow (configure while active, anything after shut-down), and the error ends the
        process; here such a request is refused (success false) with the reason logged, and so is
        any error of the transition itself. (rclpy binds the service to this name at start-up.)"""
        state = self._state_machine.current_state[1]
        allowed = {(t[0], t[1]) for t in self._state_machine.available_transitions}
        wanted = request.transition.label or request.transition.id
        if not any(wanted in pair for pair in allowed):
            names = ", ".join(sorted(label for _, label in allowed)) or "none"
            self.get_logger().warning(f"transition {wanted!r} refused: not allowed from state {state!r} "
                                      f"(allowed: {names})")
            response.success = False
            return response
        try:
            return super()._LifecycleNodeMixin__on_change_state(request, response)
        except Exception as err:  # whatever a transition raises, the node stays up
            self._internal(f"transition {wanted!r} from {state!r}", err)
            response.success = False
            return response

    @_transition
    def on_configure(self, state) -> TransitionCallbackReturn:
        reason = node_params.check(self.values())
        if reason:
            self.get_logger().error(f"cannot configure: {reason}")
            return TransitionCallbackReturn.FAILURE
        try:
            self._load()
        except (ConfigError, ValueError, RuntimeError, OSError, MemoryError) as err:
            self.get_logger().error(f"cannot configure: {err}")
            return TransitionCallbackReturn.FAILURE
        return super().on_configure(state)

    @_transition
    def on_activate(self, state) -> TransitionCallbackReturn:
        self.session.set_active(True)
        note = self._maybe_record()
        if note:
            self.get_logger().info(note[2:])
        return super().on_activate(state)

    @_transition
    def on_deactivate(self, state) -> TransitionCallbackReturn:
        self.session.set_active(False)
        return super().on_deactivate(state)

    @_transition
    def on_cleanup(self, state) -> TransitionCallbackReturn:
        self.session.clear()
        return super().on_cleanup(state)

    @_transition
    def on_shutdown(self, state) -> TransitionCallbackReturn:
        self.session.close("shutdown")
        return super().on_shutdown(state)

    # -- services ------------------------------------------------------------------------------
    @_service
    def _reset(self, request, response):
        if not self._reset_lock.acquire(blocking=False):
            response.success, response.message = False, "a reset is already under way; wait for its answer"
            return response
        try:
            return self._reset_now(response)
        finally:
            self._reset_lock.release()

    def _reset_now(self, response):
        reason = node_params.check(self.values())
        if reason:
            response.success, response.message = False, f"not reset: {reason}"
            return response
        if self.session.run is None:
            configured = self.trigger_configure() == TransitionCallbackReturn.SUCCESS
            if configured and self.value("autostart"):
                self.trigger_activate()
            response.success = configured
            response.message = (f"configured: {self._account()}" if configured
                                 else "configuring failed; see the node's log")
            return response
        try:
            text = self._load()
        except (ConfigError, ValueError, RuntimeError, OSError, MemoryError) as err:
            response.success, response.message = False, f"not reset, the previous scene stays: {shown(str(err))}"
            return response
        response.success, response.message = True, f"reset: {text}; {self.session.state}{self._maybe_record()}"
        return response

    def _account(self) -> str:
        run = self.session.run
        return "no scene" if run is None else f"{run.scene.name}, {run.solver.n} particles, {self.session.state}"

    @_service
    def _set_paused(self, request, response):
        response.success, response.message = self.session.set_paused(request.data)
        return response

    @_service
    def _step(self, request, response):
        response.success, response.message = self.session.step(STEP_WAIT)
        return response

    @_service
    def _record(self, request, response):
        if not request.data:
            path = self.session.stop_recording("stopped")
            response.success = True
            response.message = f"recording stopped: {path}" if path else "was not recording"
            return response
        directory = self.value("record_dir")
        if not directory:
            response.success = False
            response.message = "record_dir is empty: set it first (ros2 param set /sim_node record_dir /some/folder)"
        elif self.session.run is None:
            response.success, response.message = False, "no scene is loaded: configure the node (or call ~/reset)"
        else:
            try:
                response.success, response.message = True, f"recording to {self._start_recording(directory)}"
            except OSError as err:
                response.success, response.message = False, f"cannot record to {directory}: {err}"
        return response

    def _with_state_file(self, response, act):
        path = self.value("state_file")
        if not path:
            response.success, response.message = False, "state_file is empty: set it first (a file path)"
            return response
        try:
            response.success, response.message = act(path)
        except OSError as err:
            response.success, response.message = False, f"cannot write {path}: {err.strerror or err}"
        return response

    @_service
    def _save_state(self, request, response):
        return self._with_state_file(response, self.session.save_state)

    @_service
    def _load_state(self, request, response):
        return self._with_state_file(response, self.session.load_state)

    # -- output --------------------------------------------------------------------------------
    def _publish(self, topic, msg, data):
        publisher = self._topic_pubs.get(topic)
        if publisher is not None:
            self._send(publisher, data)

    def _send(self, publisher, message):
        """Publish, unless SIGINT or SIGTERM has shut the context down under the solver thread:
        then the outputs stop quietly and main() finishes the recording as interrupted."""
        try:
            publisher.publish(message)
        except Exception:
            if self.context.ok():
                raise

    def _report(self, level, text):
        if level == "error":
            self.get_logger().error(text)
        elif level == "warn":
            self.get_logger().warning(text)
        else:
            self.get_logger().info(text)
        self._publish_diagnostics()

    @_quiet
    def _clock_tick(self, msg):
        """clock: follow: the fluid may advance to the followed clock's time; a clock that goes back
        (a simulator's reset) resets the run, which then follows the clock from there, at most once
        every CLOCK_RESET_INTERVAL. A stamp ROS would not read (nanosec not below 10^9, a time before
        0) is refused and counted (/diagnostics: clock_refused)."""
        sec, nanosec = msg.clock.sec, msg.clock.nanosec
        if not (0 <= nanosec < 1_000_000_000) or sec < 0:
            self.clock_refused += 1
            self.get_logger().error(f"/clock: sec {sec}, nanosec {nanosec} is not a time (nanosec must be below "
                                    "10^9, the time at least 0): refused", throttle_duration_sec=1.0)
            return
        t = sec + nanosec * 1e-9
        if self.session.clock_to(t):
            return
        if time.monotonic() - self._clock_reset_at < CLOCK_RESET_INTERVAL:
            self.clock_resets_deferred += 1
            self.get_logger().warning(f"the followed /clock went back to t = {t:.4f} s within "
                                      f"{CLOCK_RESET_INTERVAL:g} s of the last reset it asked for: the reset waits "
                                      "(two publishers on /clock?)", throttle_duration_sec=1.0)
            return
        self.get_logger().warning(f"the followed /clock went back to t = {t:.4f} s: resetting the run")
        answer = self._reset(Trigger.Request(), Trigger.Response())
        if not answer.success:
            self.get_logger().error(f"the reset the clock asked for failed: {answer.message}")
        self.session.restart_clock(t)
        self._clock_reset_at = time.monotonic()  # the interval counts from the new run (a build takes time)

    @_quiet
    def _advance_to(self, msg, info):
        """clock: lockstep: the fluid is to reach the stamp of ``msg`` (std_msgs/Header); answered on
        ~/reached, in order (Session.advance_to). A target refused (too many waiting) is answered at
        once with its own stamp and frame_id ``refused``, and counted (/diagnostics:
        lockstep_refused); targets the middleware dropped unread are counted (lockstep_lost)."""
        seq = info.get("publication_sequence_number") if isinstance(info, dict) else None
        last, self._lockstep_seq = self._lockstep_seq, seq or self._lockstep_seq
        if seq and last is not None and seq > last + 1 and self._advance_sub.get_publisher_count() == 1:
            self.session.lockstep_lost += seq - last - 1
            self.get_logger().error(f"~/advance_to: {seq - last - 1} targets were dropped before the node read "
                                    "them (publish targets with a reliable KEEP_ALL writer); they are not answered",
                                    throttle_duration_sec=1.0)
        why = self.session.advance_to((msg.stamp.sec * 1_000_000_000 + msg.stamp.nanosec) / 1.0e9)
        if why:
            self._send(self._reached_pub, Header(stamp=msg.stamp, frame_id=REFUSED))
            self.get_logger().warning(f"~/advance_to: {why}", throttle_duration_sec=1.0)

    def _reached(self, target: float, t: float):
        """A lockstep target answered: ~/reached carries the fluid's time, the target's where it got
        there (short of it where the run ended or failed first, past it where it had passed it)."""
        msg = Header(stamp=messages.stamp(t), frame_id=self.value("frame_id"))
        self._send(self._reached_pub, msg)

    @_quiet
    def _tick(self):
        """Once a second: /diagnostics, and the recording's open chunk closed if due."""
        self.session.flush_recording()
        self._publish_diagnostics()

    def _publish_diagnostics(self):
        stats = self.session.stats()
        state = stats["state"]
        level = {"failed": DiagnosticStatus.ERROR, "unconfigured": DiagnosticStatus.WARN,
                 "shut down": DiagnosticStatus.WARN}.get(state, DiagnosticStatus.OK)
        message = f"failed: {stats['error']}" if state == "failed" else state
        if stats.get("excluded_particles") and level == DiagnosticStatus.OK:
            # the run goes on without them, up to max_excluded_fraction of the fluid
            level = DiagnosticStatus.WARN
            message += (f"; {stats['excluded_particles']} fluid particles excluded "
                        f"({stats['excluded_fraction']:.3%} of the fluid mass: {stats['excluded_by_reason']})")
        if stats.get("left_tank_particles"):  # physics, not a fault: said, not warned of
            message += (f"; {stats['left_tank_particles']} fluid particles left the tank over its walls "
                        f"({stats['left_tank_fraction']:.3%} of the fluid mass)")
        if "clock_lag" in stats:
            message += (f"; following /clock (t = {stats['clock_followed']:.3f} s): the fluid "
                        f"{stats['clock_lag']:.3f} s behind, at worst {stats['clock_lag_worst']:.3f} s")
            stats.update(clock_refused=self.clock_refused, clock_resets_deferred=self.clock_resets_deferred)
            if stats["clock_lag"] > self.session.max_lag and state not in ("finished", "failed"):
                level = max(level, DiagnosticStatus.WARN)
                message += f", past max_lag {self.session.max_lag:g} s"
        if self.unknown_parameters:
            level = max(level, DiagnosticStatus.WARN)
            names = ", ".join(u.split(":")[0] for u in self.unknown_parameters)
            message += f"; parameters not taken at start-up: {names}"
            stats["unknown_parameters"] = "; ".join(self.unknown_parameters)
        if self.internal_error:
            level, message = DiagnosticStatus.ERROR, f"{message}; {self.internal_error}"
            stats["internal_error"] = self.internal_error
        if self.awaiting_reset:
            message += f" ({', '.join(sorted(self.awaiting_reset))} changed: applies at the next ~/reset)"
        for (body, outcome), count in sorted(self.commands.items()):  # a driven body's commands
            stats[f"commands_{outcome}_{body}"] = count
        status = DiagnosticStatus(level=level, name=f"{self.get_name()}: solver", message=message,
                                  hardware_id=str(stats.get("device", self.value("device"))))
        status.values = [KeyValue(key=key, value=_text(value)) for key, value in stats.items()]
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = messages.stamp(stats.get("simulated_time", 0.0))
        self._send(self._diag_pub, msg)


def _text(value) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def main(argv=None):
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING  # no per-module load lines in the node's output
    rclpy.init(args=sys.argv if argv is None else argv)
    node = SimNode()
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.session.close("interrupted")
        node.destroy_node()
        rclpy.try_shutdown()
        _end_within(EXIT_GRACE)
    return 0


EXIT_GRACE = 3.0  # [s] after shut-down, the longest a callback still running may hold the process


def _end_within(seconds: float):
    """End the process ``seconds`` from now if it has not ended by then. Python's exit waits for every
    executor thread, and a callback still busy (a ~/reset building a large scene) would keep a node
    that SIGINT or SIGTERM stopped alive for as long as it takes; the recording is closed by now."""
    def end():
        time.sleep(seconds)
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)

    threading.Thread(target=end, name="exit", daemon=True).start()


if __name__ == "__main__":
    sys.exit(main())
