#!/usr/bin/env python3
"""Reference forward kinematics of urdf/delta.urdf, in closed form with mpmath.

With the three actuators fixed, each forearm rod (ball to ball) keeps its wrist ball centre on a
sphere about its elbow ball centre; the platform only translates (virtual guide platform_x/y/z),
so its origin p lies on three spheres with centres c_i = E_i - R0 a_i (E_i elbow ball centre in the
base frame, a_i the wrist ball centre in the platform frame, R0 the platform's constant rotation)
and radii l_i (rod lengths). Three-sphere intersection in closed form: 0 or 2 real solutions
(1 on the boundary). Every number of the mechanism is read from the URDF.

Run: python3 scripts/dev/delta_fk.py  (writes tests/data/delta_fk.json; needs mpmath)
"""
import json
import os
import sys

import mpmath as mp

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
from urdf_mp import Frame, Urdf  # noqa: E402

mp.mp.dps = 50

# Actuator triples (radians, as decimal strings: the references use exactly these decimals).
CASES = [
    ("symmetric", ["0.5", "0.5", "0.5"], "all arms 0.5 rad below horizontal"),
    ("asymmetric", ["0.2", "0.75", "-0.1"], "generic triple"),
    ("steep", ["1.1", "0.3", "0.62"], "generic triple, arm 1 steep"),
    ("near_workspace_boundary", ["1.6", "1.6", "1.6"],
     "all actuators at their upper limit: the lower assembly is the closest the file's limits allow to the "
     "serial singularity (each forearm 0.148 rad from the line of its upper arm: the platform near the "
     "bottom of its reachable workspace). For these dimensions neither singularity is reachable within the "
     "actuator limits: the parallel one (the two assemblies merge, platform in the plane of the sphere "
     "centres) needs arms folded about 2 rad under the base; the half separation of the two assemblies is "
     "at least 0.66 m over the whole limit box (grid search)"),
]


def s(x, digits=40):
    return mp.nstr(x, digits)


def vec(v):
    return [float(v[k]) for k in range(3)]


def vec_s(v):
    return [s(v[k]) for k in range(3)]


def norm(v):
    return mp.sqrt(sum(v[k] ** 2 for k in range(3)))


def cross(a, b):
    return mp.matrix([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def dot(a, b):
    return sum(a[k] * b[k] for k in range(3))


class Delta:
    def __init__(self, path):
        u = Urdf(path)
        self.u = u
        self.arms = []
        for i in (1, 2, 3):
            act = u.joints[f"actuator{i}"]
            assert act["type"] == "revolute" and act["parent"] == u.root
            upper = act["child"]
            elbow = [j for j in u.joints.values() if j["parent"] == upper and j["type"] == "spherical"]
            assert len(elbow) == 1
            elbow = elbow[0]
            forearm = elbow["child"]
            loop = u.loops[f"wrist{i}"]
            assert loop["type"] == "spherical" and loop["predecessor"] == forearm and loop["successor"] == "platform"
            # elbow ball centre = origin of the forearm frame; wrist ball centre on the rod:
            on_rod = loop["predecessor_origin"].t
            on_platform = loop["successor_origin"].t
            self.arms.append({"actuator": act, "upper": upper, "elbow": elbow, "forearm": forearm,
                              "length": norm(on_rod), "on_platform": on_platform, "loop": loop})
        # platform guide: check it is a pure translation with joint values = origin coordinates
        self.guide = ["platform_x", "platform_y", "platform_z"]
        F0 = u.link_frame("platform", {})
        for k, name in enumerate(self.guide):
            j = u.joints[name]
            assert j["type"] == "prismatic"
            e = [mp.mpf(0)] * 3
            e[k] = mp.mpf(1)
            F = u.link_frame("platform", {name: mp.mpf(1)})
            assert norm(F.t - F0.t - mp.matrix(e)) < mp.mpf(10) ** -45, name
        assert norm(F0.t) < mp.mpf(10) ** -45
        assert mp.mnorm(F0.R - mp.eye(3), 1) < mp.mpf(10) ** -45
        self.R0 = F0.R

    def elbows(self, q):
        out = []
        for arm, qi in zip(self.arms, q):
            F = self.u.link_frame(arm["upper"], {arm["actuator"]["name"]: qi}) * arm["elbow"]["origin"]
            out.append(F.t)
        return out

    def fk(self, q):
        E = self.elbows(q)
        c = [E[i] - self.R0 * self.arms[i]["on_platform"] for i in range(3)]
        r = [a["length"] for a in self.arms]
        d = norm(c[1] - c[0])
        ex = (c[1] - c[0]) / d
        i_ = dot(ex, c[2] - c[0])
        t = c[2] - c[0] - i_ * ex
        j_ = norm(t)
        ey = t / j_
        ez = cross(ex, ey)
        x = (r[0] ** 2 - r[1] ** 2 + d ** 2) / (2 * d)
        y = (r[0] ** 2 - r[2] ** 2 + i_ ** 2 + j_ ** 2) / (2 * j_) - i_ * x / j_
        h2 = r[0] ** 2 - x ** 2 - y ** 2
        sols = []
        if h2 > 0:
            h = mp.sqrt(h2)
            for sign in (-1, 1):
                sols.append(c[0] + x * ex + y * ey + sign * h * ez)
        sols.sort(key=lambda p: p[2])  # lower assembly first
        return E, c, sols, h2

    def limits_ok(self, p, q):
        ok = True
        for k, name in enumerate(self.guide):
            lo, hi = self.u.joints[name]["limits"]
            ok &= lo <= p[k] <= hi
        for arm, qi in zip(self.arms, q):
            lo, hi = arm["actuator"]["limits"]
            ok &= lo <= qi <= hi
        return bool(ok)


def main():
    path = os.path.join(REPO, "urdf", "delta.urdf")
    delta = Delta(path)
    cases = []
    for name, qs, note in CASES:
        extra = {}
        q = [mp.mpf(v) for v in qs]
        E, c, sols, h2 = delta.fk(q)
        assert len(sols) == 2, (name, h2)
        solutions = []
        for k, p in enumerate(sols):
            W = [p + delta.R0 * a["on_platform"] for a in delta.arms]
            res = [norm(W[i] - E[i]) - delta.arms[i]["length"] for i in range(3)]
            assert max(abs(x) for x in res) < mp.mpf(10) ** -40
            dirs = [(W[i] - E[i]) / delta.arms[i]["length"] for i in range(3)]
            A = [delta.u.link_frame(a["upper"], {a["actuator"]["name"]: q[i]}).t for i, a in enumerate(delta.arms)]
            stretch = [mp.acos(dot((E[i] - A[i]) / norm(E[i] - A[i]), dirs[i])) for i in range(3)]
            solutions.append({
                "assembly": "lower" if k == 0 else "upper",
                "platform_position": vec(p),
                "platform_position_40_digits": vec_s(p),
                "platform_quaternion_wxyz": [1.0, 0.0, 0.0, 0.0],
                "joints": {**{f"actuator{i + 1}": float(q[i]) for i in range(3)},
                           **{delta.guide[k2]: float(p[k2]) for k2 in range(3)}},
                "tool0_position": vec(p + delta.R0 * mp.matrix([0, 0, mp.mpf("-0.03")])),
                "elbow_ball_centres": [vec(e) for e in E],
                "wrist_ball_centres": [vec(w) for w in W],
                "forearm_directions": [vec(d) for d in dirs],
                "elbow_bend_angles": [float(x) for x in stretch],
                "rod_length_residuals": [float(x) for x in res],
                "within_joint_limits": delta.limits_ok(p, q),
            })
        case = {
            "name": name,
            "note": note,
            "actuators": {f"actuator{i + 1}": qs[i] for i in range(3)},
            "actuators_float": {f"actuator{i + 1}": float(q[i]) for i in range(3)},
            "real_solutions": len(solutions),
            "half_separation": float(mp.sqrt(h2)),
            "sphere_centres": [vec(x) for x in c],
            "solutions": solutions,
        }
        case.update(extra)
        cases.append(case)
        print(f"{name}: q = {qs}, {len(solutions)} real, half separation {mp.nstr(mp.sqrt(h2), 6)} m,"
              f" platform {[mp.nstr(x, 8) for x in sols[0]]} / {[mp.nstr(x, 8) for x in sols[1]]}")
    out = {
        "mechanism": "delta",
        "urdf": "urdf/delta.urdf",
        "generator": "scripts/dev/delta_fk.py (closed-form three-sphere intersection, mpmath 50 digits)",
        "units": "metres, radians",
        "frames": "positions in the root frame (base_link); platform_position = origin of the platform link frame "
                  "= values of the prismatic joints platform_x, platform_y, platform_z; the platform never rotates "
                  "(quaternion [1,0,0,0]); forearm_directions are unit vectors from elbow to wrist ball centre",
        "actuator_values": "decimal strings: the references use exactly these decimals (pass them to --fix as written)",
        "rod_lengths": [float(a["length"]) for a in delta.arms],
        "platform_ball_centres_in_platform_frame": [vec(a["on_platform"]) for a in delta.arms],
        "cases": cases,
    }
    target = os.path.join(REPO, "tests", "data", "delta_fk.json")
    with open(target, "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")
    print("wrote", os.path.relpath(target, REPO))


if __name__ == "__main__":
    main()
