"""Minimal URDF reader in mpmath (no linkspace code involved), for the reference scripts.

Reads joints (origin xyz/rpy, axis, type, limits), links and the top-level <loop> elements of
linkspace's URDF extension, keeping every number as the decimal string written in the file and
converting it with mpmath at the working precision: the references use exactly the file's numbers.
Rotations follow URDF: rpy = fixed-axis roll about x, pitch about y, yaw about z, R = Rz Ry Rx.
"""
import xml.etree.ElementTree as ET

import mpmath as mp


def mpf(s):
    return mp.mpf(s.strip())


def triple(s, default=("0", "0", "0")):
    parts = s.split() if s is not None else list(default)
    assert len(parts) == 3, s
    return [mpf(p) for p in parts]


def rpy_matrix(r, p, y):
    cr, sr, cp, sp, cy, sy = mp.cos(r), mp.sin(r), mp.cos(p), mp.sin(p), mp.cos(y), mp.sin(y)
    return mp.matrix([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])


def axis_angle(axis, q):
    n = mp.sqrt(sum(a * a for a in axis))
    x, y, z = (a / n for a in axis)
    c, s = mp.cos(q), mp.sin(q)
    C = 1 - c
    return mp.matrix([
        [c + x * x * C, x * y * C - z * s, x * z * C + y * s],
        [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
        [z * x * C - y * s, z * y * C + x * s, c + z * z * C],
    ])


class Frame:
    """Rigid transform p -> R p + t with mpmath entries."""

    def __init__(self, R=None, t=None):
        self.R = R if R is not None else mp.eye(3)
        self.t = t if t is not None else mp.matrix([0, 0, 0])

    def __mul__(self, other):
        return Frame(self.R * other.R, self.R * other.t + self.t)

    def apply(self, p):
        return self.R * mp.matrix(p) + self.t


def origin_frame(el):
    o = el.find("origin") if el is not None else None
    if o is None:
        return Frame()
    xyz = triple(o.get("xyz"))
    rpy = triple(o.get("rpy"))
    return Frame(rpy_matrix(*rpy), mp.matrix(xyz))


class Urdf:
    def __init__(self, path):
        self.path = path
        root = ET.parse(path).getroot()
        self.name = root.get("name")
        self.links = [l.get("name") for l in root.findall("link")]
        self.joints = {}
        for j in root.findall("joint"):
            lim = j.find("limit")
            self.joints[j.get("name")] = {
                "name": j.get("name"),
                "type": j.get("type"),
                "parent": j.find("parent").get("link"),
                "child": j.find("child").get("link"),
                "origin": origin_frame(j),
                "origin_el": j.find("origin"),
                "axis": triple(j.find("axis").get("xyz")) if j.find("axis") is not None else [mp.mpf(1), 0, 0],
                "limits": (mpf(lim.get("lower")), mpf(lim.get("upper"))) if lim is not None and lim.get("lower") is not None else None,
            }
        self.parent_joint = {j["child"]: j for j in self.joints.values()}
        children = set(self.parent_joint)
        roots = [l for l in self.links if l not in children]
        assert len(roots) == 1, roots
        self.root = roots[0]
        self.loops = {}
        for l in root.findall("loop"):
            pe, se = l.find("predecessor"), l.find("successor")
            self.loops[l.get("name")] = {
                "name": l.get("name"),
                "type": l.get("type"),
                "predecessor": pe.get("link"),
                "predecessor_origin": origin_frame(pe),
                "successor": se.get("link"),
                "successor_origin": origin_frame(se),
            }

    def joint_motion(self, j, q):
        """Transform contributed by the joint's motion (after its origin)."""
        if j["type"] in ("revolute", "continuous"):
            return Frame(axis_angle(j["axis"], q), None)
        if j["type"] == "prismatic":
            n = mp.sqrt(sum(a * a for a in j["axis"]))
            return Frame(None, mp.matrix([a / n * q for a in j["axis"]]))
        if j["type"] == "fixed":
            return Frame()
        if j["type"] in ("spherical", "floating"):
            # q is a Frame (rotation, and for floating also translation) or None for the rest pose
            return q if q is not None else Frame()
        raise ValueError(j["type"])

    def link_frame(self, link, values):
        """Pose of `link` in the root frame; values: joint name -> value (missing: rest/zero)."""
        chain = []
        while link != self.root:
            j = self.parent_joint[link]
            chain.append(j)
            link = j["parent"]
        F = Frame()
        for j in reversed(chain):
            q = values.get(j["name"], None if j["type"] in ("spherical", "floating") else mp.mpf(0))
            F = F * j["origin"] * self.joint_motion(j, q)
        return F
