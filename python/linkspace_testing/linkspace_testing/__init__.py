"""Topic-based regression tests against the linkspace ROS 2 node.

Start `linkspace serve` on a URDF, wait for a `linkspace_msgs/BoxSet` on a latched topic, and
compare it with a stored golden set, each side against the other (`compare_by_containment`):
certified roots (the centres of boxes proven to hold exactly one solution, `Box.UNIQUE`) by
containment, every one in a box of the other set within a tolerance; the solution boxes of a
positive-dimensional set (a curve, which has no certified box) by enclosure, every one meeting
the other set's boxes once those are widened by the other set's sigma plus the tolerance, so
that runs at different resolutions of the same curve agree. Box sets are compared as plain
dicts (`box_set_to_plain`), so a golden set is a JSON file (`save_golden`, `load_golden`).

The pytest fixtures are in `linkspace_testing.plugin` (registered as a pytest plugin when the
package is installed): `linkspace_node` starts nodes and stops them after the test.
"""
import bisect
import json
import os
import shutil
import subprocess
import threading
import time

BOX_SOLUTION, BOX_UNDECIDED, BOX_UNIQUE = 0, 1, 2

__all__ = ["LinkspaceNode", "box_set_to_plain", "kind", "roots", "compare_by_containment", "assert_matches_golden",
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


def _boxes(s, statuses=None):
    d = s["dim"]
    return [(s["lower"][k * d:(k + 1) * d], s["upper"][k * d:(k + 1) * d])
            for k, st in enumerate(s["box_status"]) if statuses is None or st in statuses]


def _sigma(s):
    """The resolution of a set: its `sigma` (the run's settings), else its widest box."""
    if s.get("sigma"):
        return float(s["sigma"])
    return max((h - l for lo, up in _boxes(s) for l, h in zip(lo, up)), default=0.0)


def kind(s):
    """"certified" when the set has boxes proven to hold exactly one solution (`Box.UNIQUE`),
    else "solution" (a positive-dimensional set, e.g. a curve, covered by solution boxes)."""
    return "certified" if BOX_UNIQUE in s["box_status"] else "solution"


def roots(s):
    """(points, kind): the centres of the certified boxes, or of every solution box if none is."""
    chosen = _boxes(s, (BOX_UNIQUE,) if kind(s) == "certified" else (BOX_SOLUTION, BOX_UNIQUE))
    return [[0.5 * (lo + hi) for lo, hi in zip(l, u)] for l, u in chosen], kind(s)


class _Index:
    """Boxes sorted by their lower bound in the first variable, for the ones near a query."""

    def __init__(self, boxes):
        self.boxes = sorted(boxes, key=lambda b: b[0][0])
        self.keys = [b[0][0] for b in self.boxes]
        self.width = max((b[1][0] - b[0][0] for b in self.boxes), default=0.0)

    def meets(self, lower, upper, r):
        """Whether the box [lower, upper] meets one of the boxes widened by r on every side."""
        first = bisect.bisect_left(self.keys, lower[0] - r - self.width)
        last = bisect.bisect_right(self.keys, upper[0] + r)
        return any(all(l - r <= hi and lo <= h + r for lo, hi, l, h in zip(lower, upper, bl, bu))
                   for bl, bu in self.boxes[first:last])


def _first(s, lower, upper):
    return {n: [lo, hi] for n, lo, hi in zip(s["variable_names"], lower, upper)}


def compare_by_containment(new, golden, tol=1e-9):
    """What differs between two box sets, as a list of lines (empty when they agree).

    Each side is checked against the other, by its kind (`kind`):
    - certified roots (centres of `Box.UNIQUE` boxes) must lie in a box of the other set
      widened by `tol` (containment);
    - solution boxes of a positive-dimensional set (a curve: no certified box) must each meet
      the union of the other set's boxes widened by the other set's sigma plus `tol`
      (enclosure): both sets enclose the same solutions at their own resolutions, so a box of
      one lies within the other's resolution of the other's cover, whatever the two sigmas.
    Variable names must agree."""
    if new["variable_names"] != golden["variable_names"]:
        return [f"variables differ: {new['variable_names']} against golden {golden['variable_names']}"]
    problems = []
    for a, b, name, other in ((golden, new, "golden", "new"), (new, golden, "new", "golden")):
        index = _Index(_boxes(b))
        if kind(a) == "certified":
            points, _ = roots(a)
            missing = [p for p in points if not index.meets(p, p, tol)]
            if missing:
                problems.append(f"{len(missing)} of {len(points)} certified roots of the {name} set lie in no box of the {other} set "
                                f"(tolerance {tol}); first: {dict(zip(a['variable_names'], missing[0]))}")
        else:
            r = _sigma(b) + tol
            boxes = _boxes(a, (BOX_SOLUTION,))
            missing = [(l, u) for l, u in boxes if not index.meets(l, u, r)]
            if missing:
                problems.append(f"{len(missing)} of {len(boxes)} solution boxes of the {name} set meet no box of the {other} set "
                                f"widened by {r:g} (its sigma {_sigma(b):g} plus tolerance {tol:g}); first: {_first(a, *missing[0])}")
    return problems


def assert_matches_golden(new, golden, tol=1e-9):
    problems = compare_by_containment(new, golden, tol)
    assert not problems, "box set differs from the golden set:\n" + "\n".join(problems)


def wait_for_box_set(topic, timeout=60.0, node_name="linkspace_testing", check=None):
    """The latest BoxSet on a latched `topic` (Reliable, TransientLocal), as plain data; waits up
    to `timeout` seconds for the first and a short settle for a newer one. `check`, if given,
    is called while waiting and may raise (e.g. when the publisher has exited). Needs rclpy."""
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
            if check is not None:
                check()
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

    def _check_running(self):
        if self.proc.poll() is not None:
            raise RuntimeError("linkspace serve exited:\n" + "\n".join(self.log))

    def wait_for_log(self, needle, timeout=60.0):
        """Waits for a line of the node's log (lines below `--log-level` never come)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if any(needle in l for l in self.log):
                return
            self._check_running()
            time.sleep(0.05)
        raise TimeoutError(f"linkspace serve did not log {needle!r} within {timeout} s:\n" + "\n".join(self.log))

    def box_set(self, mechanism, topic="configuration_space", timeout=60.0):
        """The mechanism's latest box set on `~/<mechanism>/<topic>`, waited for on the topic
        alone (latched: the node publishes a box set there when its run ends), whatever the
        node's log level."""
        try:
            return wait_for_box_set(f"{self.namespace}/{mechanism}/{topic}", timeout, check=self._check_running)
        except TimeoutError as e:
            raise TimeoutError(f"{e}; node log:\n" + "\n".join(self.log)) from None

    def stop(self):
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
