#!/usr/bin/env python3
"""Certified 6R IK against two analytic solvers in floating point, in the same invocation on the
same poses: IK-Geo (Elias & Wen 2022, the `ik-geo` package) and EAIK (Ostermeier et al. 2025,
the `EAIK` package), each a closed form by subproblem decomposition without certificates.

For each arm: random joint vectors q in the joint box (limits cut to one turn), their tip pose
by forward kinematics written here from the URDF's origins and axes (`bench_ik6_poses.py`'s, no
solver code), then
- linkspace: `ik6 ARM --exact-geometry --poses FILE --json OUT` once, on a copy of the URDF
  whose revolute joints are continuous; the time per pose is the report's `seconds` (the solver's own), the
  solutions its certified boxes;
- IK-Geo and EAIK: one call per pose from Python (the time includes the binding's overhead),
  on the arm as axes and offsets at the zero configuration (product of exponentials: `H`, `P`,
  the tool's orientation moved onto the target), the origins of meeting wrist axes moved to
  their common point (IK-Geo's solvers take the wrist point as the joints' origin), and
  components below 1e-9 set to 0 (IK-Geo's UR solver needs axes 2, 3, 4 exactly along a
  coordinate axis; the UR5's 1.570796327 leaves 2e-10).
All three solve over the whole torus (every angle modulo a turn; the peers know no limits) and
the arm as written (a snapped 1.5708 would move the PUMA's tip by 1e-6 m), up to those 2e-10
for the peers. Every solution is checked by
the forward kinematics here (position and rotation within 1e-6; for linkspace at its box's
midpoint), the peers' least-squares ones (`is_ls`) dropped. Prints per arm and solver the
median and maximum microseconds per pose, the solutions found (all poses together), those
checked (distinct modulo a turn), on how many poses the solver misses a checked solution
another found, and the ratio of linkspace's median to each peer's; for linkspace also the poses
its closed form left to the search, by reason. IK-Geo's solver is picked
by the arm's family (`three_parallel_two_intersecting` for the UR5, `spherical_two_parallel`
for the spherical wrists; its plain `three_parallel` returns no valid solution of the UR5 here);
EAIK picks its own. A benchmark, not a test.

    python3 -m venv target/peers-venv && target/peers-venv/bin/pip install ik-geo EAIK numpy
    target/peers-venv/bin/python scripts/bench_ik6_peers.py --linkspace target/release/linkspace --poses 200
"""
import argparse
import json
import math
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_ik6_poses import ROOT, axis_angle, chain_to, forward, limits, rpy_matrix  # noqa: E402

# name: (file, tip, IK-Geo solver, wrist joints whose axes meet: their origins are moved there)
ARMS = {
    "ur5": ("urdf/ur5.urdf", "tool0", "three_parallel_two_intersecting", (4, 5)),
    "puma560": ("urdf/puma560.urdf", "tool0", "spherical_two_parallel", (3, 4, 5)),
    "kuka_kr16": ("urdf/kuka_kr16.urdf", "tool0", "spherical_two_parallel", (3, 4, 5)),
    "staubli_tx90": ("urdf/staubli_tx90.urdf", None, "spherical_two_parallel", (3, 4, 5)),
}


def zero_frames(chain):
    """Per revolute joint at q = 0: its axis and origin in the base frame; and the tip's pose."""
    T, axes = np.eye(4), []
    for j in chain:
        o = j.find("origin")
        xyz = [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
        rpy = [float(v) for v in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
        step = np.eye(4)
        step[:3, :3], step[:3, 3] = rpy_matrix(*rpy), xyz
        T = T @ step
        if j.get("type") in ("revolute", "continuous"):
            a = j.find("axis")
            h = np.array([float(v) for v in (a.get("xyz") if a is not None else "1 0 0").split()])
            axes.append((T[:3, :3] @ (h / np.linalg.norm(h)), T[:3, 3].copy()))
    return axes, T


def meeting_point(lines):
    """The point nearest to all the lines (direction, point) in least squares, and its distance
    from the farthest."""
    A, b = np.zeros((3, 3)), np.zeros(3)
    for h, o in lines:
        m = np.eye(3) - np.outer(h, h)
        A, b = A + m, b + m @ o
    w = np.linalg.lstsq(A, b, rcond=None)[0]
    return w, max(np.linalg.norm((np.eye(3) - np.outer(h, h)) @ (w - o)) for h, o in lines)


def hp_model(chain, wrist):
    """`H` (6×3), `P` (7×3) and the tool's orientation at q = 0: tip(q) = (Π R(hᵢ, qᵢ))·R_tool,
    position Σ R₀..ᵢ pᵢ."""
    axes, tip = zero_frames(chain)
    origins = [o for _, o in axes]
    w, miss = meeting_point([axes[k] for k in wrist])
    assert miss < 1e-9, f"wrist axes {wrist} miss by {miss}"
    for k in wrist:
        origins[k] = w
    H = np.array([h for h, _ in axes])
    P = np.array([origins[0]] + [origins[k + 1] - origins[k] for k in range(5)] + [tip[:3, 3] - origins[5]])
    H[np.abs(H) < 1e-9], P[np.abs(P) < 1e-9] = 0.0, 0.0
    return H / np.linalg.norm(H, axis=1)[:, None], P, tip[:3, :3]


def continuous_copy(path, out):
    """The URDF at `path` with every revolute joint continuous, written to `out`."""
    tree = ET.parse(path)
    for j in tree.getroot().findall("joint"):
        if j.get("type") == "revolute":
            j.set("type", "continuous")
    tree.write(out)


def checked(chain, T, q, tol=1e-6):
    F = forward(chain, q)
    return np.abs(F[:3, :3] - T[:3, :3]).max() < tol and np.abs(F[:3, 3] - T[:3, 3]).max() < tol


def distinct(qs, tol=1e-6):
    """Solutions distinct modulo a turn."""
    out = []
    for q in qs:
        if not any(all(abs(math.remainder(a - b, math.tau)) < tol for a, b in zip(q, p)) for p in out):
            out.append(q)
    return out


def peers(H, P):
    import eaik.IK_HP
    import ik_geo

    return eaik.IK_HP.HPRobot(H, P), ik_geo


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--linkspace", default=os.path.join(ROOT, "target/release/linkspace"))
    ap.add_argument("--poses", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--arms", default=",".join(ARMS))
    args = ap.parse_args()
    rng = random.Random(args.seed)
    print(f"{'arm':13} {'solver':10} {'median us':>10} {'max us':>10} {'solutions':>9} {'checked':>8} {'poses missing one':>17} {'linkspace/peer':>14}")
    for name in args.arms.split(","):
        rel, tip, family, wrist = ARMS[name]
        path = os.path.join(ROOT, rel)
        chain = chain_to(path, tip)
        box = limits(chain)
        qs = [[rng.uniform(lo, hi) for lo, hi in box] for _ in range(args.poses)]
        targets = [forward(chain, q) for q in qs]
        H, P, R_tool = hp_model(chain, wrist)
        eaik_robot, ik_geo = peers(H, P)
        geo_robot = getattr(ik_geo.Robot, family)(H.tolist(), P.tolist())
        found = {"linkspace": [], "ik-geo": [], "eaik": []}
        times = {"linkspace": [], "ik-geo": [], "eaik": []}
        with tempfile.TemporaryDirectory() as tmp:
            file, out, urdf = os.path.join(tmp, "poses.txt"), os.path.join(tmp, "answers.jsonl"), os.path.join(tmp, "arm.urdf")
            continuous_copy(path, urdf)
            open(file, "w").write("\n".join(",".join(repr(float(x)) for x in T.reshape(-1)) for T in targets) + "\n")
            subprocess.run([args.linkspace, "ik6", urdf, "--exact-geometry", "--poses", file, "--json", out], check=True, capture_output=True)
            answers = [json.loads(line) for line in open(out)]
        assert len(answers) == len(targets), f"{name}: {len(answers)} answers for {len(targets)} poses"
        declined = {}
        for a in answers:
            if a["method"] != "closed_form":
                declined[a.get("closed_form_declined")] = declined.get(a.get("closed_form_declined"), 0) + 1
            found["linkspace"].append([[0.5 * (b[j][0] + b[j][1]) for j in a["joints"]] for b in a["unique"]])
            times["linkspace"].append(a["seconds"])
        for T in targets:
            R, p = T[:3, :3] @ R_tool.T, T[:3, 3]
            t = time.perf_counter()
            # IK-Geo takes (and its forward kinematics gives) the rotation by columns.
            sols = geo_robot.get_ik(R.T.tolist(), p.tolist())
            times["ik-geo"].append(time.perf_counter() - t)
            found["ik-geo"].append([list(q) for q, ls in sols if not ls])
            pose = np.eye(4)
            pose[:3, :3], pose[:3, 3] = R, p
            t = time.perf_counter()
            sol = eaik_robot.IK(pose)
            times["eaik"].append(time.perf_counter() - t)
            found["eaik"].append([list(q) for q, ls in zip(sol.Q, sol.is_LS) if not ls])
        good = {s: [distinct([q for q in qs_ if checked(chain, T, q)]) for qs_, T in zip(found[s], targets)] for s in found}
        # A pose where a solver misses a solution some other solver checked.
        union = [distinct([q for s in good for q in good[s][i]]) for i in range(len(targets))]
        ls_median = statistics.median(times["linkspace"])
        for s in found:
            misses = sum(len(good[s][i]) < len(union[i]) for i in range(len(targets)))
            med = statistics.median(times[s])
            ratio = f"  search after the closed form declined: {declined}" if s == "linkspace" and declined else ""
            ratio = ratio if s == "linkspace" else f"{ls_median / med:14.1f}"
            print(f"{name:13} {s:10} {1e6 * med:10.1f} {1e6 * max(times[s]):10.1f} {sum(map(len, found[s])):9} {sum(map(len, good[s])):8} {misses:17} {ratio}")


if __name__ == "__main__":
    main()
