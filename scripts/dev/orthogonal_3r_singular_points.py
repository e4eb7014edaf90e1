#!/usr/bin/env python3
"""Cusps and nodes of an orthogonal 3R (seed 003's closed form), without linkspace.

Reads d2, d3, d4, r2, r3 from the URDF (joint2's origin x, joint3's origin x and y, the tool
joint's origin x and z; the file's own decimals), then uses the seed's map

    rho = (cos t2 (d4 cos t3 + d3) + d2 - r3 sin t2)^2 + (d4 sin t3 + r2)^2
    z   = sin t2 (d4 cos t3 + d3) + r3 cos t2

with derivatives written out by hand.

1. The singular curve det Df = 0 is traced by marching squares on an N x N grid of the torus
   (plain floats; N = 2000 by default: cells of 3.1e-3 rad).
2. Cusp candidates: points of the traced polyline where the image's direction reverses (the
   dot product of consecutive image chords < 0). Node candidates: proper crossings of two
   non-adjacent image chords (found by bucketing the chords in the image plane).
3. Every candidate is polished by Newton in mpmath (50 digits): cusps on (det, g) with
   g = Df T, T = (-d det/d t3, d det/d t2) (the seed's system (2), the row with the larger
   |grad f_k|); nodes on the doubled system (3): f(x1) - f(x2) = 0, det(x1) = 0, det(x2) = 0.
   Converged roots are kept when the residual is < 1e-40 and, for nodes, |x1 - x2| > 1e-6
   (chords near a cusp cross without a node: Newton then runs to the diagonal or diverges);
   duplicates (and the seam copies) are merged.

Usage: python3 scripts/dev/orthogonal_3r_singular_points.py URDF [N] > tests/data/FILE.json
(mpmath only; about 30 s for N = 2000 on one core).
"""
import json
import math
import sys
import xml.etree.ElementTree as ET

import mpmath as mp

mp.mp.dps = 50


def lengths(path):
    joints = {j.get("name"): j for j in ET.parse(path).getroot().findall("joint")}
    def xyz(name):
        return [mp.mpf(v) for v in joints[name].find("origin").get("xyz").split()]
    tool = [j for j in joints.values() if j.get("type") == "fixed"][0].get("name")
    d2 = xyz("joint2")[0]
    d3, r2 = xyz("joint3")[0], xyz("joint3")[1]
    d4, r3 = xyz(tool)[0], xyz(tool)[2]
    return d2, d3, d4, r2, r3


class Map:
    def __init__(self, d2, d3, d4, r2, r3, lib):
        self.p = (d2, d3, d4, r2, r3)
        self.m = lib

    def jets(self, t2, t3):
        """f, Df and det Df at (t2, t3)."""
        d2, d3, d4, r2, r3 = self.p
        m = self.m
        c2, s2, c3, s3 = m.cos(t2), m.sin(t2), m.cos(t3), m.sin(t3)
        a = d4 * c3 + d3
        x = c2 * a + d2 - r3 * s2
        y = d4 * s3 + r2
        rho = x * x + y * y
        z = s2 * a + r3 * c2
        x2, x3 = -s2 * a - r3 * c2, -c2 * d4 * s3
        y3 = d4 * c3
        rho2, rho3 = 2 * x * x2, 2 * x * x3 + 2 * y * y3
        z2, z3 = c2 * a - r3 * s2, -s2 * d4 * s3
        det = rho2 * z3 - rho3 * z2
        return (rho, z), ((rho2, rho3), (z2, z3)), det

    def det(self, t2, t3):
        return self.jets(t2, t3)[2]


def mp_det_grad(mp_map, t2, t3):
    return mp.diff(lambda a, b: mp_map.det(a, b), (t2, t3), (1, 0)), mp.diff(lambda a, b: mp_map.det(a, b), (t2, t3), (0, 1))


def trace(fmap, n):
    """Marching squares on det over the torus: a list of segments ((t2, t3), (t2, t3))."""
    h = 2 * math.pi / n
    ts = [-math.pi + i * h for i in range(n + 1)]
    grid = [[fmap.det(ts[i], ts[j]) for j in range(n + 1)] for i in range(n + 1)]
    segs = []
    for i in range(n):
        for j in range(n):
            corners = [(ts[i], ts[j], grid[i][j]), (ts[i + 1], ts[j], grid[i + 1][j]), (ts[i + 1], ts[j + 1], grid[i + 1][j + 1]), (ts[i], ts[j + 1], grid[i][j + 1])]
            pts = []
            for k in range(4):
                (a2, a3, va), (b2, b3, vb) = corners[k], corners[(k + 1) % 4]
                if (va < 0) != (vb < 0):
                    t = va / (va - vb)
                    pts.append((a2 + t * (b2 - a2), a3 + t * (b3 - a3)))
            if len(pts) == 2:
                segs.append((pts[0], pts[1]))
            elif len(pts) == 4:  # saddle cell: pair by the centre's sign (rare at this N)
                segs.append((pts[0], pts[1]))
                segs.append((pts[2], pts[3]))
    return segs


def chains(segs):
    """Joins segments sharing an end point into polylines."""
    key = lambda p: (round(p[0], 12), round(p[1], 12))
    ends = {}
    for k, (a, b) in enumerate(segs):
        ends.setdefault(key(a), []).append(k)
        ends.setdefault(key(b), []).append(k)
    used = [False] * len(segs)
    lines = []
    for k in range(len(segs)):
        if used[k]:
            continue
        used[k] = True
        line = [segs[k][0], segs[k][1]]
        for direction in (1, 0):
            while True:
                tip = line[-1] if direction else line[0]
                nxt = [s for s in ends.get(key(tip), []) if not used[s]]
                if not nxt:
                    break
                s = nxt[0]
                used[s] = True
                a, b = segs[s]
                other = b if key(a) == key(tip) else a
                if direction:
                    line.append(other)
                else:
                    line.insert(0, other)
        lines.append(line)
    return lines


def cross(o, a, b):
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def proper_crossing(p1, p2, q1, q2):
    d1, d2, d3, d4 = cross(q1, q2, p1), cross(q1, q2, p2), cross(p1, p2, q1), cross(p1, p2, q2)
    return (d1 > 0) != (d2 > 0) and (d3 > 0) != (d4 > 0) and d1 != 0 and d2 != 0 and d3 != 0 and d4 != 0


def wrap(t):
    return (t + mp.pi) % (2 * mp.pi) - mp.pi


def main():
    path = sys.argv[1]
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 2000
    ls = lengths(path)
    fmap = Map(*[float(v) for v in ls], lib=math)
    mmap = Map(*ls, lib=mp)
    lines = chains(trace(fmap, n))
    # Image polylines.
    pts = []  # (line, index, joint point, image point)
    for li, line in enumerate(lines):
        for k, p in enumerate(line):
            pts.append((li, k, p, fmap.jets(*p)[0]))
    by_line = {}
    for li, k, p, im in pts:
        by_line.setdefault(li, []).append((p, im))
    cusp_starts, node_starts = [], []
    chords = []
    for li, seq in by_line.items():
        for k in range(1, len(seq) - 1):
            (_, a), (_, b), (_, c) = seq[k - 1], seq[k], seq[k + 1]
            if (b[0] - a[0]) * (c[0] - b[0]) + (b[1] - a[1]) * (c[1] - b[1]) < 0:
                cusp_starts.append(seq[k][0])
        for k in range(len(seq) - 1):
            chords.append((li, k, seq[k], seq[k + 1]))
    # Bucket the chords by their image bounding boxes.
    cell = 2e-3
    buckets = {}
    for idx, (_, _, (_, a), (_, b)) in enumerate(chords):
        for i in range(int(math.floor(min(a[0], b[0]) / cell)), int(math.floor(max(a[0], b[0]) / cell)) + 1):
            for j in range(int(math.floor(min(a[1], b[1]) / cell)), int(math.floor(max(a[1], b[1]) / cell)) + 1):
                buckets.setdefault((i, j), []).append(idx)
    seen = set()
    for members in buckets.values():
        for x in range(len(members)):
            for y in range(x + 1, len(members)):
                i, j = members[x], members[y]
                if (i, j) in seen:
                    continue
                seen.add((i, j))
                (li, ki, (pa, a), (pb, b)), (lj, kj, (qa, c), (qb, d)) = chords[i], chords[j]
                if li == lj and abs(ki - kj) <= 1:
                    continue
                if proper_crossing(a, b, c, d):
                    node_starts.append(((pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (qa[0] + qb[0]) / 2, (qa[1] + qb[1]) / 2))
    cusps = []
    for t2, t3 in cusp_starts:
        def system(a, b):
            (_, _), df, det = mmap.jets(a, b)
            g2, g3 = mp_det_grad(mmap, a, b)
            k = 0 if abs(df[0][0]) + abs(df[0][1]) >= abs(df[1][0]) + abs(df[1][1]) else 1
            return [det, df[k][0] * (-g3) + df[k][1] * g2]
        try:
            r = mp.findroot(system, (mp.mpf(t2), mp.mpf(t3)), tol=mp.mpf(10) ** -45, maxsteps=50)
        except (ValueError, ZeroDivisionError):
            continue
        r = [wrap(r[0]), wrap(r[1])]
        if max(abs(v) for v in system(*r)) > mp.mpf(10) ** -40:
            continue
        if all(max(abs(r[0] - c[0]), abs(r[1] - c[1])) > 1e-20 for c in cusps):
            cusps.append(r)
    nodes = []
    for s in node_starts:
        def system(a2, a3, b2, b3):
            fa, _, da = mmap.jets(a2, a3)
            fb, _, db = mmap.jets(b2, b3)
            return [fa[0] - fb[0], fa[1] - fb[1], da, db]
        try:
            r = mp.findroot(system, tuple(mp.mpf(v) for v in s), tol=mp.mpf(10) ** -45, maxsteps=50)
        except (ValueError, ZeroDivisionError):
            continue
        r = [wrap(v) for v in r]
        if max(abs(v) for v in system(*r)) > mp.mpf(10) ** -40:
            continue
        if max(abs(r[0] - r[2]), abs(r[1] - r[3])) < 1e-6:
            continue
        if r[0] > r[2] or (r[0] == r[2] and r[1] > r[3]):
            r = [r[2], r[3], r[0], r[1]]
        if all(max(abs(r[i] - m[i]) for i in range(4)) > 1e-20 for m in nodes):
            nodes.append(r)
    def image(a, b):
        (rho, z), _, _ = mmap.jets(a, b)
        return [float(mp.sqrt(rho)), float(z)]
    out = {
        "urdf": path,
        "lengths": {"d2": str(ls[0]), "d3": str(ls[1]), "d4": str(ls[2]), "r2": str(ls[3]), "r3": str(ls[4])},
        "method": f"marching squares on det Df, {n} x {n} grid; image direction reversals (cusps) and chord crossings (nodes); Newton in mpmath at 50 digits on (det, g_k) and on system (3)",
        "cusps": [{"joints": [float(c[0]), float(c[1])], "joints_40_digits": [mp.nstr(c[0], 40), mp.nstr(c[1], 40)], "radius_z": image(*c)} for c in sorted(cusps)],
        "nodes": [{"points": [[float(m[0]), float(m[1])], [float(m[2]), float(m[3])]], "points_40_digits": [[mp.nstr(m[0], 40), mp.nstr(m[1], 40)], [mp.nstr(m[2], 40), mp.nstr(m[3], 40)]], "radius_z": image(m[0], m[1])} for m in sorted(nodes)],
    }
    json.dump(out, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
