"""What sim_node costs: the particle cloud per output, and how fast it answers while it steps.

1. Cloud cost per output (``cloud``): DamBreak 1 filled at the spacing that gives about 10^4,
   10^5 and 10^6 particles; per output the median of --repeat of each stage the node runs:
   packing the rows on the device (pressure by the equation of state, x, y, z + 5 fields as
   float32, in scene order) into the reusable host buffer, the PointCloud2 around one copy of
   its bytes, CDR serialisation (once, shared by publisher and bag), rmw publish with no
   subscriber, and the MCAP write of those bytes to a bag on disk (the operating system's page cache, not a sync).
2. Responsiveness (``response``): sim_node started in its own process, stepping DamBreak 1 at
   dx = 0.028 m (19,700 particles) flat out on this device; a client times --samples round trips
   of a parameter get, a parameter set (cfl, a live change), and a service call (~/record false)
   spread over the run.

    python bench/node.py [cloud] [response] [--device cpu] [--repeat 5] [--samples 20]
"""
import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import warp as wp

from series import model_of_about

BENCH = Path(__file__).resolve().parent
SCENE = "dambreak1_thesis"
TARGETS = (1e4, 1e5, 1e6)


def _median_ms(fn, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times) * 1e3, out


def cloud(device: str, repeat: int, targets=TARGETS):
    import rclpy
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import PointCloud2

    from gpusph_ros.measure.cloud import CloudPacker
    from gpusph_ros.output.messages import CloudBuilder
    from gpusph_ros.output.recording import BagRecorder

    rclpy.init()
    node = rclpy.create_node("bench_cloud")
    pub = node.create_publisher(PointCloud2, "bench/particles", 1)
    print(f"cloud cost per output on {device}, float32 rows x y z vx vy vz density pressure (32 B/particle)")
    print(f"{'particles':>10} {'pack':>7} {'message':>8} {'serialise':>9} {'publish':>8} {'record':>7} "
          f"{'total':>8}  ms   {'MB':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        for target in targets:
            model = model_of_about(SCENE, target, device=device)
            solver = model.solver()
            packer = CloudPacker(solver)
            builder = CloudBuilder(packer.fields)
            recorder = BagRecorder(Path(tmp) / f"bag_{int(target)}", {"bench": "cloud"})
            packer.pack()  # compile and warm up
            t_pack, rows = _median_ms(packer.pack, repeat)
            t_msg, msg = _median_ms(lambda: builder.build(0.0, rows), repeat)
            t_ser, data = _median_ms(lambda: serialize_message(msg), repeat)
            t_pub, _ = _median_ms(lambda: pub.publish(data), repeat)
            t_rec, _ = _median_ms(lambda: recorder.write("/sim_node/particles", msg, 0.0, data), repeat)
            recorder.close()
            total = t_pack + t_msg + t_ser + t_pub + t_rec
            print(f"{solver.n:>10,} {t_pack:>7.2f} {t_msg:>8.2f} {t_ser:>9.2f} {t_pub:>8.2f} {t_rec:>7.2f} "
                  f"{total:>8.2f}      {len(data) / 1e6:>6.1f}", flush=True)
            del solver, model
    node.destroy_node()
    rclpy.shutdown()


def response(device: str, samples: int):
    sys.path.insert(0, str(BENCH.parent / "tests"))
    from std_srvs.srv import SetBool

    from ros_client import Client

    domain = 150 + os.getpid() % 50
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    node = subprocess.Popen([sys.executable, "-m", "gpusph_ros.ros.sim_node", "--ros-args", "-p", f"scene:={SCENE}",
                             "-p", "dx:=0.028", "-p", f"device:={device}", "-p", "end_time:=100.0"], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    client = Client(domain)
    try:
        from diagnostic_msgs.msg import DiagnosticArray

        client.subscribe("/diagnostics", DiagnosticArray)

        def stat(key):
            msgs = client.wait_for("/diagnostics", lambda ms: ms and ms[-1].status[0].message == "running", 300.0)
            return {kv.key: kv.value for kv in msgs[-1].status[0].values}[key]

        particles = stat("particles")
        time.sleep(3.0)  # stepping at full speed
        kinds = {"parameter get": lambda: client.get("cfl"),
                 "parameter set (cfl)": lambda: client.set(cfl=0.3),
                 "service ~/record false": lambda: client.call("record", SetBool, data=False)}
        for fn in kinds.values():
            fn()  # first calls create clients and wait for discovery: not counted
        results = {name: [] for name in kinds}
        for _ in range(samples):
            for name, fn in kinds.items():
                start = time.perf_counter()
                fn()
                results[name].append((time.perf_counter() - start) * 1e3)
            time.sleep(0.2)
        print(f"responsiveness while stepping {SCENE}, {particles} particles, {stat('steps_per_s')} steps/s "
              f"({stat('mipps')} MIPPS) on {device}, {samples} samples each")
        for name, ms in results.items():
            print(f"  {name:<24} median {statistics.median(ms):7.1f} ms   max {max(ms):7.1f} ms")
    finally:
        client.close()
        node.send_signal(signal.SIGINT)
        node.wait(timeout=60)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("parts", nargs="*", default=["cloud", "response"], choices=["cloud", "response"])
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--samples", type=int, default=20)
    parser.add_argument("--particles", type=float, nargs="+", default=TARGETS,
                        help="about how many particles each cloud case has")
    args = parser.parse_args()
    wp.config.log_level = wp.LOG_WARNING
    if "cloud" in args.parts:
        cloud(args.device, args.repeat, args.particles)
    if "response" in args.parts:
        response(args.device, args.samples)


if __name__ == "__main__":
    main()
