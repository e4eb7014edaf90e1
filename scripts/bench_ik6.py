#!/usr/bin/env python3
"""Certified 6R inverse kinematics (`linkspace ik6`) against a numerical solver, ikpy.

For each arm: random joint vectors q in [-3.1, 3.1]^6, their tip pose by ikpy's own forward
kinematics (independent of linkspace), then
- linkspace: `ik6 ARM --pose <4x4> --json` (every solution in [-pi, pi]^6, each certified);
- ikpy: `inverse_kinematics_frame` from R random starts (scipy least squares), the converged
  ones (position 1e-6 m, rotation 1e-6) deduplicated (1e-4 rad).
Both solve the same problem: the arm's URDF with every revolute limit set to [-pi, pi], every
angle as written (`--exact-geometry`: no snapping of truncated quarter turns).

Prints per arm: median and maximum seconds per pose (linkspace: its own solver time from the
JSON, `seconds`; ikpy: all R starts), the histogram of solution counts each finds, and checks
that every ikpy solution lies in a linkspace box (a solution linkspace lost would be a bug)
and that q itself is in one.

    python3 -m venv V && V/bin/pip install ikpy
    V/bin/python scripts/bench_ik6.py --linkspace target/release/linkspace --poses 100 --restarts 64
"""
import argparse
import collections
import json
import math
import os
import random
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

try:
    from ikpy.chain import Chain
except ImportError:
    sys.exit("bench_ik6.py: needs ikpy (pip install ikpy)")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ARMS = {
    "ur5": "urdf/ur5.urdf",
    "crx": "tests/data/fanuc_crx10ial_style.urdf",
    "puma560": "urdf/puma560.urdf",
    "kuka_kr16": "urdf/kuka_kr16.urdf",
}


def one_turn(xml):
    """Every revolute limit set to [-pi, pi] (both solvers then search the same box)."""
    return re.sub(r'lower="[^"]*"(\s+)upper="[^"]*"', lambda m: f'lower="{-math.pi!r}"{m.group(1)}upper="{math.pi!r}"', xml)


def revolute_path(xml):
    """Root link, then joint, link, joint, ... down to the child of the sixth revolute joint:
    the chain `ik6` analyses by default, spelled out for ikpy (which otherwise follows the
    first child, a side link on some arms)."""
    import xml.etree.ElementTree as ET
    robot = ET.fromstring(xml)
    joints = [(j.get("name"), j.get("type"), j.find("parent").get("link"), j.find("child").get("link")) for j in robot.findall("joint")]
    children = {c for _, _, _, c in joints}
    root = next(l.get("name") for l in robot.findall("link") if l.get("name") not in children)

    def walk(link, path, revolute):
        if revolute == 6:
            return path
        for name, kind, parent, child in joints:
            if parent == link:
                got = walk(child, path + [name, child], revolute + (kind in ("revolute", "continuous")))
                if got:
                    return got
        return None

    return walk(root, [root], 0)


def wrap(x):
    return (x + math.pi) % (2 * math.pi) - math.pi


def near(a, b, tol):
    return all(abs(wrap(x - y)) <= tol for x, y in zip(a, b))


def ikpy_solutions(chain, mask, target, restarts, rng):
    found = []
    t0 = time.process_time()
    n = len(chain.links)
    for _ in range(restarts):
        start = np.zeros(n)
        start[mask] = [rng.uniform(-math.pi, math.pi) for _ in range(6)]
        try:
            q = chain.inverse_kinematics_frame(target, initial_position=start, orientation_mode="all")
        except Exception:  # a failed optimisation is a start that did not converge
            continue
        f = chain.forward_kinematics(q)
        if np.linalg.norm(f[:3, 3] - target[:3, 3]) > 1e-6 or np.linalg.norm(f[:3, :3] - target[:3, :3]) > 1e-6:
            continue
        joints = [wrap(x) for x in np.asarray(q)[mask]]
        if not any(near(joints, s, 1e-4) for s in found):
            found.append(joints)
    return found, time.process_time() - t0


def linkspace_solutions(binary, urdf, target):
    pose = ",".join(repr(float(x)) for x in target.reshape(-1))
    with tempfile.NamedTemporaryFile(suffix=".json") as out:
        # --exact-geometry: ikpy takes every angle as written, so linkspace must not snap the
        # file's truncated quarter turns (its default rounding policy) to solve the same arm.
        subprocess.run([binary, "ik6", urdf, "--exact-geometry", "--pose", pose, "--json", out.name], check=True, capture_output=True)
        report = json.load(open(out.name))
    joints = report["joints"]
    boxes = [[b[j] for j in joints] for b in report["unique"]]
    return boxes, report["clusters"], report["seconds"], report["status"]


def inside(q, box, slack):
    # A box may straddle +-pi; compare modulo 2 pi around its middle.
    for x, (lo, hi) in zip(q, box):
        mid = 0.5 * (lo + hi)
        x = mid + wrap(x - mid)
        if not (lo - slack <= x <= hi + slack):
            return False
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--linkspace", default=os.path.join(ROOT, "target/release/linkspace"))
    ap.add_argument("--poses", type=int, default=100)
    ap.add_argument("--restarts", type=int, default=64)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--arms", default=",".join(ARMS))
    args = ap.parse_args()
    rng = random.Random(args.seed)
    rows = []
    for name in args.arms.split(","):
        rel = ARMS[name]
        xml = one_turn(open(os.path.join(ROOT, rel)).read())
        with tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False) as f:
            f.write(xml)
            urdf = f.name
        chain = Chain.from_urdf_file(urdf, base_elements=revolute_path(xml))
        mask = [i for i, l in enumerate(chain.links) if getattr(l, "joint_type", None) == "revolute"]
        if len(mask) != 6:
            sys.exit(f"{name}: ikpy reads {len(mask)} revolute joints, not 6")
        ls_t, ik_t, ls_n, ik_n, lost, q_missed = [], [], collections.Counter(), collections.Counter(), 0, 0
        for _ in range(args.poses):
            q = [rng.uniform(-3.1, 3.1) for _ in range(6)]
            full = np.zeros(len(chain.links))
            full[mask] = q
            target = chain.forward_kinematics(full)
            boxes, clusters, seconds, status = linkspace_solutions(args.linkspace, urdf, target)
            numeric, cpu = ikpy_solutions(chain, mask, target, args.restarts, rng)
            ls_t.append(seconds)
            ik_t.append(cpu)
            ls_n[len(boxes) if status == "complete" and not clusters else f"{len(boxes)}+{len(clusters)} undecided"] += 1
            ik_n[len(numeric)] += 1
            for s in numeric:
                if any(inside(s, b, 1e-6) for b in boxes):
                    continue
                # Near a singular pose a pose residual of 1e-7 allows joint errors of 1e-3 and
                # more: say how far the nearest certified solution is, and the residual there.
                gap = min((max(abs(wrap(x - 0.5 * (lo + hi))) for x, (lo, hi) in zip(s, b)) for b in boxes), default=math.inf)
                full_s = np.zeros(len(chain.links))
                full_s[mask] = s
                f = chain.forward_kinematics(full_s)
                residual = np.linalg.norm(f[:3, 3] - target[:3, 3]) + np.linalg.norm(f[:3, :3] - target[:3, :3])
                print(f"  {name}: ikpy solution {[round(x, 6) for x in s]} (pose residual {residual:.1e}) lies {gap:.1e} rad from the nearest certified box; q = {[round(x, 6) for x in q]}", flush=True)
                lost += gap > 1e-3
            q_missed += 0 if any(inside(q, b, 1e-6) for b in boxes) else 1
        os.unlink(urdf)
        rows.append((name, ls_t, ik_t, ls_n, ik_n, lost, q_missed))
        print(f"{name}: {args.poses} poses; linkspace median {statistics.median(ls_t) * 1e3:.1f} ms, max {max(ls_t) * 1e3:.1f} ms, "
              f"counts {dict(sorted(ls_n.items(), key=str))}; ikpy ({args.restarts} starts) median {statistics.median(ik_t) * 1e3:.1f} ms, "
              f"max {max(ik_t) * 1e3:.1f} ms, counts {dict(sorted(ik_n.items()))}; ikpy solutions more than 1e-3 rad from every linkspace box: {lost}; "
              f"poses whose q is in no box: {q_missed}", flush=True)
    print()
    print("| arm | poses | linkspace median / max ms | solutions (linkspace) | ikpy median / max ms | solutions (ikpy) | ikpy solutions > 1e-3 rad from linkspace's boxes |")
    print("|---|---|---|---|---|---|---|")
    for name, ls_t, ik_t, ls_n, ik_n, lost, _ in rows:
        avg = lambda c: sum(k * v for k, v in c.items() if isinstance(k, int)) / max(1, sum(v for k, v in c.items() if isinstance(k, int)))
        print(f"| {name} | {len(ls_t)} | {statistics.median(ls_t) * 1e3:.1f} / {max(ls_t) * 1e3:.1f} | mean {avg(ls_n):.2f} | "
              f"{statistics.median(ik_t) * 1e3:.1f} / {max(ik_t) * 1e3:.1f} | mean {avg(ik_n):.2f} | {lost} |")
    sys.exit(1 if any(r[5] or r[6] for r in rows) else 0)


if __name__ == "__main__":
    main()
