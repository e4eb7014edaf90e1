#!/usr/bin/env python3
"""Subscribe to a linkspace box set (linkspace_msgs/BoxSet) and plot it with matplotlib.

Run it with the Python that has rclpy and linkspace_msgs (scripts/ros_env.sh makes one, or a
sourced Jazzy workspace where linkspace_msgs is built):

    python3 scripts/plot_boxes.py --mechanism four_bar                      # a window
    python3 scripts/plot_boxes.py --mechanism four_bar --png cspace.png     # a file
    python3 scripts/plot_boxes.py --topic /linkspace/four_bar/solve_result --x rocker_joint --y coupler_joint

Each box is drawn as a rectangle over two coordinates (joint values by default, or system
variables with --space variables), coloured by its connected component; undecided boxes are
grey. The topic is latched (transient local), so the latest result arrives even when the node
published it long ago. --json FILE also writes the message as JSON (the tests read it).
"""
import argparse
import json
import math
import sys
import time


def to_plain(msg):
    """A ROS message as plain Python data (non-finite floats as strings, for strict JSON)."""
    if hasattr(msg, "get_fields_and_field_types"):
        return {f: to_plain(getattr(msg, f)) for f in msg.get_fields_and_field_types()}
    if isinstance(msg, (list, tuple)) or type(msg).__name__ in ("array", "ndarray"):
        return [to_plain(x) for x in msg]
    if isinstance(msg, float) and not math.isfinite(msg):
        return str(msg)
    if isinstance(msg, bytes):
        return list(msg)
    return msg


def latched_qos(depth=1):
    from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy, HistoryPolicy
    return QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL, history=HistoryPolicy.KEEP_LAST)


def receive(topic, timeout):
    """The first BoxSet on `topic`, or None after `timeout` seconds."""
    import rclpy
    from linkspace_msgs.msg import BoxSet
    rclpy.init()
    node = rclpy.create_node("linkspace_plot_boxes")
    got = []
    node.create_subscription(BoxSet, topic, got.append, latched_qos())
    end = time.monotonic() + timeout
    while not got and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.1)
    node.destroy_node()
    rclpy.shutdown()
    return got[0] if got else None


def columns(msg, space):
    """(names, lower rows, upper rows) of the chosen coordinates."""
    if space == "joints":
        names, lo, hi = list(msg.joint_names), msg.joint_lower, msg.joint_upper
    else:
        names, lo, hi = list(msg.variable_names), msg.lower, msg.upper
    d = len(names)
    n = len(msg.box_status)
    rows = lambda flat: [list(flat[i * d:(i + 1) * d]) for i in range(n)]
    return names, rows(lo), rows(hi)


def plot(msg, x, y, space, png):
    import matplotlib
    if png:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle
    names, lo, hi = columns(msg, space)
    x = x or names[0]
    y = y or (names[1] if len(names) > 1 else names[0])
    for axis in (x, y):
        if axis not in names:
            sys.exit(f"plot_boxes: no coordinate '{axis}' (have: {', '.join(names)})")
    i, j = names.index(x), names.index(y)
    fig, ax = plt.subplots(figsize=(6, 6))
    palette = plt.get_cmap("tab10")
    for k in range(len(lo)):
        c = msg.cluster[k]
        colour = palette(c % 10) if c >= 0 else (0.5, 0.5, 0.5, 0.4)
        w = max(hi[k][i] - lo[k][i], 1e-9)
        h = max(hi[k][j] - lo[k][j], 1e-9)
        ax.add_patch(Rectangle((lo[k][i], lo[k][j]), w, h, facecolor=colour, edgecolor=colour, linewidth=0.5))
        if w < 1e-3 and h < 1e-3:
            # Boxes far smaller than the axes would vanish: mark them.
            ax.plot([lo[k][i] + w / 2], [lo[k][j] + h / 2], "o", color=colour, markersize=4)
    if lo:
        xs = [r[i] for r in lo] + [r[i] for r in hi]
        ys = [r[j] for r in lo] + [r[j] for r in hi]
        pad = lambda v: 0.05 * (max(v) - min(v)) + 1e-3
        ax.set_xlim(min(xs) - pad(xs), max(xs) + pad(xs))
        ax.set_ylim(min(ys) - pad(ys), max(ys) + pad(ys))
    status = "complete" if msg.status == 0 else f"incomplete ({msg.limit})"
    ax.set_title(f"{msg.mechanism} {msg.analysis}: {len(lo)} boxes, {msg.clusters} components, {status}")
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    if png:
        fig.savefig(png, dpi=100)
    else:
        plt.show()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mechanism", help="robot name: plots <node>/<mechanism>/configuration_space")
    ap.add_argument("--node", default="/linkspace", help="the node's fully qualified name (default /linkspace)")
    ap.add_argument("--topic", help="a BoxSet topic (instead of --mechanism)")
    ap.add_argument("--x", help="coordinate on the x axis (default: the first)")
    ap.add_argument("--y", help="coordinate on the y axis (default: the second)")
    ap.add_argument("--space", choices=["joints", "variables"], default="joints")
    ap.add_argument("--png", help="write the plot here instead of opening a window")
    ap.add_argument("--json", help="also write the received message here as JSON")
    ap.add_argument("--timeout", type=float, default=15.0, help="seconds to wait for the box set")
    args = ap.parse_args()
    if not (args.topic or args.mechanism):
        ap.error("give --mechanism or --topic")
    topic = args.topic or f"{args.node.rstrip('/')}/{args.mechanism}/configuration_space"
    msg = receive(topic, args.timeout)
    if msg is None:
        sys.exit(f"plot_boxes: nothing on {topic} within {args.timeout} s")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(to_plain(msg), f)
    plot(msg, args.x, args.y, args.space, args.png)
    print(f"plot_boxes: {topic}: {len(msg.box_status)} boxes, {msg.clusters} components")


if __name__ == "__main__":
    main()
