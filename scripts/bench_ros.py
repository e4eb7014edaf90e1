#!/usr/bin/env python3
"""Measures a running `linkspace serve` from rclpy: box-set topic throughput and latency, and
service round trips. Used by `cargo bench --bench ros` (benches/ros.rs), which starts the node
with --republish; prints one JSON object.

    bench_ros.py --topic /linkspace/four_bar/configuration_space --seconds 8 --calls 200
"""
import argparse
import json
import statistics
import time

import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy, HistoryPolicy
from linkspace_msgs.msg import BoxSet
from linkspace_msgs.srv import ListMechanisms, Classify


def percentile(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * len(xs)))] if xs else float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--topic", required=True)
    ap.add_argument("--seconds", type=float, default=8.0)
    ap.add_argument("--calls", type=int, default=200)
    ap.add_argument("--node", default="/linkspace")
    ap.add_argument("--mechanism", required=True)
    ap.add_argument("--joints", default="{}", help="JSON: a configuration to classify")
    args = ap.parse_args()
    rclpy.init()
    node = rclpy.create_node("linkspace_bench")
    arrivals = []
    def on_set(msg):
        now = time.time()
        sent = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        arrivals.append((time.monotonic(), now - sent, len(msg.box_status), len(msg.lower)))
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL, history=HistoryPolicy.KEEP_LAST)
    node.create_subscription(BoxSet, args.topic, on_set, qos)
    end = time.monotonic() + 20
    while not arrivals and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    # Measure a window that starts after the first (latched) sample.
    arrivals.clear()
    t0 = time.monotonic()
    while time.monotonic() - t0 < args.seconds:
        rclpy.spin_once(node, timeout_sec=0.05)
    span = time.monotonic() - t0
    n = len(arrivals)
    boxes = arrivals[-1][2] if arrivals else 0
    # CDR payload: two float64 per box and variable, two per box and joint, plus small columns.
    mb = sum(16 * a[3] for a in arrivals) / 1e6
    lat = [1000 * a[1] for a in arrivals]
    out = {"topic": args.topic, "boxes": boxes, "received": n, "rate": n / span, "mb_per_s": mb / span,
           "latency_ms_median": statistics.median(lat) if lat else float("nan"), "latency_ms_p90": percentile(lat, 0.9)}

    def round_trips(client, make):
        client.wait_for_service(timeout_sec=10)
        warm = time.monotonic() + 0.5
        while time.monotonic() < warm:
            rclpy.spin_once(node, timeout_sec=0.05)
        times = []
        for _ in range(args.calls):
            t = time.monotonic()
            f = client.call_async(make())
            rclpy.spin_until_future_complete(node, f, timeout_sec=10)
            if f.done():
                times.append(1000 * (time.monotonic() - t))
        return {"calls": len(times), "median_ms": statistics.median(times) if times else float("nan"), "p90_ms": percentile(times, 0.9)}

    base = args.node.rstrip("/")
    out["list_mechanisms"] = round_trips(node.create_client(ListMechanisms, f"{base}/list_mechanisms"), ListMechanisms.Request)
    joints = json.loads(args.joints)
    if joints:
        out["classify"] = round_trips(node.create_client(Classify, f"{base}/classify"),
                                      lambda: Classify.Request(mechanism=args.mechanism, joint_names=list(joints), joint_values=[float(v) for v in joints.values()]))
    print(json.dumps(out))
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
