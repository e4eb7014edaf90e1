#!/usr/bin/env python3
"""Benchmark (not a test): how long a large service reply takes to reach rclpy on loopback,
from `linkspace serve` (RustDDS) and, as the baseline in the same run, from a tiny rclpy server
sending the very same reply (Fast DDS on both sides).

The payloads are Solve replies of the four-bar at sigma 1e-6, their size steered by max_boxes
(about 160 bytes of CDR per box; the first call calibrates). A reply's delivery time is its
arrival minus the wall-clock stamp of its box set, which the node sets once the run has ended
and the baseline server sets just before it replies: the solve itself is not counted.

Run through `cargo test --release --test integration topics::reply_delivery_benchmark --
--ignored --nocapture` (the venv of scripts/ros_env.sh), or directly:

    bench_replies.py --linkspace target/release/linkspace [--sizes 1,4,16,32] [--tries 10]

Prints a table, then one JSON object on the last line.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def ros_environment(domain):
    env = dict(os.environ)
    env.update({"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp", "ROS_AUTOMATIC_DISCOVERY_RANGE": "SYSTEM_DEFAULT",
                "FASTRTPS_DEFAULT_PROFILES_FILE": f"{ROOT}/scripts/fastdds_loopback.xml", "ROS_DOMAIN_ID": str(domain)})
    env.pop("ROS_LOCALHOST_ONLY", None)
    env.pop("ROS_STATIC_PEERS", None)
    return env


def stamp_seconds(header):
    return header.stamp.sec + 1e-9 * header.stamp.nanosec


def serve(args):
    """The baseline server: answers /baseline/solve with the reply serialized in the file the
    request names (its `mechanism`), stamped now."""
    import rclpy
    from rclpy.serialization import deserialize_message
    from linkspace_msgs.srv import Solve
    rclpy.init()
    node = rclpy.create_node("bench_replies_baseline")
    cache = {}

    def answer(request, _response):
        st = os.stat(request.mechanism)
        key = (request.mechanism, st.st_size, st.st_mtime_ns)
        if key not in cache:
            cache.clear()
            with open(request.mechanism, "rb") as f:
                cache[key] = deserialize_message(f.read(), Solve.Response)
        reply = cache[key]
        now = time.time()
        reply.result.header.stamp.sec = int(now)
        reply.result.header.stamp.nanosec = int((now - int(now)) * 1e9)
        return reply

    node.create_service(Solve, "/baseline/solve", answer)
    print("ready", flush=True)
    rclpy.spin(node)


def summary(xs):
    if not xs:
        return {"n": 0}
    return {"n": len(xs), "min": min(xs), "median": statistics.median(xs), "max": max(xs)}


def bench(args):
    import rclpy
    from rclpy.serialization import serialize_message
    from linkspace_msgs.msg import Settings
    from linkspace_msgs.srv import Solve

    env = ros_environment(args.domain)
    os.environ.update(env)
    node_proc = subprocess.Popen([args.linkspace, "serve", f"{ROOT}/urdf/four_bar.urdf", "--domain", str(args.domain), "--network", "loopback",
                                  "--sigma", "1e-2", "--max-request-boxes", "100000000", "--max-runs", "1", "--max-wait", "600"] + args.node_args,
                                 stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    baseline_proc = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--serve"], stdin=subprocess.DEVNULL,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env, text=True)
    rclpy.init()
    client_node = rclpy.create_node("bench_replies_client")
    clients = {"linkspace": client_node.create_client(Solve, "/linkspace/solve"), "rclpy": client_node.create_client(Solve, "/baseline/solve")}
    tmp = tempfile.NamedTemporaryFile(prefix="bench-replies-", suffix=".cdr", delete=False)
    tmp.close()
    results = []
    try:
        baseline_proc.stdout.readline()
        for name, client in clients.items():
            if not client.wait_for_service(timeout_sec=60):
                raise SystemExit(f"{name}: service not available")
        # Let Fast DDS finish matching before the first request.
        end = time.monotonic() + 1.0
        while time.monotonic() < end:
            rclpy.spin_once(client_node, timeout_sec=0.05)

        def call(name, request, timeout):
            """(delivery seconds or None, round-trip seconds, reply)."""
            t = time.monotonic()
            future = clients[name].call_async(request)
            end = t + timeout
            while not future.done() and time.monotonic() < end:
                rclpy.spin_once(client_node, timeout_sec=0.01)
            if not future.done():
                clients[name].remove_pending_request(future)
                return None, time.monotonic() - t, None
            arrived = time.time()
            reply = future.result()
            return arrived - stamp_seconds(reply.result.header), time.monotonic() - t, reply

        def solve_request(max_boxes):
            settings = Settings(sigma=1e-6, rho=0.95, max_boxes=max_boxes, timeout=0.0)
            return Solve.Request(mechanism="four_bar", settings=settings, wait=600.0)

        solve_rate = [None]  # seconds of solving per max_boxes, from the calibration

        def linkspace_call(max_boxes):
            # The run's own time, generously, and then the reply's.
            timeout = args.timeout + (60.0 if solve_rate[0] is None else 10.0 + 3 * solve_rate[0] * max_boxes)
            # The node refuses while its load-time runs go on (--max-runs 1): ask again.
            for _ in range(600):
                delivery, seconds, reply = call("linkspace", solve_request(max_boxes), timeout)
                if reply is None or reply.ok or not reply.message.startswith("busy"):
                    return delivery, seconds, reply
                time.sleep(0.2)
            raise SystemExit("the node stayed busy")

        # Calibration: bytes per processed box, from a reply that is small enough to be quick.
        # A request sent right at matching may be lost (Fast DDS): ask again.
        for _ in range(3):
            _, seconds, reply = linkspace_call(4000)
            if reply is not None:
                break
        if reply is None or not reply.ok:
            raise SystemExit(f"calibration failed: {reply.message if reply else 'no reply'}")
        solve_rate[0] = seconds / 4000
        per_box = len(serialize_message(reply)) / 4000
        print(f"calibration: {per_box:.1f} bytes of reply per max_boxes", file=sys.stderr)
        print("size MB | sender | delivered | delivery s min | median | max | round trip s median")
        for mb in args.sizes:
            max_boxes = max(1, int(mb * 1e6 / per_box))
            row = {"target_mb": mb, "max_boxes": max_boxes}
            size = None  # of the node's reply, which the baseline then sends too
            for name in ("linkspace", "rclpy"):
                times, trips = [], []
                for attempt in range(args.tries):
                    if name == "linkspace":
                        delivery, seconds, reply = linkspace_call(max_boxes)
                        if reply is not None and size is None:
                            data = serialize_message(reply)
                            size = len(data)
                            with open(tmp.name, "wb") as f:
                                f.write(data)
                    elif size is None:
                        break  # nothing to send: the node's reply never came
                    else:
                        delivery, seconds, reply = call("rclpy", Solve.Request(mechanism=tmp.name), args.timeout)
                    if reply is not None and not reply.ok:
                        raise SystemExit(f"{name}: {reply.message}")
                    if name == "rclpy" and reply is not None and len(serialize_message(reply)) != size:
                        raise SystemExit(f"{name}: a reply of {len(serialize_message(reply))} bytes, not {size}")
                    if delivery is not None:
                        times.append(delivery)
                        trips.append(seconds)
                    print(f"  {mb} MB {name} try {attempt + 1}: " + (f"{delivery:.2f} s" if delivery is not None else f"no reply within {args.timeout} s"), file=sys.stderr, flush=True)
                s = summary(times)
                row[name] = {"bytes": size, "delivered": len(times), "tries": args.tries, "delivery_s": s,
                             "round_trip_s_median": statistics.median(trips) if trips else None}
                mb_text = f"{size / 1e6:.1f}" if size else f"~{mb}"
                if times:
                    print(f"{mb_text} | {name} | {len(times)}/{args.tries} | {s['min']:.2f} | {s['median']:.2f} | {s['max']:.2f} | {statistics.median(trips):.2f}", flush=True)
                else:
                    print(f"{mb_text} | {name} | 0/{args.tries} | - | - | - | -", flush=True)
            results.append(row)
    finally:
        for p in (node_proc, baseline_proc):
            p.kill()
            p.wait()
        os.unlink(tmp.name)
    print(json.dumps({"results": results}))
    client_node.destroy_node()
    rclpy.shutdown()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--serve", action="store_true", help="run the baseline rclpy server (used by the benchmark itself)")
    ap.add_argument("--linkspace", help="the linkspace binary to benchmark")
    ap.add_argument("--sizes", default="1,4,16,32", help="reply sizes in MB, comma separated")
    ap.add_argument("--tries", type=int, default=10)
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds a reply may take before the try counts as undelivered")
    ap.add_argument("--domain", type=int, default=91)
    ap.add_argument("--node-arg", dest="node_args", action="append", default=[], help="one more argument of `linkspace serve`")
    args = ap.parse_args()
    if args.serve:
        serve(args)
        return
    if not args.linkspace:
        ap.error("--linkspace is required")
    args.sizes = [float(x) for x in args.sizes.split(",")]
    bench(args)


if __name__ == "__main__":
    main()
