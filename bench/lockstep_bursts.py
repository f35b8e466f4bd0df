"""Bursts of lockstep targets back to back, beside bursts of body commands: does sim_node read
every target? (issue 66: the 30-minute soak lost 239 of 127,394 to the middleware).

Starts sim_node on ``paddle_2d`` at 4 cm with ``clock: lockstep`` on a DDS domain of its own, then
sends --bursts bursts of --size targets 1 ms apart (the next burst --gap s after the last is sent)
while a second thread sends the paddle 200 twist commands at a time; at the end sets an end time
behind the fluid so that every target still waiting is answered, and prints the targets sent, the
answers (reached and refused) and the node's own counts (/diagnostics: lockstep_refused,
lockstep_lost). Exit status 1 where a target went unanswered.

Sent with a KEEP_ALL writer, as docs/node.md asks of a master, a burst the node has not read holds
``publish`` back and nothing is lost; ``--keep-last 2000`` shows what a KEEP_LAST writer loses.

    python bench/lockstep_bursts.py [--bursts 20] [--size 1500] [--gap 0.1] [--keep-last N]
"""
import argparse
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bursts", type=int, default=20)
    parser.add_argument("--size", type=int, default=1500)
    parser.add_argument("--gap", type=float, default=0.1, help="[s] between the end of a burst and the next")
    parser.add_argument("--keep-last", type=int, default=0,
                        help="the targets' writer keeps the last N (KEEP_LAST), not all (KEEP_ALL)")
    args = parser.parse_args()
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import TwistStamped
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import Header

    from ros_client import Client, stop

    domain = 150 + os.getpid() % 80
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    node = subprocess.Popen([sys.executable, "-m", "gpusph_ros.ros.sim_node", "--ros-args", "-p", "scene:=paddle_2d",
                             "-p", "dx:=0.04", "-p", "clock:=lockstep", "-p", "end_time:=1000.0"],
                            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    client = Client(domain)
    qos = QoSProfile(depth=2000, reliability=ReliabilityPolicy.RELIABLE)
    writer = (QoSProfile(depth=args.keep_last, reliability=ReliabilityPolicy.RELIABLE) if args.keep_last else
              QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE))
    counts = {"answered": 0, "refused": 0}
    lock = threading.Lock()

    def reached(msg):
        with lock:
            counts["answered"] += 1
            counts["refused"] += msg.frame_id == "refused"
    client.node.create_subscription(Header, "/sim_node/reached", reached, qos)
    client.subscribe("/diagnostics", DiagnosticArray)
    targets = client.node.create_publisher(Header, "/sim_node/advance_to", writer)
    twist = client.node.create_publisher(TwistStamped, "/sim_node/bodies/paddle/cmd_twist", 10)
    try:
        client.wait_for("/diagnostics", lambda m: bool(m) and "running" in m[-1].status[0].message, timeout=300.0)
        while targets.get_subscription_count() == 0 or client.node.count_publishers("/sim_node/reached") == 0:
            time.sleep(0.05)
        time.sleep(0.5)
        sending = {"on": True}

        def commands():
            while sending["on"]:
                for _ in range(200):
                    twist.publish(TwistStamped())
                time.sleep(0.05)
        threading.Thread(target=commands, daemon=True).start()
        sent, t_ns, start = 0, 0, time.monotonic()
        for _ in range(args.bursts):
            for _ in range(args.size):
                t_ns += 1_000_000
                msg = Header()
                msg.stamp.sec, msg.stamp.nanosec = divmod(t_ns, 1_000_000_000)
                targets.publish(msg)
                sent += 1
            time.sleep(args.gap)
        sending["on"] = False
        took = time.monotonic() - start
        client.set(end_time=0.05)  # behind the fluid: the run ends, every waiting target is answered
        deadline = time.monotonic() + 60.0
        while counts["answered"] < sent and time.monotonic() < deadline:
            time.sleep(0.2)
        time.sleep(1.5)  # /diagnostics comes once a second: one sent after the last answer
        values = {kv.key: kv.value for kv in client.wait_for(
            "/diagnostics", lambda m: bool(m), timeout=10.0)[-1].status[0].values}
    finally:
        client.close()
        stop(node)
    lost = sent - counts["answered"]
    history = f"KEEP_LAST {args.keep_last}" if args.keep_last else "KEEP_ALL"
    print(f"{args.bursts} bursts of {args.size} targets ({args.gap:g} s apart, {history}) in {took:.1f} s, beside "
          f"200 twist commands every 50 ms: sent {sent:,}, answered {counts['answered']:,} "
          f"(refused {counts['refused']:,}), unanswered {lost:,}; the node: "
          + ", ".join(f"{k} {values.get(k)}" for k in ("lockstep_refused", "lockstep_lost", "lockstep_waiting")))
    return 1 if lost else 0


if __name__ == "__main__":
    sys.exit(main())
