"""A soak of sim_node: a node stepping a small 2D tank (SCENE: a driven paddle and a floating box) at
3 cm for --minutes, driven by one client that makes a call at random every --period seconds (about) of
every kind a user or a hostile client makes: parameter gets, live and reset parameter sets, refused
values (a 100 kB choice, a frame id that is no ROS name, an out-of-range number), ~/set_paused,
~/step, ~/record on and off, ~/reset, ~/save_state and ~/load_state (of the state saved, of a FIFO,
of a pickle that carries code), lifecycle deactivate / activate, and the bodies' commands: poses and
twists for the paddle and wrenches for the box, good and hostile (not finite, 1e308, another frame,
a stamp from the future, a rotation that is not one), one at a time or in bursts of 200. Every call
has 2 s to answer.

Every --sample seconds it samples the node's resident memory, open files and threads from /proc;
each bag the node has closed is opened with rosbags and its messages counted against its index
(then deleted, so a long soak does not fill the disk). At the end the node is stopped with SIGINT.

Writes ``soak.csv`` (the samples), ``soak_calls.csv`` (each call: time, kind, latency, answered) and
``soak.md`` (the summary: RSS growth per minute after the first 5 minutes by a least-squares line,
the latencies' median, 99th percentile and worst per kind, calls unanswered within 2 s, bags read)
under --out. Exit status 0 when RSS grows under 1 MB a minute after 5 minutes, every call answers
within 2 s and every bag reads whole, else 1.

``--clock follow`` starts the node with ``clock: follow`` and publishes its /clock from the soak, in
real time at 200 Hz (a robot simulator's bridge), going back to 0 now and then (a simulator's reset)
as one more kind of call. ``--clock lockstep`` starts it with ``clock: lockstep``, and a burst of
1 to 1,500 targets on ~/advance_to, 1 ms apart past the last sent, is one more kind of call; at the
end the node is let run until every target is answered on ~/reached (reached or refused) or 60 s
pass, and the summary counts the targets never answered.

Issue 66's race is one more kind of call in every mode: ~/save_state, ~/reset with the scene
switched to the other of two (SCENE and SCENE_B, whose bodies differ) and ~/record on, sent at
once from three threads. Every bag is then checked to hold one run: the topics of its own scene
only (named by its folder) and one /clock message per time, in order.

    python bench/soak.py [--minutes 30] [--out docs/results/soak] [--seed 1] [--clock follow|lockstep]
"""
import argparse
import csv
import os
import pickle
import random
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

BENCH = Path(__file__).resolve().parent
sys.path.insert(0, str(BENCH.parent / "tests"))
ANSWER = 2.0  # [s] the longest a call may take
WARM_UP = 5.0  # [min] RSS growth is fitted after this
SCENE = """name: soak_bodies
dim: 2
tank: [1.2, 0.6]
fluid:
  - {name: water, lo: [0.1, 0.0], hi: [1.2, 0.3]}
obstacles:
  - {name: paddle, lo: [0.04, 0.0], hi: [0.1, 0.6],
     motion: {type: driven, max_speed: 0.3, max_acceleration: 3.0, timeout: 0.5}}
  - {name: box, lo: [0.6, 0.25], hi: [0.8, 0.35], displaces_fluid: true, floating: {density: 500}}
"""
# the other scene of the race: the same tank with one floating body of another name, so that a bag
# holding the other run's messages shows by its topics
SCENE_B = SCENE.split("obstacles:")[0].replace("soak_bodies", "soak_float") + """obstacles:
  - {name: float, lo: [0.5, 0.25], hi: [0.7, 0.35], displaces_fluid: true, floating: {density: 500}}
"""
FOREIGN = {"soak_bodies": ("/bodies/float/",), "soak_float": ("/bodies/paddle/", "/bodies/box/")}
BURST = 200  # commands published back to back
MAX_TARGETS = 1500  # the largest burst of lockstep targets


class _Payload:
    """A pickle that runs a command when loaded: the node must refuse it and run nothing."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return os.system, (f"touch {self.marker}",)


def _proc(pid: int) -> dict:
    status = Path(f"/proc/{pid}/status").read_text().splitlines()
    fields = dict(line.split(":", 1) for line in status if ":" in line)
    return {"rss_mb": int(fields["VmRSS"].split()[0]) / 1024.0, "threads": int(fields["Threads"]),
            "fds": len(os.listdir(f"/proc/{pid}/fd"))}


def _check_closed_bags(folder: Path, keep_open: bool) -> list:
    """(bag, messages, whole, one run) for each bag under ``folder`` whose file is finished (all of
    them when not ``keep_open``); each is read with rosbags, then deleted. One run: no topic of the
    other scene (FOREIGN, by the folder's scene name) and /clock's stamps strictly increasing."""
    from rosbags.highlevel import AnyReader

    from gpusph_ros.output.recording import bag_files, is_whole

    out = []
    for bag in sorted(p for p in folder.iterdir() if p.is_dir()):
        files = bag_files(bag)
        if not files or (keep_open and not all(is_whole(f) for f in files)):
            continue
        foreign = next((v for k, v in FOREIGN.items() if bag.name.startswith(k + "_")), ())
        one_run = True
        try:
            with AnyReader([bag]) as reader:
                count, clock = 0, []
                for connection, stamp, _ in reader.messages():
                    count += 1
                    one_run &= not any(f in connection.topic for f in foreign)
                    if connection.topic == "/clock":
                        clock.append(stamp)
                whole = count == reader.message_count and all(is_whole(f) for f in files)
                one_run &= all(b > a for a, b in zip(clock, clock[1:]))
        except Exception as err:  # a bag that does not read is the finding
            print(f"  bag {bag.name} does not read: {type(err).__name__}: {err}", flush=True)
            count, whole = 0, False
        if not one_run:
            print(f"  bag {bag.name} holds another run's messages", flush=True)
        out.append((bag.name, count, whole, one_run))
        shutil.rmtree(bag)
    return out


def soak(minutes: float, out: Path, seed: int, period: float, sample: float, clock: str = "publish") -> int:
    from geometry_msgs.msg import PoseStamped, TwistStamped, WrenchStamped
    from lifecycle_msgs.msg import Transition
    from lifecycle_msgs.srv import ChangeState
    from rosgraph_msgs.msg import Clock
    from std_srvs.srv import SetBool, Trigger

    from ros_client import Client, stop

    rng = random.Random(seed)
    work = Path(tempfile.mkdtemp(prefix="soak_"))
    bags, saved = work / "bags", work / "state.npz"
    bags.mkdir()
    fifo, poison, marker = work / "state.fifo", work / "poison.npz", work / "ran"
    os.mkfifo(fifo)
    scene, scene_b = work / "soak_bodies.yaml", work / "soak_float.yaml"
    scene.write_text(SCENE)
    scene_b.write_text(SCENE_B)
    poison.write_bytes(pickle.dumps({"scene": _Payload(marker)}))
    domain = 200 + os.getpid() % 30
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
           "PYTHONUNBUFFERED": "1"}
    log = open(work / "node.log", "w")
    node = subprocess.Popen([sys.executable, "-m", "gpusph_ros.ros.sim_node", "--ros-args", "-p", f"scene:={scene}",
                             "-p", "dx:=0.03", "-p", "end_time:=100000.0", "-p", "real_time_factor:=1.0",
                             "-p", f"record_dir:={bags}", "-p", f"state_file:={saved}", "-p", f"clock:={clock}"],
                            env=env, stdout=log, stderr=subprocess.STDOUT)
    client = Client(domain)
    calls, samples, read = [], [], []
    publishers = {kind: client.node.create_publisher(msg_type, f"/sim_node/bodies/{body}/cmd_{kind}", 10)
                  for kind, body, msg_type in (("pose", "paddle", PoseStamped), ("twist", "paddle", TwistStamped),
                                               ("wrench", "box", WrenchStamped))}

    def command(kind, hostile=None):
        """A body command, good or with one hostile field (a stamp of zero: now)."""
        msg = {"pose": PoseStamped, "twist": TwistStamped, "wrench": WrenchStamped}[kind]()
        value = {"nan": float("nan"), "huge": 1.0e308}.get(hostile, rng.uniform(-0.5, 0.5))
        if kind == "pose":
            msg.pose.position.x, msg.pose.position.z, msg.pose.orientation.w = 0.07 + 0.05 * value, 0.3, 1.0
            if hostile == "turn":
                msg.pose.orientation.w = 2.0
        elif kind == "twist":
            msg.twist.linear.x = value
        else:
            msg.wrench.force.z, msg.wrench.torque.y = 20.0 * value, value
        if hostile == "frame":
            msg.header.frame_id = "base_link"
        if hostile == "future":
            msg.header.stamp.sec = 2_000_000_000
        publishers[kind].publish(msg)

    def commands():
        kind = rng.choice(["pose", "twist", "wrench"])
        for _ in range(BURST if rng.random() < 0.2 else 1):
            command(kind, rng.choice([None, None, "nan", "huge", "frame", "future", "turn"]))

    ticking = {"origin": time.monotonic(), "run": clock == "follow"}
    clock_pub = client.node.create_publisher(Clock, "/clock", 10)

    def tick():
        """The followed clock: real time since its origin, 200 times a second."""
        while ticking["run"]:
            t = time.monotonic() - ticking["origin"]
            msg = Clock()
            msg.clock.sec, msg.clock.nanosec = int(t), int((t - int(t)) * 1e9)
            clock_pub.publish(msg)
            time.sleep(0.005)

    def clock_back():
        ticking["origin"] = time.monotonic()

    lockstep = {"sent": 0, "answered": 0, "refused": 0, "last_ns": 0}
    if clock == "lockstep":
        from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import Header

        qos = QoSProfile(depth=2000, reliability=ReliabilityPolicy.RELIABLE)
        targets = client.node.create_publisher(Header, "/sim_node/advance_to", QoSProfile(
            history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE))  # as docs/node.md asks

        from diagnostic_msgs.msg import DiagnosticArray

        client.subscribe("/diagnostics", DiagnosticArray)

        def reached(msg):
            lockstep["answered"] += 1
            lockstep["refused"] += msg.frame_id == "refused"
        client.node.create_subscription(Header, "/sim_node/reached", reached, qos)

    def burst():
        """1 to MAX_TARGETS lockstep targets, 1 ms apart past the last sent."""
        for _ in range(rng.randint(1, MAX_TARGETS)):
            lockstep["last_ns"] += 1_000_000
            msg = Header()
            msg.stamp.sec, msg.stamp.nanosec = divmod(lockstep["last_ns"], 1_000_000_000)
            targets.publish(msg)
            lockstep["sent"] += 1

    race_calls = []  # (kind, latency) of each call of a race, reported with the others

    def race():
        """~/save_state, ~/reset to the other scene and ~/record on, at once: each answers in time."""
        current = client.get("scene")["scene"]
        other = str(scene_b if current == str(scene) else scene)
        client.set(scene=other)
        failures = []

        def call(name, srv, **fields):
            t0 = time.monotonic()
            try:
                client.call(name, srv, timeout=ANSWER, **fields)
            except TimeoutError as err:
                failures.append(err)
            race_calls.append((f"race: {name}", time.monotonic() - t0))
        threads = [threading.Thread(target=call, args=args, kwargs=kw) for args, kw in (
            (("save_state", Trigger), {}), (("reset", Trigger), {}), (("record", SetBool), {"data": True}))]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        if failures:
            raise failures[0]

    def lifecycle(label):
        ids = {"deactivate": Transition.TRANSITION_DEACTIVATE, "activate": Transition.TRANSITION_ACTIVATE}
        return client.call("change_state", ChangeState, timeout=ANSWER, transition=Transition(id=ids[label]))

    def load(path):
        def call():
            client.set(state_file=str(path))
            reply = client.call("load_state", Trigger, timeout=ANSWER)
            client.set(state_file=str(saved))
            return reply
        return call

    kinds = {
        "get": lambda: client.get("cfl", "scene", "output_rate", "frame_id"),
        "set cfl": lambda: client.set(cfl=rng.choice([0.2, 0.25, 0.3])),
        "set output_rate": lambda: client.set(output_rate=rng.choice([0.0, 20.0, 50.0])),
        "set particle_fields": lambda: client.set(particle_fields=rng.choice([["vx", "density"], ["pressure"]])),
        "set frame_id": lambda: client.set(frame_id=rng.choice(["world", "map"])),
        "set dx (reset)": lambda: client.set(dx=rng.choice([0.02, 0.025])),
        "refused value": lambda: client.set(**rng.choice([{"kernel": "k" * 100_000}, {"frame_id": "../.."},
                                                          {"cfl": 7.0}, {"compression": "gzip"}])),
        "set_paused": lambda: client.call("set_paused", SetBool, timeout=ANSWER, data=rng.random() < 0.5),
        "step": lambda: client.call("step", Trigger, timeout=ANSWER),
        "record": lambda: client.call("record", SetBool, timeout=ANSWER, data=rng.random() < 0.6),
        "reset": lambda: client.call("reset", Trigger, timeout=ANSWER),
        "save_state": lambda: client.call("save_state", Trigger, timeout=ANSWER),
        "load_state": lambda: client.call("load_state", Trigger, timeout=ANSWER),
        "load_state fifo": load(fifo),
        "load_state pickle": load(poison),
        "lifecycle": lambda: lifecycle(rng.choice(["deactivate", "activate"])),
        "body commands": commands,
        "save/reset/record race": race,
    }
    if clock == "lockstep":
        kinds["lockstep burst"] = burst
    if clock == "follow":
        kinds["clock back to 0"] = clock_back
        threading.Thread(target=tick, daemon=True).start()
    try:
        deadline = time.monotonic() + 300
        while node.poll() is None and time.monotonic() < deadline:  # up and stepping
            try:
                if "soak_bodies" in client.call("reset", Trigger, timeout=10.0).message:
                    break
            except TimeoutError:
                pass
        for name, srv in (("set_paused", SetBool), ("step", Trigger), ("record", SetBool), ("reset", Trigger),
                          ("save_state", Trigger), ("load_state", Trigger), ("change_state", ChangeState)):
            client.call(name, srv, timeout=30.0, **({"data": False} if srv is SetBool else {}))
        start = time.monotonic()
        end, next_sample = start + 60.0 * minutes, start
        print(f"soak: sim_node pid {node.pid}, {scene.stem} at 3 cm, {minutes:g} min, a call about every "
              f"{period:g} s, samples every {sample:g} s -> {out}", flush=True)
        while time.monotonic() < end and node.poll() is None:
            now = time.monotonic()
            if now >= next_sample:
                row = {"minute": (now - start) / 60.0, **_proc(node.pid)}
                samples.append(row)
                read += _check_closed_bags(bags, keep_open=True)
                next_sample += sample
                print(f"  {row['minute']:6.2f} min  RSS {row['rss_mb']:7.1f} MB  fds {row['fds']:3d}  threads "
                      f"{row['threads']:3d}  calls {len(calls)}  bags read {len(read)}", flush=True)
            kind = rng.choice(list(kinds))
            t0 = time.monotonic()
            try:
                kinds[kind]()
                answered = True
            except TimeoutError:
                answered = False
            if kind != "save/reset/record race":  # its calls are counted one by one
                calls.append({"minute": (t0 - start) / 60.0, "kind": kind, "latency_s": time.monotonic() - t0,
                              "answered": answered})
            while race_calls:  # the race's own calls, each against the same bound
                name, latency = race_calls.pop()
                calls.append({"minute": (t0 - start) / 60.0, "kind": name, "latency_s": latency,
                              "answered": latency <= ANSWER})
            time.sleep(rng.uniform(0.0, 2.0 * period))
        alive = node.poll() is None
        if alive and clock == "lockstep":
            # every target still waiting lies ahead of the fluid, which each reset sent back to 0 (up
            # to a thousand, the last some 100 s of simulated time ahead): an end time behind the
            # fluid ends the run, and the node answers each waiting target with where it stopped
            lifecycle("activate")  # refused where it is active already
            client.call("set_paused", SetBool, timeout=10.0, data=False)
            client.set(end_time=0.05)  # one output interval at the slowest output_rate the soak sets
            wait = time.monotonic() + 60.0
            while lockstep["answered"] < lockstep["sent"] and time.monotonic() < wait:
                time.sleep(0.5)
            lockstep["diagnostics"] = {kv.key: kv.value for kv in client.wait_for(
                "/diagnostics", lambda m: bool(m), timeout=10.0)[-1].status[0].values}
        if alive:
            client.call("record", SetBool, timeout=10.0, data=False)
    finally:
        ticking["run"] = False
        client.close()
        stop(node)
        log.close()
    read += _check_closed_bags(bags, keep_open=False)
    return _report(out, minutes, samples, calls, read, alive, marker.exists(), work, clock, lockstep)


def _report(out: Path, minutes, samples, calls, read, alive, ran, work, clock, lockstep) -> int:
    out.mkdir(parents=True, exist_ok=True)
    for name, rows in (("soak.csv", samples), ("soak_calls.csv", calls)):
        with open(out / name, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
    late = [s for s in samples if s["minute"] >= WARM_UP]
    slope = float("nan")
    if len(late) >= 2:
        xs, ys = [s["minute"] for s in late], [s["rss_mb"] for s in late]
        mx, my = statistics.fmean(xs), statistics.fmean(ys)
        slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    unanswered = [c for c in calls if not c["answered"]]
    slow = [c for c in calls if c["latency_s"] > ANSWER]
    broken = [b for b in read if not b[2]]
    mixed = [b for b in read if not b[3]]
    lost = lockstep["sent"] - lockstep["answered"]
    lines = [f"# sim_node soak: {minutes:g} minutes", "",
             "`python bench/soak.py --minutes %g --clock %s` (a 2D tank with a driven paddle and a floating box at "
             "3 cm, real_time_factor 1, recording on and off at random; one client, a call about every 0.5 s, body "
             "commands among them, good and hostile, alone or %d at once). The node's log: %s."
             % (minutes, clock, BURST, work / "node.log"),
             "", f"- node alive at the end: {alive}; the pickle's command ran: {ran}",
             f"- calls: {len(calls)}; unanswered within {ANSWER:g} s: {len(unanswered)}; slower than {ANSWER:g} s: "
             f"{len(slow)}",
             f"- RSS: {samples[0]['rss_mb']:.1f} MB at the start, {samples[-1]['rss_mb']:.1f} MB at the end; "
             f"growth after the first {WARM_UP:g} minutes {slope:+.3f} MB/min (least squares over "
             f"{len(late)} samples)",
             f"- open files {min(s['fds'] for s in samples)}-{max(s['fds'] for s in samples)}, threads "
             f"{min(s['threads'] for s in samples)}-{max(s['threads'] for s in samples)}",
             f"- bags read with rosbags: {len(read)}, {sum(b[1] for b in read):,} messages; not whole or not "
             f"readable: {len(broken)}; holding another run's messages (topics of the other scene, or /clock "
             f"stamps not strictly increasing): {len(mixed)}",
             *([f"- lockstep targets sent: {lockstep['sent']:,}; answered {lockstep['answered']:,} (refused "
                f"{lockstep['refused']:,}); never answered: {lost:,}; the node's count at the end: "
                + ", ".join(f"{k} {v}" for k, v in lockstep.get("diagnostics", {}).items() if k.startswith("lockstep"))]
               if clock == "lockstep" else []),
             "", "| call | n | median ms | p99 ms | worst ms |",
             "| --- | --- | --- | --- | --- |"]
    for kind in sorted({c["kind"] for c in calls}):
        ms = sorted(1e3 * c["latency_s"] for c in calls if c["kind"] == kind)
        p99 = ms[min(len(ms) - 1, int(0.99 * len(ms)))]
        lines.append(f"| {kind} | {len(ms)} | {statistics.median(ms):.0f} | {p99:.0f} | {ms[-1]:.0f} |")
    (out / "soak.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    ok = alive and not ran and not unanswered and not slow and not broken and not mixed and not lost and slope < 1.0
    return 0 if ok else 1


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--minutes", type=float, default=30.0)
    parser.add_argument("--out", type=Path, default=Path("runs/soak"))
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--period", type=float, default=0.5, help="mean seconds between two calls")
    parser.add_argument("--sample", type=float, default=10.0, help="seconds between two samples of the node")
    parser.add_argument("--clock", choices=["publish", "follow", "lockstep"], default="publish",
                        help="follow: the node follows a /clock the soak publishes in real time; lockstep: the "
                             "soak sends bursts of targets on ~/advance_to")
    args = parser.parse_args()
    sys.exit(soak(args.minutes, args.out, args.seed, args.period, args.sample, args.clock))


if __name__ == "__main__":
    main()
