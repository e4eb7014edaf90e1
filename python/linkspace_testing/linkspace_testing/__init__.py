"""Topic-based regression tests against the linkspace ROS 2 node.

Start `linkspace serve` on a URDF, wait for a `linkspace_msgs/BoxSet` on a latched topic, and
compare it with a stored golden set by containment: every certified root of the golden set
(the centre of a box proven to hold exactly one solution, `Box.UNIQUE`; of every solution box
when the set has no certified one, e.g. a curve) lies in a box of the new set, within a
tolerance, and vice versa. Box sets are compared as plain dicts (`box_set_to_plain`), so a
golden set is a JSON file (`save_golden`, `load_golden`).

The pytest fixtures are in `linkspace_testing.plugin` (registered as a pytest plugin when the
package is installed): `linkspace_node` starts nodes and stops them after the test.
"""
import json
import math
import os
import shutil
import subprocess
import threading
import time

BOX_SOLUTION, BOX_UNDECIDED, BOX_UNIQUE = 0, 1, 2

__all__ = ["LinkspaceNode", "box_set_to_plain", "roots", "compare_by_containment", "assert_matches_golden",
           "load_golden", "save_golden", "wait_for_box_set"]


def box_set_to_plain(msg):
    """The fields of a BoxSet message needed for comparisons, as plain Python data."""
    return {
        "mechanism": msg.mechanism,
        "analysis": msg.analysis,
        "status": int(msg.status),
        "limit": msg.limit,
        "dim": int(msg.dim),
        "variable_names": list(msg.variable_names),
        "lower": [float(x) for x in msg.lower],
        "upper": [float(x) for x in msg.upper],
        "box_status": [int(x) for x in msg.box_status],
        "sigma": float(msg.settings.sigma),
    }


def save_golden(box_set, path):
    with open(path, "w") as f:
        json.dump(box_set, f, indent=1)


def load_golden(path):
    with open(path) as f:
        return json.load(f)


def _boxes(s):
    d = s["dim"]
    return [(s["lower"][k * d:(k + 1) * d], s["upper"][k * d:(k + 1) * d]) for k in range(len(s["box_status"]))]


def roots(s):
    """(points, kind): the centres of the certified boxes, or of every solution box if none is."""
    boxes = _boxes(s)
    unique = [b for b, st in zip(boxes, s["box_status"]) if st == BOX_UNIQUE]
    chosen, kind = (unique, "certified") if unique else (
        [b for b, st in zip(boxes, s["box_status"]) if st in (BOX_SOLUTION, BOX_UNIQUE)], "solution")
    return [[0.5 * (lo + hi) for lo, hi in zip(l, u)] for l, u in chosen], kind


def _covered(point, boxes, tol):
    return any(all(lo - tol <= x <= hi + tol for x, lo, hi in zip(point, l, u)) for l, u in boxes)


def compare_by_containment(new, golden, tol=1e-9):
    """What differs between two box sets, as a list of lines (empty when they agree): variable
    names, the golden roots not in a box of the new set, and the new roots not in a box of the
    golden set, each box widened by `tol`."""
    problems = []
    if new["variable_names"] != golden["variable_names"]:
        return [f"variables differ: {new['variable_names']} against golden {golden['variable_names']}"]
    for a, b, name in ((golden, new, "golden"), (new, golden, "new")):
        points, kind = roots(a)
        boxes = _boxes(b)
        missing = [p for p in points if not _covered(p, boxes, tol)]
        if missing:
            other = "new" if name == "golden" else "golden"
            problems.append(f"{len(missing)} of {len(points)} {kind} roots of the {name} set lie in no box of the {other} set "
                            f"(tolerance {tol}); first: {dict(zip(a['variable_names'], missing[0]))}")
    return problems


def assert_matches_golden(new, golden, tol=1e-9):
    problems = compare_by_containment(new, golden, tol)
    assert not problems, "box set differs from the golden set:\n" + "\n".join(problems)


def wait_for_box_set(topic, timeout=60.0, node_name="linkspace_testing"):
    """The latest BoxSet on a latched `topic` (Reliable, TransientLocal), as plain data; waits up
    to `timeout` seconds for the first and a short settle for a newer one. Needs rclpy."""
    import rclpy
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    from linkspace_msgs.msg import BoxSet
    own = not rclpy.ok()
    if own:
        rclpy.init()
    try:
        node = rclpy.create_node(node_name)
        got = []
        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                         history=HistoryPolicy.KEEP_LAST)
        node.create_subscription(BoxSet, topic, got.append, qos)
        end = time.monotonic() + timeout
        while not got and time.monotonic() < end:
            rclpy.spin_once(node, timeout_sec=0.05)
        settle = time.monotonic() + 0.3
        while got and time.monotonic() < settle:
            rclpy.spin_once(node, timeout_sec=0.05)
        node.destroy_node()
        if not got:
            raise TimeoutError(f"no BoxSet on {topic} within {timeout} s")
        return box_set_to_plain(got[-1])
    finally:
        if own:
            rclpy.try_shutdown()


class LinkspaceNode:
    """`linkspace serve` as a subprocess on loopback. `binary`: the `linkspace` executable
    (default: $LINKSPACE_BIN, else `linkspace` on PATH)."""

    def __init__(self, urdfs, args=(), domain=None, binary=None, namespace="/linkspace"):
        self.binary = binary or os.environ.get("LINKSPACE_BIN") or shutil.which("linkspace")
        if not self.binary:
            raise FileNotFoundError("no linkspace binary: set LINKSPACE_BIN or put linkspace on PATH")
        self.domain = int(domain if domain is not None else os.environ.get("ROS_DOMAIN_ID", "0"))
        self.namespace = namespace.rstrip("/")
        cmd = [self.binary, "serve", "--domain", str(self.domain), "--network", "loopback", *map(str, urdfs), *map(str, args)]
        self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        self.log = []
        threading.Thread(target=self._drain, daemon=True).start()

    def _drain(self):
        for line in self.proc.stderr:
            self.log.append(line.rstrip("\n"))

    def wait_for_log(self, needle, timeout=60.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if any(needle in l for l in self.log):
                return
            if self.proc.poll() is not None:
                raise RuntimeError("linkspace serve exited:\n" + "\n".join(self.log))
            time.sleep(0.05)
        raise TimeoutError(f"linkspace serve did not log {needle!r} within {timeout} s:\n" + "\n".join(self.log))

    def box_set(self, mechanism, topic="configuration_space", timeout=60.0):
        """The mechanism's latest box set (after its load-time analysis is published)."""
        if topic == "configuration_space":
            self.wait_for_log(f"{mechanism}: published configuration_space", timeout)
        return wait_for_box_set(f"{self.namespace}/{mechanism}/{topic}", timeout)

    def stop(self):
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
