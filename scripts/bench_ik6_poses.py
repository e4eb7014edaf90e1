#!/usr/bin/env python3
"""What a planner pays per certified 6R IK answer: `ik6 --poses FILE` (one process, every pose)
against one `ik6 --pose` process per pose, in the same invocation on the same poses.

For each arm: random joint vectors q in the joint box, their tip pose by forward kinematics
written here from the URDF's origins and axes (independent of linkspace), then
- batch: `ik6 ARM --poses FILE --json OUT` once, wall time over all poses;
- single: `ik6 ARM --pose P --json OUT` per pose for the first `--singles` poses, wall time each.
Both take every angle as written (`--exact-geometry`), as the forward kinematics here does: the
default rounding solves the arm with its truncated quarter turns snapped, whose solutions near a
singular configuration lie 1e-7 rad from those of the arm as written. Checks that each single
answer's unique boxes are the batch answer's for that pose, and that q lies in one of them. Prints per arm the solver's own time per pose (median and mean of the
reports' `seconds`) and the time outside it per pose (start, reading the URDF, building the chain,
writing): the batch's wall time less the solver's, over the poses, and the median for one
process per pose, and how many poses each method answered (`closed` the closed form of a
recognised geometry, such as the spherical wrists of the PUMA and KR16 or the UR5's parallel
axes 2, 3, 4, `search` the search).

    python3 scripts/bench_ik6_poses.py --linkspace target/release/linkspace --poses 200 --singles 20
"""
import argparse
import json
import math
import os
import random
import statistics
import subprocess
import tempfile
import time
import xml.etree.ElementTree as ET

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ARMS = {
    "ur5": ("urdf/ur5.urdf", "tool0"),
    "crx": ("tests/data/fanuc_crx10ial_style.urdf", "tool0"),
    "puma560": ("urdf/puma560.urdf", "tool0"),
    "kuka_kr16": ("urdf/kuka_kr16.urdf", "tool0"),
}


def rpy_matrix(r, p, y):
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], [-sp, cp * sr, cp * cr]])


def axis_angle(axis, t):
    a = axis / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(t) * k + (1 - math.cos(t)) * k @ k


def chain_to(path, tip):
    """The joints from the root to `tip` (default: the child of the sixth revolute joint on the
    first path that has six)."""
    robot = ET.parse(path).getroot()
    joints = robot.findall("joint")
    by_child = {j.find("child").get("link"): j for j in joints}
    if tip is None:
        for j in joints:
            link, n = j.find("child").get("link"), 0
            walk = link
            while walk in by_child:
                n += by_child[walk].get("type") in ("revolute", "continuous")
                walk = by_child[walk].find("parent").get("link")
            if n == 6:
                tip = link
                break
    chain, link = [], tip
    while link in by_child:
        chain.append(by_child[link])
        link = by_child[link].find("parent").get("link")
    return list(reversed(chain))


def forward(chain, q):
    T, k = np.eye(4), 0
    for j in chain:
        o = j.find("origin")
        xyz = [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
        rpy = [float(v) for v in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
        step = np.eye(4)
        step[:3, :3], step[:3, 3] = rpy_matrix(*rpy), xyz
        if j.get("type") in ("revolute", "continuous"):
            a = j.find("axis")
            turn = np.eye(4)
            turn[:3, :3] = axis_angle(np.array([float(v) for v in (a.get("xyz") if a is not None else "1 0 0").split()]), q[k])
            step, k = step @ turn, k + 1
        T = T @ step
    return T


def limits(chain):
    out = []
    for j in chain:
        if j.get("type") == "revolute":
            lim = j.find("limit")
            out.append((max(float(lim.get("lower")), -math.pi), min(float(lim.get("upper")), math.pi)))
        elif j.get("type") == "continuous":
            out.append((-math.pi, math.pi))
    return out


def unique_boxes(report):
    return sorted(tuple(tuple(b[j]) for j in report["joints"]) for b in report["unique"])


def holds(report, q, slack=1e-7):
    """Whether `q` lies in one of the report's unique boxes."""
    return any(all(b[n][0] - slack <= q[i] <= b[n][1] + slack for i, n in enumerate(report["joints"])) for b in report["unique"])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--linkspace", default=os.path.join(ROOT, "target/release/linkspace"))
    ap.add_argument("--poses", type=int, default=200)
    ap.add_argument("--singles", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--arms", default=",".join(ARMS))
    args = ap.parse_args()
    rng = random.Random(args.seed)
    print(f"{'arm':10} {'poses':>5} {'solver us/pose':>15} {'mean':>8} {'max':>8} {'outside the solver, ms/pose: batch':>36} {'single':>8}  methods")
    for name in args.arms.split(","):
        rel, tip = ARMS[name]
        path = os.path.join(ROOT, rel)
        chain = chain_to(path, tip)
        box = limits(chain)
        qs = [[rng.uniform(lo, hi) for lo, hi in box] for _ in range(args.poses)]
        poses = [",".join(repr(float(x)) for x in forward(chain, q).reshape(-1)) for q in qs]
        with tempfile.TemporaryDirectory() as tmp:
            file, out = os.path.join(tmp, "poses.txt"), os.path.join(tmp, "answers.jsonl")
            open(file, "w").write("\n".join(poses) + "\n")
            t = time.perf_counter()
            subprocess.run([args.linkspace, "ik6", path, "--exact-geometry", "--poses", file, "--json", out], check=True, capture_output=True)
            wall = time.perf_counter() - t
            answers = [json.loads(line) for line in open(out)]
            assert len(answers) == len(poses), f"{name}: {len(answers)} answers for {len(poses)} poses"
            batch = (wall - sum(a["seconds"] for a in answers)) / len(poses)
            singles = []
            for k in range(min(args.singles, len(poses))):
                one = os.path.join(tmp, f"one-{k}.json")
                t = time.perf_counter()
                subprocess.run([args.linkspace, "ik6", path, "--exact-geometry", "--pose", poses[k], "--json", one], check=True, capture_output=True)
                alone = json.load(open(one))
                singles.append(time.perf_counter() - t - alone["seconds"])
                assert unique_boxes(alone) == unique_boxes(answers[k]), f"{name} pose {k}: the batch answer differs from the single one"
        complete = [a for a in answers if a["status"] == "complete"]
        lost = [k for k, (q, a) in enumerate(zip(qs, answers)) if a["status"] == "complete" and not holds(a, q)]
        assert not lost, f"{name}: the configuration of poses {lost} is in no unique box"
        solver = statistics.median(a["seconds"] for a in answers)
        mean = statistics.fmean(a["seconds"] for a in answers)
        single = statistics.median(singles)
        worst = max(a["seconds"] for a in answers)
        methods = {m: sum(a.get("method") == m for a in answers) for m in ("closed_form", "closed_form_and_search", "search")}
        print(f"{name:10} {len(poses):5} {1e6 * solver:15.1f} {1e6 * mean:8.1f} {1e6 * worst:8.0f} {1e3 * batch:36.3f} {1e3 * single:8.3f}  closed {methods['closed_form']}, closed+search {methods['closed_form_and_search']}, search {methods['search']} ({len(complete)} complete)")


if __name__ == "__main__":
    main()
