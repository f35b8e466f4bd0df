#!/usr/bin/env python3
"""A stand-in robot loop that steps sim_node in lockstep (``clock: lockstep``): it sends each time on
``/sim_node/advance_to`` (std_msgs/Header: the stamp), waits for ``/sim_node/reached`` to answer it,
reads the body's wrench at that time (``wrench_fast``, with ``wrench_rate`` set to the loop's rate)
and goes on. A robot simulator that can be stepped does the same: gz-sim's world control service
through ros_gz_bridge (launch/gz_lockstep.launch.py).

    ros2 run gpusph_ros sim_node --ros-args -p scene:=paddle_2d -p dx:=0.04 -p clock:=lockstep \\
        -p wrench_rate:=1000.0
    python3 examples/lockstep_loop.py --body paddle --step 0.001 --end 0.5 --out loop.csv

With ``--gz-world NAME`` it steps gz-sim first, through ros_gz_bridge: before each target it asks
``/world/NAME/control`` (ros_gz_interfaces/srv/ControlWorld) for the steps of ``--gz-step`` that
make up ``--step``, and waits for the bridged ``/clock`` to reach the target; then the fluid follows.
That mode is not run here: these machines have no gz-sim (launch/gz_lockstep.launch.py).

Each row of ``--out``: the target [s], the time the node answered with, the wall time the round
trip took [ms], and the body's force and torque (x, y, z) at that time. It stops, with exit status 1,
at the first answer that does not come within ``--timeout`` or is not the target's.
"""
import argparse
import csv
import sys
import threading
import time

import rclpy
from builtin_interfaces.msg import Time
from geometry_msgs.msg import WrenchStamped
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Header

NS = 1_000_000_000


class GzWorld:
    """gz-sim's world, paused, stepped through ros_gz_bridge: ``step_to(t_ns)`` asks for the steps of
    ``step`` [s] that bring its /clock to ``t_ns`` and waits until it reads so."""

    def __init__(self, node, world: str, step: float):
        from ros_gz_interfaces.srv import ControlWorld  # gz-sim's own: only this mode needs it

        self.request = ControlWorld.Request()
        self.request.world_control.pause = True
        self.control = node.create_client(ControlWorld, f"/world/{world}/control")
        self.step_ns, self.now_ns = int(round(step * NS)), 0
        self.cond = threading.Condition()
        node.create_subscription(Clock, "/clock", self._tick, 10)

    def _tick(self, msg):
        with self.cond:
            self.now_ns = msg.clock.sec * NS + msg.clock.nanosec
            self.cond.notify_all()

    def step_to(self, target_ns: int, timeout: float) -> bool:
        with self.cond:
            steps = (target_ns - self.now_ns) // self.step_ns
        if steps > 0:
            self.request.world_control.multi_step = int(steps)
            self.control.call_async(self.request)
        deadline = time.monotonic() + timeout
        with self.cond:
            return self.cond.wait_for(lambda: self.now_ns >= target_ns, max(0.0, deadline - time.monotonic()))


class Loop:
    def __init__(self, node, namespace: str, body: str):
        qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        # KEEP_ALL: a target the node has not read yet holds publish() back rather than being overwritten
        self.pub = node.create_publisher(Header, f"{namespace}/advance_to", QoSProfile(
            history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE))
        self.answers, self.wrenches = [], {}
        self.cond = threading.Condition()
        node.create_subscription(Header, f"{namespace}/reached", self._answer, qos)
        if body:
            node.create_subscription(WrenchStamped, f"{namespace}/bodies/{body}/wrench_fast", self._wrench, qos)

    def _answer(self, msg):
        with self.cond:
            self.answers.append(msg.stamp.sec * NS + msg.stamp.nanosec)
            self.cond.notify_all()

    def _wrench(self, msg):
        f, m = msg.wrench.force, msg.wrench.torque
        with self.cond:
            self.wrenches[msg.header.stamp.sec * NS + msg.header.stamp.nanosec] = (f.x, f.y, f.z, m.x, m.y, m.z)
            self.cond.notify_all()

    def advance(self, target_ns: int, timeout: float, wrench: bool):
        """Send ``target_ns``, wait for its answer (and the wrench at it): (answer [ns], wrench)."""
        with self.cond:
            count = len(self.answers)
        self.pub.publish(Header(stamp=Time(sec=target_ns // NS, nanosec=target_ns % NS)))
        deadline = time.monotonic() + timeout
        with self.cond:
            while len(self.answers) == count or (wrench and self.answers[count] == target_ns
                                                 and target_ns not in self.wrenches):
                if not self.cond.wait(deadline - time.monotonic()):
                    return None, None
            return self.answers[count], self.wrenches.pop(target_ns, None)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--namespace", default="/sim_node")
    parser.add_argument("--body", default="", help="the body whose wrench_fast to read at each step")
    parser.add_argument("--step", type=float, default=0.001, help="[s] simulated, each advance")
    parser.add_argument("--end", type=float, default=0.5, help="[s] simulated, the last target")
    parser.add_argument("--timeout", type=float, default=30.0, help="[s] wall, the longest an answer may take")
    parser.add_argument("--out", help="a CSV file for the rows")
    parser.add_argument("--gz-world", help="step this gz-sim world first, through ros_gz_bridge (not run here)")
    parser.add_argument("--gz-step", type=float, default=0.001, help="[s] gz-sim's physics step")
    args = parser.parse_args(argv)
    rclpy.init()
    node = rclpy.create_node("lockstep_loop")
    loop = Loop(node, args.namespace, args.body)
    world = GzWorld(node, args.gz_world, args.gz_step) if args.gz_world else None
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    deadline = time.monotonic() + args.timeout
    while node.count_subscribers(f"{args.namespace}/advance_to") == 0:  # the node is up
        if time.monotonic() > deadline:
            print(f"no node listens on {args.namespace}/advance_to", file=sys.stderr)
            return 1
        time.sleep(0.1)
    step_ns, steps = int(round(args.step * NS)), int(round(args.end / args.step))
    rows, status, start = [], 0, time.monotonic()
    for k in range(1, steps + 1):
        sent = time.monotonic()
        if world is not None and not world.step_to(k * step_ns, args.timeout):
            print(f"step {k}: gz-sim's /clock did not reach {k * step_ns / NS:.6f} s", file=sys.stderr)
            status = 1
            break
        answer, wrench = loop.advance(k * step_ns, args.timeout, bool(args.body))
        if answer != k * step_ns:
            print(f"step {k}: target {k * step_ns / NS:.6f} s answered with "
                  f"{'nothing' if answer is None else f'{answer / NS:.6f} s'}", file=sys.stderr)
            status = 1
            break
        rows.append([k * step_ns / NS, answer / NS, 1e3 * (time.monotonic() - sent), *(wrench or [""] * 6)])
    wall = time.monotonic() - start
    if rows:
        print(f"{len(rows)} steps of {args.step:g} s answered in order to t = {rows[-1][1]:.6f} s in {wall:.2f} s of "
              f"wall time: real-time factor {rows[-1][1] / wall:.3f}")
    if args.out:
        with open(args.out, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(["target_s", "reached_s", "round_trip_ms", "fx", "fy", "fz", "tx", "ty", "tz"])
            writer.writerows(rows)
    executor.shutdown(timeout_sec=5.0)
    spinner.join(timeout=5.0)
    node.destroy_node()
    rclpy.shutdown()
    return status


if __name__ == "__main__":
    sys.exit(main())
