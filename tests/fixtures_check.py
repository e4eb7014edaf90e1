#!/usr/bin/env python3
"""Independent geometric check of the URDF fixtures in ../urdf/.

The URDF files are parsed here with xml.etree (no Rust code involved).  For each
mechanism, configurations are computed from the mechanism's own equations
(paper loop equations, Freudenstein, slider-crank closed form, circle
intersections), converted to tree joint values, pushed through forward
kinematics of the *parsed* URDF, and every <loop> closure is checked.

Loop-closure extension (URDF+-style): a top-level
    <loop name=.. type="revolute|prismatic">
      <predecessor link=..><origin xyz rpy/></predecessor>
      <successor link=..><origin xyz rpy/></successor>
      <axis xyz/>
    </loop>
requires the two frames to coincide (revolute: same point, rotation only about
the axis; prismatic: displacement only along the axis, no relative rotation).

Run: python3 tests/fixtures_check.py   (exit status 0 on success)
"""
import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
URDF_DIR = os.path.join(HERE, "..", "urdf")
TOL = 1e-4          # required closure tolerance
TIGHT = 1e-9        # what we actually expect from converged solutions

FAILURES = []


def check(cond, msg):
    if not cond:
        FAILURES.append(msg)
        print("  FAIL: " + msg)
    return cond


# --------------------------------------------------------------------------
# URDF parsing / forward kinematics
# --------------------------------------------------------------------------

def _vec(s, default):
    if s is None:
        return np.array(default, dtype=float)
    v = np.array([float(t) for t in s.split()], dtype=float)
    assert v.shape == (3,), s
    return v


def _origin(elem):
    o = elem.find("origin") if elem is not None else None
    if o is None:
        return np.zeros(3), np.zeros(3)
    return _vec(o.get("xyz"), [0, 0, 0]), _vec(o.get("rpy"), [0, 0, 0])


def rpy_matrix(rpy):
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = (math.cos(r), math.sin(r), math.cos(p),
                              math.sin(p), math.cos(y), math.sin(y))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def transform(xyz, rpy):
    t = np.eye(4)
    t[:3, :3] = rpy_matrix(rpy)
    t[:3, 3] = xyz
    return t


def axis_angle(axis, q):
    k = axis / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(q) * kx + (1 - math.cos(q)) * kx @ kx


def parse_urdf(path):
    root = ET.parse(path).getroot()
    assert root.tag == "robot", path
    model = {"name": root.get("name"), "links": [], "joints": {}, "loops": {}}
    for child in root:
        if child.tag == "link":
            model["links"].append(child.get("name"))
        elif child.tag == "joint":
            xyz, rpy = _origin(child)
            lim = child.find("limit")
            model["joints"][child.get("name")] = {
                "type": child.get("type"),
                "parent": child.find("parent").get("link"),
                "child": child.find("child").get("link"),
                "xyz": xyz, "rpy": rpy,
                "axis": _vec(child.find("axis").get("xyz") if child.find("axis") is not None else None, [1, 0, 0]),
                "limit": None if lim is None else {k: float(lim.get(k)) for k in lim.keys()},
            }
        elif child.tag == "loop":
            ends = {}
            for role in ("predecessor", "successor"):
                e = child.find(role)
                xyz, rpy = _origin(e)
                ends[role] = {"link": e.get("link"), "xyz": xyz, "rpy": rpy}
            model["loops"][child.get("name")] = {
                "type": child.get("type"),
                "axis": _vec(child.find("axis").get("xyz"), [1, 0, 0]),
                **ends,
            }
    return model


def validate_structure(model, planar=True):
    """Tree + loop references + our planar conventions.  Returns the root link."""
    links = model["links"]
    name = model["name"]
    check(len(set(links)) == len(links), f"{name}: duplicate link names")
    children = [j["child"] for j in model["joints"].values()]
    check(len(set(children)) == len(children), f"{name}: a link has two parent joints")
    roots = [l for l in links if l not in children]
    check(len(roots) == 1, f"{name}: expected one root link, got {roots}")
    for jn, j in model["joints"].items():
        check(j["parent"] in links and j["child"] in links, f"{name}: joint {jn} references unknown link")
        check(j["type"] in ("continuous", "revolute", "prismatic", "fixed"), f"{name}: joint {jn} type {j['type']}")
        if j["type"] in ("revolute", "prismatic"):
            lim = j["limit"]
            check(lim is not None and "effort" in lim and "velocity" in lim,
                  f"{name}: joint {jn} needs <limit effort velocity>")
        if planar:
            check(abs(j["xyz"][2]) < 1e-15 and np.allclose(j["rpy"], 0), f"{name}: joint {jn} not planar/rpy=0")
            if j["type"] in ("continuous", "revolute"):
                check(np.allclose(j["axis"], [0, 0, 1]), f"{name}: joint {jn} axis not +z")
            if j["type"] == "prismatic":
                check(abs(j["axis"][2]) < 1e-15, f"{name}: joint {jn} prismatic axis not in plane")
    # reachability (acyclic tree)
    reached, frontier = {roots[0]} if roots else set(), list(roots[:1])
    while frontier:
        p = frontier.pop()
        for j in model["joints"].values():
            if j["parent"] == p:
                check(j["child"] not in reached, f"{name}: cycle in tree at {j['child']}")
                reached.add(j["child"])
                frontier.append(j["child"])
    check(reached == set(links), f"{name}: links not reachable from root: {set(links) - reached}")
    for ln, lp in model["loops"].items():
        check(lp["type"] in ("revolute", "prismatic"), f"{name}: loop {ln} type {lp['type']}")
        for role in ("predecessor", "successor"):
            check(lp[role]["link"] in links, f"{name}: loop {ln} {role} link unknown")
            if planar:
                check(abs(lp[role]["xyz"][2]) < 1e-15 and np.allclose(lp[role]["rpy"], 0),
                      f"{name}: loop {ln} {role} origin not planar")
        if planar and lp["type"] == "revolute":
            check(np.allclose(lp["axis"], [0, 0, 1]), f"{name}: loop {ln} axis not +z")
    return roots[0] if roots else None


def fk(model, q):
    """World transforms of every link for joint values q (dict name -> value)."""
    root = [l for l in model["links"] if l not in [j["child"] for j in model["joints"].values()]][0]
    world = {root: np.eye(4)}
    pending = dict(model["joints"])
    while pending:
        progressed = False
        for jn, j in list(pending.items()):
            if j["parent"] not in world:
                continue
            t = world[j["parent"]] @ transform(j["xyz"], j["rpy"])
            m = np.eye(4)
            v = q.get(jn, 0.0)
            if j["type"] in ("continuous", "revolute"):
                m[:3, :3] = axis_angle(j["axis"], v)
            elif j["type"] == "prismatic":
                m[:3, 3] = v * j["axis"] / np.linalg.norm(j["axis"])
            world[j["child"]] = t @ m
            del pending[jn]
            progressed = True
        assert progressed, "joint graph is not a tree"
    return world


def loop_errors(model, q):
    """Max closure error of each <loop> (position + orientation constraint)."""
    world = fk(model, q)
    errs = {}
    for ln, lp in model["loops"].items():
        tp = world[lp["predecessor"]["link"]] @ transform(lp["predecessor"]["xyz"], lp["predecessor"]["rpy"])
        ts = world[lp["successor"]["link"]] @ transform(lp["successor"]["xyz"], lp["successor"]["rpy"])
        axis = lp["axis"] / np.linalg.norm(lp["axis"])
        d = ts[:3, 3] - tp[:3, 3]
        if lp["type"] == "revolute":
            pos = np.linalg.norm(d)
            # rotation only about the axis: axis expressed in world must agree
            rot = np.linalg.norm(tp[:3, :3] @ axis - ts[:3, :3] @ axis)
        else:
            a_w = tp[:3, :3] @ axis
            pos = np.linalg.norm(d - np.dot(d, a_w) * a_w)
            rot = np.linalg.norm(tp[:3, :3] - ts[:3, :3])
        errs[ln] = max(pos, rot)
    return errs


def check_closure(model, q, label):
    errs = loop_errors(model, q)
    worst = max(errs.values())
    check(worst < TOL, f"{model['name']}: {label}: loop closure error {worst:.3e} ({errs})")
    return worst


def load(fname, expect_name, expect_loops):
    path = os.path.join(URDF_DIR, fname)
    model = parse_urdf(path)
    check(model["name"] == expect_name, f"{fname}: robot name {model['name']!r} != {expect_name!r}")
    validate_structure(model)
    check(sorted(model["loops"]) == sorted(expect_loops),
          f"{fname}: loops {sorted(model['loops'])} != {sorted(expect_loops)}")
    n_cycles = len(model["joints"]) + len(model["loops"]) - len(model["links"]) + 1
    check(n_cycles == len(expect_loops), f"{fname}: cycle count {n_cycles}")
    return model


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def u(t):
    return np.array([math.cos(t), math.sin(t)])


def R(g):
    return np.array([[math.cos(g), -math.sin(g)], [math.sin(g), math.cos(g)]])


def newton(f, x0, tol=1e-13, maxit=50):
    x = np.array(x0, dtype=float)
    for _ in range(maxit):
        r = f(x)
        if np.linalg.norm(r) < tol:
            break
        jac = np.empty((len(r), len(x)))
        h = 1e-7
        for k in range(len(x)):
            e = np.zeros_like(x)
            e[k] = h
            jac[:, k] = (f(x + e) - f(x - e)) / (2 * h)
        x = x - np.linalg.lstsq(jac, r, rcond=None)[0]
    return x, np.linalg.norm(f(x))


def circle_intersections(c0, r0, c1, r1):
    """Both intersection points of two circles (None if they do not meet)."""
    v = c1 - c0
    dist = np.linalg.norm(v)
    x = (dist * dist + r0 * r0 - r1 * r1) / (2 * dist)
    h2 = r0 * r0 - x * x
    if h2 < 0:
        return None, h2
    e = v / dist
    nrm = np.array([-e[1], e[0]])
    h = math.sqrt(h2)
    return (c0 + x * e + h * nrm, c0 + x * e - h * nrm), h2


# --------------------------------------------------------------------------
# 1. double butterfly
# --------------------------------------------------------------------------

def check_double_butterfly():
    print("[double_butterfly.urdf]")
    m = load("double_butterfly.urdf", "double_butterfly", ["loop15", "loop13", "loop24"])
    a0, b0, a1, b1, a2, b2, b6, c6 = 7, 13, 7, 6, 5, 3, 3, 2
    l3, l4, l5, l7 = 7, 9, 12, 11
    g0 = eta6 = math.atan2(3, 4)
    g1 = math.atan2(5, 12)
    g2 = math.atan2(4, 3)
    t6 = math.atan2(12, 5)
    w0 = a0 * np.array([math.cos(g0), -math.sin(g0)])
    B0 = np.array([b0, 0.0])

    def eqs(x):
        t1, t2, t3, t4, t5, t7 = x
        A = l7 * u(t7) + a2 * u(t2) + a1 * u(t1) - l5 * u(t5) + B0
        B = (l7 * u(t7) + a2 * u(t2) + b1 * R(g1) @ u(t1) - l3 * u(t3)
             - c6 * R(eta6) @ u(t6) + w0)
        C = l7 * u(t7) + b2 * R(g2) @ u(t2) - l4 * u(t4) - b6 * u(t6) + w0
        return np.concatenate([A, B, C])

    given = [(-0.49432, 0.78082, -2.96808), (1.72770, 1.13865, 3.12666),
             (0.55303, -0.71931, -2.96187), (-2.66941, -0.64815, 1.54821),
             (-2.25882, 2.77062, 0.86916), (0.41351, 2.44496, 2.71005)]
    paper_t3 = [-0.81924, 2.58872, -1.20077, -0.40127, -0.24062, 2.10928]
    paper_t4 = [-2.42719, -2.66043, -1.96316, 0.56971, -0.01687, -2.79537]
    # sanity: ground pivots of the URDF match the paper geometry
    j = m["joints"]
    check(np.allclose(j["joint6"]["xyz"][:2], [-a0 * math.cos(g0), a0 * math.sin(g0)], atol=1e-15), "joint6 origin")
    check(np.allclose(j["joint5"]["xyz"][:2], [-b0, 0]), "joint5 origin")
    sols = []
    print("  #   theta1       theta2       theta3       theta4       theta5       theta6       theta7      |F|      closure  d(given)")
    for i, (t1, t2, t7) in enumerate(given):
        # initial guesses for t3, t4, t5 from each loop individually
        p1 = l7 * u(t7) + a2 * u(t2) + a1 * u(t1) + B0
        t5 = math.atan2(p1[1], p1[0])
        p3 = l7 * u(t7) + a2 * u(t2) + b1 * R(g1) @ u(t1) - c6 * R(eta6) @ u(t6) + w0
        t3 = math.atan2(p3[1], p3[0])
        p4 = l7 * u(t7) + b2 * R(g2) @ u(t2) - b6 * u(t6) + w0
        t4 = math.atan2(p4[1], p4[0])
        x, res = newton(eqs, [t1, t2, t3, t4, t5, t7])
        x = np.array([wrap(v) for v in x])
        t1s, t2s, t3s, t4s, t5s, t7s = x
        check(res < 1e-10, f"butterfly #{i+1}: Newton residual {res:.2e}")
        dgiven = max(abs(wrap(t1s - t1)), abs(wrap(t2s - t2)), abs(wrap(t7s - t7)))
        check(dgiven < 5e-4, f"butterfly #{i+1}: solution drifted {dgiven:.2e} from given angles")
        check(abs(wrap(t3s - paper_t3[i])) < 5e-4, f"butterfly #{i+1}: theta3 {t3s:.5f} != paper {paper_t3[i]}")
        check(abs(wrap(t4s - paper_t4[i])) < 5e-4, f"butterfly #{i+1}: theta4 {t4s:.5f} != paper {paper_t4[i]}")
        th = {1: t1s, 2: t2s, 3: t3s, 4: t4s, 5: t5s, 6: t6, 7: t7s}
        q = {"joint7": th[7], "joint2": th[2] - th[7], "joint1": th[1] - th[2], "joint5": th[5],
             "joint6": th[6], "joint3": th[3] - th[6], "joint4": th[4] - th[6]}
        err = check_closure(m, q, f"solution #{i+1}")
        check(err < TIGHT, f"butterfly #{i+1}: closure {err:.2e} not tight")
        print(f"  {i+1}  " + " ".join(f"{th[k]:+.8f}" for k in range(1, 8)) + f"  {res:.1e}  {err:.1e}  {dgiven:.1e}")
        sols.append(th)
    # six distinct solutions
    for a in range(6):
        for b in range(a + 1, 6):
            d = max(abs(wrap(sols[a][k] - sols[b][k])) for k in range(1, 8))
            check(d > 1e-3, f"butterfly solutions #{a+1} and #{b+1} coincide")
    # a non-solution must NOT close (guards against a vacuous check)
    q_bad = {"joint7": 0.3, "joint2": 0.2, "joint1": 0.1, "joint5": 0.0, "joint6": t6, "joint3": 0.0, "joint4": 0.0}
    check(max(loop_errors(m, q_bad).values()) > 1.0, "butterfly: arbitrary configuration unexpectedly closes")
    return sols


# --------------------------------------------------------------------------
# 2. four-bar
# --------------------------------------------------------------------------

def check_four_bar():
    print("[four_bar.urdf]")
    m = load("four_bar.urdf", "four_bar", ["loop_coupler_rocker"])
    a, b, c, d = 1.5, 4.0, 3.5, 4.0
    lens = sorted([a, b, c, d])
    check(lens[0] + lens[3] <= lens[1] + lens[2] and lens[0] == a, "four_bar: not a Grashof crank-rocker")
    K1, K2, K3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    worst, worst_len, n = 0.0, 0.0, 0
    for t2 in np.linspace(-math.pi, math.pi, 73):
        A = math.cos(t2) - K1 - K2 * math.cos(t2) + K3
        Bq = -2 * math.sin(t2)
        C = K1 - (K2 + 1) * math.cos(t2) + K3
        disc = Bq * Bq - 4 * A * C
        check(disc > 0, f"four_bar: no assembly at theta2={t2:.3f}")
        for sgn in (+1, -1):
            t4 = 2 * math.atan2(-Bq + sgn * math.sqrt(disc), 2 * A)
            pa = a * u(t2)
            pb = np.array([d, 0.0]) + c * u(t4)
            worst_len = max(worst_len, abs(np.linalg.norm(pb - pa) - b))
            t3 = math.atan2(*(pb - pa)[::-1])
            q = {"crank_joint": t2, "coupler_joint": t3 - t2, "rocker_joint": t4}
            worst = max(worst, check_closure(m, q, f"theta2={t2:.3f} branch {sgn:+d}"))
            n += 1
    check(worst_len < 1e-9, f"four_bar: Freudenstein coupler length error {worst_len:.2e}")
    check(worst < TIGHT, f"four_bar: closure {worst:.2e}")
    print(f"  {n} configurations (73 crank angles x 2 branches): max closure {worst:.1e}, "
          f"max |AB|-b {worst_len:.1e}")


# --------------------------------------------------------------------------
# 3. slider-crank
# --------------------------------------------------------------------------

def check_slider_crank():
    print("[slider_crank.urdf]")
    m = load("slider_crank.urdf", "slider_crank", ["loop_rod_slider"])
    r, l = 1.0, 3.0
    lim = m["joints"]["slider_joint"]["limit"]
    check(m["joints"]["slider_joint"]["type"] == "prismatic", "slider_joint not prismatic")
    check(np.allclose(m["joints"]["slider_joint"]["axis"], [1, 0, 0]), "slider axis")
    check(lim["lower"] == 0 and lim["upper"] == 5, "slider limits")
    worst, n = 0.0, 0
    for t in np.linspace(-math.pi, math.pi, 73):
        x = r * math.cos(t) + math.sqrt(l * l - (r * math.sin(t)) ** 2)
        check(lim["lower"] <= x <= lim["upper"], f"slider x={x} outside limits")
        phi = math.atan2(-r * math.sin(t), x - r * math.cos(t))
        q = {"crank_joint": t, "rod_joint": phi - t, "slider_joint": x}
        worst = max(worst, check_closure(m, q, f"t={t:.3f}"))
        n += 1
    check(worst < TIGHT, f"slider_crank: closure {worst:.2e}")
    # wrong slider position must not close
    q = {"crank_joint": 0.4, "rod_joint": -0.4, "slider_joint": 1.0}
    check(max(loop_errors(m, q).values()) > 0.1, "slider_crank: wrong configuration closes")
    print(f"  {n} crank angles: max closure {worst:.1e}, slider stroke x in [{l - r:g}, {l + r:g}] "
          f"within limit [{lim['lower']:g}, {lim['upper']:g}]")


# --------------------------------------------------------------------------
# 4. Watt I six-bar
# --------------------------------------------------------------------------

def check_watt():
    print("[watt_six_bar.urdf]")
    m = load("watt_six_bar.urdf", "watt_six_bar", ["loop_coupler_rocker", "loop_bar5_bar6"])
    J = m["joints"]
    L = m["loops"]
    check(sorted(m["links"]) == sorted(["ground", "crank", "coupler", "rocker", "bar5", "bar6"]), "watt links")
    # read dimensions from the file, then check them against the documented design
    a = J["coupler_joint"]["xyz"][0]
    d = J["rocker_joint"]["xyz"][0]
    b = L["loop_coupler_rocker"]["predecessor"]["xyz"][0]
    c = L["loop_coupler_rocker"]["successor"]["xyz"][0]
    P = J["bar5_joint"]["xyz"][:2]
    Q = J["bar6_joint"]["xyz"][:2]
    l5 = L["loop_bar5_bar6"]["predecessor"]["xyz"][0]
    l6 = L["loop_bar5_bar6"]["successor"]["xyz"][0]
    check((a, b, c, d, l5, l6) == (1, 4, 3, 4, 3, 2.8) and np.allclose(P, [2, 1.5]) and np.allclose(Q, [1.5, -1.5]),
          "watt: dimensions differ from documented design")
    # link degrees: coupler and rocker ternary and adjacent (Watt chain)
    deg = {ln: 0 for ln in m["links"]}
    for j in J.values():
        deg[j["parent"]] += 1
        deg[j["child"]] += 1
    for lp in L.values():
        deg[lp["predecessor"]["link"]] += 1
        deg[lp["successor"]["link"]] += 1
    check(deg == {"ground": 2, "crank": 2, "coupler": 3, "rocker": 3, "bar5": 2, "bar6": 2},
          f"watt: link degrees {deg}")
    lens = sorted([a, b, c, d])
    check(lens[0] + lens[3] <= lens[1] + lens[2] and lens[0] == a, "watt: loop 1 not a Grashof crank-rocker")
    O4 = np.array([d, 0.0])
    worst = 0.0
    min_h2 = {+1: math.inf, -1: math.inf}
    pq = {+1: [math.inf, -math.inf], -1: [math.inf, -math.inf]}
    ok_angles = 0
    for t2 in np.radians(np.arange(360)):
        pa = a * u(t2)
        pts, h2 = circle_intersections(pa, b, O4, c)
        check(pts is not None, f"watt: loop 1 fails at {math.degrees(t2):.0f} deg")
        if pts is None:
            continue
        all_ok = True
        for br1, pb in zip((+1, -1), pts):
            t3 = math.atan2(*(pb - pa)[::-1])
            t4 = math.atan2(*(pb - O4)[::-1])
            Pw = pa + R(t3) @ P
            Qw = O4 + R(t4) @ Q
            dist = np.linalg.norm(Pw - Qw)
            pq[br1][0] = min(pq[br1][0], dist)
            pq[br1][1] = max(pq[br1][1], dist)
            pts2, h2b = circle_intersections(Pw, l5, Qw, l6)
            min_h2[br1] = min(min_h2[br1], h2b)
            if not check(pts2 is not None, f"watt: loop 2 fails at {math.degrees(t2):.0f} deg, loop-1 branch {br1:+d}"):
                all_ok = False
                continue
            for E in pts2:
                t5 = math.atan2(*(E - Pw)[::-1])
                t6 = math.atan2(*(E - Qw)[::-1])
                q = {"crank_joint": t2, "coupler_joint": t3 - t2, "rocker_joint": t4,
                     "bar5_joint": t5 - t3, "bar6_joint": t6 - t4}
                worst = max(worst, check_closure(m, q, f"{math.degrees(t2):.0f} deg"))
        ok_angles += all_ok
    check(worst < TIGHT, f"watt: closure {worst:.2e}")
    print(f"  dims: d={d:g} a={a:g} b={b:g} c={c:g}  P={P.tolist()} (coupler)  Q={Q.tolist()} (rocker)  l5={l5:g} l6={l6:g}")
    print(f"  {ok_angles}/360 crank angles: loop 1 (both branches) and loop 2 (both branches) real; "
          f"max closure {worst:.1e} over {ok_angles*4} configurations")
    for br in (+1, -1):
        print(f"  loop-1 branch {br:+d}: |PQ| in [{pq[br][0]:.4f}, {pq[br][1]:.4f}] vs "
              f"[{abs(l5-l6):g}, {l5+l6:g}], min loop-2 h^2 = {min_h2[br]:.4f}")


def main():
    sols = check_double_butterfly()
    check_four_bar()
    check_slider_crank()
    check_watt()
    if FAILURES:
        print(f"\n{len(FAILURES)} FAILURE(S)")
        return 1
    print("\nall fixture checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
