#!/usr/bin/env python3
"""Reference forward kinematics of a 6-6 Stewart-Gough platform URDF (urdf/stewart_6_6.urdf by default): EVERY assembly, by homotopy.

No interval solver and no linkspace code. Geometry is read from the URDF (scripts/dev/urdf_mp.py).

Formulation (Study / soma coordinates, Wampler 1996): unknowns x = (e, g) in C^8, quaternions;
the platform maps a point p of its frame to  (e p e' + g e') / (e e')  (' = quaternion conjugate),
i.e. rotation R(e) and translation t = g e' / (e e'), whose scalar part vanishes on the Study
quadric e.g = 0. Leg i (base ball b_i, platform ball p_i, length L_i) is
    |e p_i + g - b_i e|^2 = L_i^2 |e|^2,
a quadratic form x^T Q_i x = 0 (bilinear dot products, so it stays polynomial for complex data).
With the Study quadric and a random complex affine chart c.x = 1: 8 equations in 8 unknowns whose
isolated solutions, for generic data, are the 40 assemblies (e = 0 only gives a positive-
dimensional extraneous set, which homotopy paths from isolated solutions never reach).

Method:
 1. Monodromy: random complex data P0 (base points, platform points, squared lengths) built
    around one random complex (e, g) on the Study quadric, which is thus a solution. Loops
    P0 -> P1 -> P2 -> P0 over random complex triangles, tracking every known solution; new
    endpoints join the set. Stop when the count has not grown for STALL loops (it must be 40).
 2. Parameter homotopy from P0 to the real data of the URDF and the leg lengths, along
    P0 -> gamma-point -> target (a random complex intermediate point: the gamma trick for a
    parameter homotopy), predictor (RK4) - corrector (Newton), adaptive step, all 40 paths.
 3. Endpoints refined by Newton in mpmath at 60 digits; real ones kept (imaginary part of R
    and t below 1e-8 relative); each verified by its leg residuals at 50 digits.
 4. Cross-check: the whole computation (monodromy, chart, path) is repeated with a second
    seed; both must give 40 distinct solutions and the same real set.

Run: python3 scripts/dev/stewart_fk.py   (writes tests/data/stewart_6_6_fk.json; numpy, mpmath)
     python3 scripts/dev/stewart_fk.py --urdf urdf/stewart_40.urdf --out tests/data/stewart_40_fk.json \
         --case NAME=L1,...,L6   (the stated leg lengths of another platform)
"""
import argparse
import json
import os
import sys
import time

import mpmath as mp
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
from urdf_mp import Urdf, rpy_matrix  # noqa: E402

N_SOLUTIONS = 40
STALL = 6           # monodromy loops without a new solution before stopping
REAL_TOL = 1e-8     # relative imaginary part below which a solution is real

# ----------------------------------------------------------------------------------------------
# quaternion multiplication matrices: q*r = Lm(q) r, r*q = Rm(q) r
# ----------------------------------------------------------------------------------------------


def Lm(q):
    w, x, y, z = q
    return np.array([[w, -x, -y, -z], [x, w, -z, y], [y, z, w, -x], [z, -y, x, w]])


def Rm(q):
    w, x, y, z = q
    return np.array([[w, -x, -y, -z], [x, w, z, -y], [y, -z, w, x], [z, y, -x, w]])


UNIT = np.eye(3)
LK = np.array([Lm([0, *UNIT[k]]) for k in range(3)], dtype=complex)    # (3,4,4)
RK = np.array([Rm([0, *UNIT[k]]) for k in range(3)], dtype=complex)
RTL = np.einsum("kba,lbc->klac", RK, LK)                                # Rk^T Ll
S_STUDY = np.zeros((8, 8), dtype=complex)
S_STUDY[:4, 4:] = np.eye(4) / 2
S_STUDY[4:, :4] = np.eye(4) / 2


def quads(b, p, L2):
    """Q (..., 6, 8, 8) from b, p (..., 6, 3) and L2 (..., 6)."""
    A = np.einsum("...k,kac->...ac", p, RK) - np.einsum("...k,kac->...ac", b, LK)
    B = np.einsum("...k,...l,klac->...ac", p, b, RTL)
    k = (p * p).sum(-1) + (b * b).sum(-1) - L2
    shape = b.shape[:-1]
    Q = np.zeros(shape + (8, 8), dtype=complex)
    Q[..., :4, :4] = k[..., None, None] * np.eye(4) - B - np.swapaxes(B, -1, -2)
    Q[..., 4:, :4] = A
    Q[..., :4, 4:] = np.swapaxes(A, -1, -2)
    Q[..., 4:, 4:] = np.eye(4)
    return Q


def dquads(b, p, L2, db, dp, dL2):
    """Derivative of quads along (db, dp, dL2)."""
    A = np.einsum("...k,kac->...ac", dp, RK) - np.einsum("...k,kac->...ac", db, LK)
    B = np.einsum("...k,...l,klac->...ac", dp, b, RTL) + np.einsum("...k,...l,klac->...ac", p, db, RTL)
    k = 2 * (p * dp).sum(-1) + 2 * (b * db).sum(-1) - dL2
    shape = b.shape[:-1]
    Q = np.zeros(shape + (8, 8), dtype=complex)
    Q[..., :4, :4] = k[..., None, None] * np.eye(4) - B - np.swapaxes(B, -1, -2)
    Q[..., 4:, :4] = A
    Q[..., :4, 4:] = np.swapaxes(A, -1, -2)
    return Q


class Params:
    """A point of parameter space: b (6,3), p (6,3), L2 (6), all complex."""

    def __init__(self, b, p, L2):
        self.b, self.p, self.L2 = np.asarray(b, complex), np.asarray(p, complex), np.asarray(L2, complex)

    def vec(self):
        return np.concatenate([self.b.ravel(), self.p.ravel(), self.L2])

    @staticmethod
    def from_vec(v):
        return Params(v[:18].reshape(6, 3), v[18:36].reshape(6, 3), v[36:42])


class System:
    def __init__(self, chart):
        self.c = np.asarray(chart, complex)

    def eval(self, X, Pv, Dv=None):
        """X (n,8), Pv (n,42) parameter vectors; returns F (n,8), J (n,8,8), Fs (n,8) (if Dv)."""
        b, p, L2 = Pv[:, :18].reshape(-1, 6, 3), Pv[:, 18:36].reshape(-1, 6, 3), Pv[:, 36:42]
        Q = quads(b, p, L2)
        QX = np.einsum("nijk,nk->nij", Q, X)
        F = np.empty((X.shape[0], 8), complex)
        F[:, :6] = np.einsum("nij,nj->ni", QX, X)
        SX = X @ S_STUDY.T
        F[:, 6] = (SX * X).sum(-1)
        F[:, 7] = X @ self.c - 1
        J = np.empty((X.shape[0], 8, 8), complex)
        J[:, :6, :] = 2 * QX
        J[:, 6, :] = 2 * SX
        J[:, 7, :] = self.c
        if Dv is None:
            return F, J, None
        db, dp, dL2 = Dv[:, :18].reshape(-1, 6, 3), Dv[:, 18:36].reshape(-1, 6, 3), Dv[:, 36:42]
        dQ = dquads(b, p, L2, db, dp, dL2)
        Fs = np.zeros((X.shape[0], 8), complex)
        Fs[:, :6] = np.einsum("nijk,nj,nk->ni", dQ, X, X)
        return F, J, Fs


def track(system, X0, Pa, Pb, tol=1e-9, h0=0.02, hmin=1e-12, max_steps=20000, hmax=0.05):
    """Track solutions X0 (n,8) of F(.;Pa)=0 along the segment Pa->Pb (parameter vectors).
    Returns (X (n,8), ok (n,) bool)."""
    n = X0.shape[0]
    X = X0.copy()
    s = np.zeros(n)
    h = np.full(n, h0)
    active = np.ones(n, bool)
    ok = np.zeros(n, bool)
    D = (Pb - Pa)[None, :]

    def field(Xa, sa):
        Pv = Pa[None, :] + sa[:, None] * D
        F, J, Fs = system.eval(Xa, Pv, np.repeat(D, len(sa), 0))
        try:
            return -np.linalg.solve(J, Fs[..., None])[..., 0]
        except np.linalg.LinAlgError:
            return np.full_like(Xa, np.nan)

    steps = 0
    while active.any() and steps < max_steps:
        steps += 1
        idx = np.nonzero(active)[0]
        Xa, sa, ha = X[idx], s[idx], np.minimum(h[idx], 1 - s[idx])
        k1 = field(Xa, sa)
        k2 = field(Xa + ha[:, None] / 2 * k1, sa + ha / 2)
        k3 = field(Xa + ha[:, None] / 2 * k2, sa + ha / 2)
        k4 = field(Xa + ha[:, None] * k3, sa + ha)
        Y = Xa + ha[:, None] / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        s1 = sa + ha
        Pv = Pa[None, :] + s1[:, None] * D
        good = np.isfinite(Y).all(1)
        norms = []
        for it in range(3):
            F, J, _ = system.eval(np.where(good[:, None], Y, 0), Pv)
            with np.errstate(all="ignore"):
                try:
                    dY = np.linalg.solve(J, F[..., None])[..., 0]
                except np.linalg.LinAlgError:
                    dY = np.full_like(Y, np.nan)
            Y = Y - dY
            nrm = np.linalg.norm(dY, axis=1) / (1 + np.linalg.norm(Y, axis=1))
            norms.append(nrm)
            good &= np.isfinite(nrm)
        # accept: predictor close (no path jumping), corrector converged (last update at the
        # rounding floor or quadratically smaller than the previous one)
        conv = good & (norms[0] < 1e-6) & (norms[1] < 1e-6) & (norms[2] < np.maximum(tol, 1e-1 * norms[1]))
        conv &= np.isfinite(Y).all(1)
        acc = idx[conv]
        rej = idx[~conv]
        X[acc] = Y[conv]
        s[acc] = s1[conv]
        h[acc] = np.minimum(h[acc] * 1.6, hmax)
        h[rej] = h[rej] / 2
        done = acc[s[acc] >= 1 - 1e-15]
        ok[done] = True
        active[done] = False
        dead = rej[h[rej] < hmin]
        active[dead] = False
    return X, ok


def newton_np(system, X, Pv, iters=6):
    P = np.repeat(Pv[None, :], X.shape[0], 0)
    for _ in range(iters):
        F, J, _ = system.eval(X, P)
        X = X - np.linalg.solve(J, F[..., None])[..., 0]
    F, J, _ = system.eval(X, P)
    return X, np.linalg.norm(F, axis=1), np.linalg.cond(J)


def distinct(X, tol=1e-6):
    keep = []
    for x in X:
        if not any(np.linalg.norm(x - y) <= tol * (1 + np.linalg.norm(x)) for y in keep):
            keep.append(x)
    return np.array(keep)


def random_params(rng, scale=1.0):
    z = lambda *s: (rng.standard_normal(s) + 1j * rng.standard_normal(s)) * scale
    return z(42)


def start_system(rng):
    """Random complex data with one known solution on the Study quadric."""
    chart = rng.standard_normal(8) + 1j * rng.standard_normal(8)
    e = rng.standard_normal(4) + 1j * rng.standard_normal(4)
    g = rng.standard_normal(4) + 1j * rng.standard_normal(4)
    g = g - (e @ g) / (e @ e) * e
    x = np.concatenate([e, g])
    x = x / (chart @ x)
    P = Params(rng.standard_normal((6, 3)) + 1j * rng.standard_normal((6, 3)),
               rng.standard_normal((6, 3)) + 1j * rng.standard_normal((6, 3)), np.zeros(6))
    F0 = np.einsum("ijk,j,k->i", quads(P.b, P.p, P.L2), x, x)
    P.L2 = F0 / (x[:4] @ x[:4])   # F = F0 - L2 e.e
    system = System(chart)
    F, _, _ = system.eval(x[None, :], P.vec()[None, :])
    assert np.abs(F).max() < 1e-12, F
    return system, P.vec(), x


def monodromy(system, P0, x0, rng, log):
    sols = np.array([x0])
    stall, loops = 0, 0
    while stall < STALL:
        loops += 1
        P1, P2 = random_params(rng), random_params(rng)
        X = sols
        okall = np.ones(len(X), bool)
        for a, b in ((P0, P1), (P1, P2), (P2, P0)):
            X, ok = track(system, X, a, b)
            okall &= ok
        X, res, cond = newton_np(system, X[okall], P0)
        X = X[(res < 1e-10) & np.isfinite(res)]
        before = len(sols)
        sols = distinct(np.concatenate([sols, X]))
        stall = stall + 1 if len(sols) == before else 0
        log(f"  monodromy loop {loops}: {len(sols)} solutions ({int((~okall).sum())} paths failed)")
        if loops > 60:
            break
    return sols, loops


# ----------------------------------------------------------------------------------------------
# the mechanism from the URDF
# ----------------------------------------------------------------------------------------------


class Stewart:
    def __init__(self, path):
        u = Urdf(path)
        self.u = u
        fl = [j for j in u.joints.values() if j["type"] == "floating" and j["parent"] == u.root]
        assert len(fl) == 1
        self.platform = fl[0]["child"]
        self.legs = []
        for i in range(1, 7):
            leg = u.joints[f"leg{i}"]
            assert leg["type"] == "prismatic"
            cyl, rod = leg["parent"], leg["child"]
            ball = u.parent_joint[cyl]
            assert ball["type"] == "spherical" and ball["parent"] == u.root
            base = u.link_frame(cyl, {}).t           # base ball centre (root frame)
            loop = u.loops[f"leg{i}_top"]
            assert loop["type"] == "spherical" and loop["predecessor"] == rod and loop["successor"] == self.platform
            on_rod = loop["predecessor_origin"].t
            # top ball in the cylinder frame: origin.t + origin.R (q axis + on_rod); offset must be 0
            n = mp.sqrt(sum(a * a for a in leg["axis"]))
            axis = leg["origin"].R * mp.matrix([a / n for a in leg["axis"]])
            at0 = leg["origin"].t + leg["origin"].R * on_rod
            assert mp.norm(at0) < mp.mpf(10) ** -40, "ball-to-ball length must equal the prismatic value"
            self.legs.append({"name": leg["name"], "base": base, "top": loop["successor_origin"].t,
                              "limits": leg["limits"], "axis_cyl": axis})
        self.b = np.array([[float(l["base"][k]) for k in range(3)] for l in self.legs])
        self.p = np.array([[float(l["top"][k]) for k in range(3)] for l in self.legs])

    def lengths(self, R, t):
        """Leg lengths (mp) of a pose given as mp rotation matrix and translation."""
        return [mp.norm(R * l["top"] + t - l["base"]) for l in self.legs]

    def params(self, L):
        """Parameter vector (complex128) for leg lengths L (mp or float)."""
        return Params(self.b, self.p, np.array([float(mp.mpf(x) ** 2) for x in L])).vec()


# ----------------------------------------------------------------------------------------------
# refinement and read-out in mpmath
# ----------------------------------------------------------------------------------------------


def qmul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return [w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2]


def conj(q):
    return [q[0], -q[1], -q[2], -q[3]]


def bdot(a, b):
    return sum(x * y for x, y in zip(a, b))


def mp_system(st, L, chart):
    b = [[l["base"][k] for k in range(3)] for l in st.legs]
    p = [[l["top"][k] for k in range(3)] for l in st.legs]
    L2 = [mp.mpf(x) ** 2 for x in L]
    c = [mp.mpc(z.real, z.imag) for z in chart]

    def F(x):
        e, g = x[:4], x[4:]
        out = []
        for i in range(6):
            v = [u + gg - w for u, gg, w in zip(qmul(e, [0] + p[i]), g, qmul([0] + b[i], e))]
            out.append(bdot(v, v) - L2[i] * bdot(e, e))
        out.append(bdot(e, g))
        out.append(bdot(c, x) - 1)
        return out
    return F


def mp_newton(F, x, iters=12):
    x = [mp.mpc(v.real, v.imag) for v in x]
    h = mp.mpf(10) ** (-mp.mp.dps // 2)
    for _ in range(iters):
        f = F(x)
        # Jacobian by complex-step-free central differences would lose digits: use exact
        # derivatives of quadratics via polarisation: J v = (F(x+hv) - F(x-hv)) / (2h), exact
        # for quadratic F up to rounding.
        J = mp.matrix(8, 8)
        for j in range(8):
            xp = list(x)
            xm = list(x)
            xp[j] += h
            xm[j] -= h
            fp, fm = F(xp), F(xm)
            for i in range(8):
                J[i, j] = (fp[i] - fm[i]) / (2 * h)
        dx = mp.lu_solve(J, mp.matrix(f))
        x = [x[k] - dx[k] for k in range(8)]
        if mp.norm(dx) < mp.mpf(10) ** (-mp.mp.dps + 8):
            break
    return x, max(abs(v) for v in F(x))


def pose_of(x):
    """R (3x3), t, quaternion of an (e, g) solution, complex mp."""
    e, g = x[:4], x[4:]
    ee = bdot(e, e)
    R = mp.matrix(3, 3)
    for k in range(3):
        col = qmul(qmul(e, [0] + [1 if m == k else 0 for m in range(3)]), conj(e))
        for r in range(3):
            R[r, k] = col[r + 1] / ee
    tq = qmul(g, conj(e))
    t = mp.matrix([tq[1] / ee, tq[2] / ee, tq[3] / ee])
    q = [v / mp.sqrt(ee) for v in e]
    return R, t, q, tq[0] / ee


def solve_case(st, L, runs, log):
    """Track every start solution of each run to leg lengths L; returns per-run endpoint lists."""
    results = []
    for run in runs:
        system, P0, sols, rng = run["system"], run["P0"], run["sols"], run["rng_target"]
        Pt = st.params(L)
        Pg = random_params(rng, scale=0.5) + Pt    # gamma point
        X, ok1 = track(system, sols, P0, Pg)
        X, ok2 = track(system, X, Pg, Pt)
        ok = ok1 & ok2
        for _ in range(6):
            # a failed path, or one whose endpoint another path also reached (path jumping), is
            # tracked again through another gamma point with shorter steps
            bad = ~ok
            for i in range(len(X)):
                for j in range(i + 1, len(X)):
                    if ok[i] and ok[j] and np.linalg.norm(X[i] - X[j]) <= 1e-7 * (1 + np.linalg.norm(X[i])):
                        bad[i] = bad[j] = True
            if not bad.any():
                break
            bad = np.nonzero(bad)[0]
            Pg2 = random_params(rng, scale=0.5) + Pt
            Y, o1 = track(system, sols[bad], P0, Pg2, hmax=0.02)
            Y, o2 = track(system, Y, Pg2, Pt, hmax=0.02)
            X[bad], ok[bad] = Y, o1 & o2
        X, res, cond = newton_np(system, X, Pt)
        results.append({"X": X, "ok": ok, "res": res, "cond": cond, "system": system})
    return results


def readout(st, L, X, system, log, dps=60):
    """Refine endpoints in mp, classify real ones, compute residuals."""
    mp.mp.dps = dps
    F = mp_system(st, L, system.c)
    out = []
    for x in X:
        xr, res = mp_newton(F, x)
        R, t, q, scal = pose_of(xr)
        mag = max([abs(v) for v in list(R) + list(t)])
        imag = max([abs(mp.im(v)) for v in list(R) + list(t)])
        out.append({"x": xr, "R": R, "t": t, "q": q, "res": res, "imag_rel": imag / (1 + mag),
                    "real": imag / (1 + mag) < REAL_TOL})
    return out


def real_pose(sol):
    R = mp.matrix(3, 3)
    for i in range(3):
        for j in range(3):
            R[i, j] = mp.re(sol["R"][i, j])
    t = mp.matrix([mp.re(v) for v in sol["t"]])
    # quaternion from e/sqrt(e.e), made real with w >= 0 (or first nonzero > 0)
    q = [mp.re(v) for v in sol["q"]]
    imag_q = max(abs(mp.im(v)) for v in sol["q"])
    if imag_q > max(abs(v) for v in q):   # sqrt picked the imaginary branch
        q = [mp.im(v) for v in sol["q"]]
    n = mp.sqrt(sum(v * v for v in q))
    q = [v / n for v in q]
    lead = next(v for v in q if abs(v) > mp.mpf(10) ** -20)
    if lead < 0:
        q = [-v for v in q]
    return R, t, q


def rpy_of(R):
    pitch = mp.asin(-R[2, 0])
    roll = mp.atan2(R[2, 1], R[2, 2])
    yaw = mp.atan2(R[1, 0], R[0, 0])
    return [roll, pitch, yaw]


def fl(v):
    return [float(x) for x in v]


def generated_cases(st, runs, count, log):
    """from_pose, many_real, near_singular: leg lengths made from poses of the platform."""
    cases = []
    # case 1: from a known pose
    pose1 = {"xyz": ["0.0231", "-0.0417", "0.6538"], "rpy": ["0.0712", "-0.0535", "0.1289"]}
    R1 = rpy_matrix(*[mp.mpf(v) for v in pose1["rpy"]])
    t1 = mp.matrix([mp.mpf(v) for v in pose1["xyz"]])
    L1 = [mp.nstr(x, 10) for x in st.lengths(R1, t1)]
    cases.append({"name": "from_pose", "L": L1, "generating_pose": pose1,
                  "note": "leg lengths of the generating pose rounded to 10 significant digits; the solutions are those of the rounded lengths"})

    # case 2: search poses for many real assemblies
    rng = np.random.default_rng(4242)
    best = None
    tried = 0
    while tried < int(os.environ.get("STEWART_POSES", "80")):
        tried += 1
        xyz = [rng.uniform(-0.12, 0.12), rng.uniform(-0.12, 0.12), rng.uniform(0.45, 0.8)]
        rpy = [rng.uniform(-0.45, 0.45), rng.uniform(-0.45, 0.45), rng.uniform(-0.7, 0.7)]
        xyz_s = [f"{v:.4f}" for v in xyz]
        rpy_s = [f"{v:.4f}" for v in rpy]
        R = rpy_matrix(*[mp.mpf(v) for v in rpy_s])
        t = mp.matrix([mp.mpf(v) for v in xyz_s])
        Ls = st.lengths(R, t)
        if any(not (l["limits"][0] <= x <= l["limits"][1]) for l, x in zip(st.legs, Ls)):
            continue
        L = [mp.nstr(x, 7) for x in Ls]
        n, nreal = count(L)
        log(f"  pose {tried}: {n} complex, {nreal} real")
        if n == N_SOLUTIONS and (best is None or nreal > best[0]):
            best = (nreal, L, {"xyz": xyz_s, "rpy": rpy_s})
    log(f"best: {best[0]} real")
    cases.append({"name": "many_real", "L": best[1], "generating_pose": best[2],
                  "note": f"the pose with the most real assemblies among {tried} random poses (seed 4242); leg lengths rounded to 7 significant digits"})

    # case 3: near a singularity, two real assemblies close together
    La = [mp.mpf(x) for x in best[1]]
    Lb = [mp.mpf(x) for x in L1]
    na = count(best[1])[1]
    nb = count(L1)[1]
    lo, hi = mp.mpf(0), mp.mpf(1)
    near = None
    if na != nb:
        nlo = na
        for _ in range(30):
            mid = (lo + hi) / 2
            Lm_ = [mp.nstr(a + mid * (b - a), 12) for a, b in zip(La, Lb)]
            c = count(Lm_)[1]
            if c == nlo:
                lo = mid
            else:
                hi = mid
        # on the side with more real solutions, at distance ~1e-6 of the merge (in lambda)
        more_lo = count([mp.nstr(a + lo * (b - a), 12) for a, b in zip(La, Lb)])[1] >= \
            count([mp.nstr(a + hi * (b - a), 12) for a, b in zip(La, Lb)])[1]
        lam = lo - mp.mpf("1e-6") if more_lo else hi + mp.mpf("1e-6")
        near = [mp.nstr(a + lam * (b - a), 10) for a, b in zip(La, Lb)]
        cases.append({"name": "near_singular", "L": near, "stability_test": True,
                      "lambda": float(lam), "lambda_merge": float((lo + hi) / 2),
                      "note": "STABILITY TEST: on the segment L(lambda) = (1-lambda) L[many_real] + lambda L[from_pose], "
                              "two real assemblies merge (a singularity of the leg Jacobian) at lambda_merge; these lengths "
                              "(lambda about 1e-6 from it, rounded to 10 significant digits) keep two real assemblies close together"})

    return cases


def arguments():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--urdf", default="urdf/stewart_6_6.urdf", help="the platform (path from the repository root)")
    ap.add_argument("--out", default="tests/data/stewart_6_6_fk.json", help="the reference written (path from the repository root)")
    ap.add_argument("--case", action="append", default=[], metavar="NAME=L1,...,L6",
                    help="a case of stated leg lengths (decimal strings); without any, the cases from_pose, many_real, near_singular are made")
    ap.add_argument("--note", default="leg lengths as stated in the URDF's comment", help="the note of the --case cases")
    return ap.parse_args()


def main():
    args = arguments()
    t_start = time.time()
    log = lambda m: print(f"[{time.time() - t_start:7.1f}s] {m}", flush=True)
    mp.mp.dps = 50
    st = Stewart(os.path.join(REPO, args.urdf))
    log(f"read {len(st.legs)} legs from {args.urdf}")

    # two independent runs (seeds): monodromy start systems
    runs = []
    for seed in (20240512, 31337):
        rng = np.random.default_rng(seed)
        system, P0, x0 = start_system(rng)
        log(f"seed {seed}: monodromy")
        sols, loops = monodromy(system, P0, x0, rng, log)
        log(f"seed {seed}: {len(sols)} solutions after {loops} loops")
        assert len(sols) == N_SOLUTIONS, len(sols)
        runs.append({"seed": seed, "system": system, "P0": P0, "sols": sols, "loops": loops,
                     "rng_target": np.random.default_rng(seed + 1)})

    def count(L, runs_=runs[:1]):
        r = solve_case(st, L, runs_, log)[0]
        good = r["ok"] & (r["res"] < 1e-8)
        X = distinct(r["X"][good], 1e-7)
        # quick float real test on (R, t)
        nreal = 0
        for x in X:
            e, g = x[:4], x[4:]
            ee = e @ e
            tq = np.array(qmul(list(g), conj(list(e)))) / ee
            sc = np.sqrt(ee)
            en = e / sc
            if np.abs(en.imag).max() < 1e-6 and np.abs(tq.imag).max() < 1e-6:
                nreal += 1
        return len(X), nreal

    cases = []
    for spec in args.case:
        name, lengths = spec.split("=", 1)
        L = lengths.split(",")
        assert len(L) == len(st.legs), spec
        cases.append({"name": name, "L": L, "note": args.note})
    if not cases:
        cases = generated_cases(st, runs, count, log)
    out_cases = []
    for case in cases:
        log(f"case {case['name']}: tracking 40 paths for each of {len(runs)} runs")
        L = case["L"]
        res = solve_case(st, L, runs, log)
        per_run = []
        for r, run in zip(res, runs):
            X = r["X"]
            assert r["ok"].all(), f"{int((~r['ok']).sum())} paths failed"
            D = distinct(X, 1e-7)
            assert len(D) == N_SOLUTIONS, f"only {len(D)} distinct endpoints"
            sols = readout(st, L, X, r["system"], log)
            assert max(s["res"] for s in sols) < mp.mpf(10) ** -40
            per_run.append(sols)
            log(f"  seed {run['seed']}: {len(D)} distinct, {sum(s['real'] for s in sols)} real, "
                f"max path-end cond {np.max(r['cond']):.2e}")
        # compare runs: same real poses
        mp.mp.dps = 50
        reals = [[real_pose(s) for s in sols if s["real"]] for sols in per_run]
        assert len(reals[0]) == len(reals[1]), (len(reals[0]), len(reals[1]))
        maxdiff = mp.mpf(0)
        for R, t, q in reals[0]:
            d = min(mp.norm(t - t2) + mp.mnorm(R - R2, 1) for R2, t2, q2 in reals[1])
            maxdiff = max(maxdiff, d)
        assert maxdiff < mp.mpf(10) ** -25, maxdiff
        # complex sets too (via R, t, chart independent)
        cmax = mp.mpf(0)
        for s in per_run[0]:
            d = min(mp.norm(s["t"] - s2["t"]) + mp.mnorm(s["R"] - s2["R"], 1) for s2 in per_run[1])
            cmax = max(cmax, d)
        assert cmax < mp.mpf(10) ** -20, cmax
        solutions = []
        for R, t, q in sorted(reals[0], key=lambda v: (float(v[1][2]), float(v[1][0]))):
            lens = st.lengths(R, t)
            resid = [lens[i] - mp.mpf(L[i]) for i in range(6)]
            assert max(abs(v) for v in resid) < mp.mpf(10) ** -40
            orth = mp.mnorm(R.T * R - mp.eye(3), 1)
            assert orth < mp.mpf(10) ** -40 and abs(mp.det(R) - 1) < mp.mpf(10) ** -40
            # leg Jacobian (rows: unit leg direction, moment) smallest singular value, float
            rows = []
            for l in st.legs:
                top = R * l["top"] + t
                u_ = (top - l["base"]) / mp.norm(top - l["base"])
                m_ = R * l["top"]
                rows.append(fl(u_) + fl([m_[1] * u_[2] - m_[2] * u_[1], m_[2] * u_[0] - m_[0] * u_[2], m_[0] * u_[1] - m_[1] * u_[0]]))
            sv = np.linalg.svd(np.array(rows), compute_uv=False)
            solutions.append({
                "platform_position": fl(t),
                "platform_position_40_digits": [mp.nstr(v, 40) for v in t],
                "platform_quaternion_wxyz": fl(q),
                "platform_quaternion_wxyz_40_digits": [mp.nstr(v, 40) for v in q],
                "platform_rotation_matrix": [fl(R[i, :]) for i in range(3)],
                "platform_rpy": fl(rpy_of(R)),
                "joints": {l["name"]: float(mp.mpf(x)) for l, x in zip(st.legs, L)},
                "platform_ball_centres": [fl(R * l["top"] + t) for l in st.legs],
                "leg_residuals": [float(v) for v in resid],
                "leg_jacobian_singular_values": [float(v) for v in sv],
                "within_leg_limits": all(l["limits"][0] <= mp.mpf(x) <= l["limits"][1] for l, x in zip(st.legs, L)),
            })
        # closest pair among real solutions
        closest = None
        for i in range(len(solutions)):
            for j in range(i + 1, len(solutions)):
                a, b = solutions[i], solutions[j]
                d = float(np.linalg.norm(np.array(a["platform_position"]) - np.array(b["platform_position"])) +
                          np.linalg.norm(np.array(a["platform_rotation_matrix"]) - np.array(b["platform_rotation_matrix"])))
                if closest is None or d < closest[0]:
                    closest = (d, i, j)
        entry = {
            "name": case["name"],
            "note": case["note"],
            "leg_lengths": {l["name"]: x for l, x in zip(st.legs, L)},
            "leg_lengths_float": {l["name"]: float(mp.mpf(x)) for l, x in zip(st.legs, L)},
            "squared_leg_lengths_float": {l["name"]: float(mp.mpf(x) ** 2) for l, x in zip(st.legs, L)},
            "complex_solutions": N_SOLUTIONS,
            "real_solutions": len(solutions),
            "cross_check": {
                "seeds": [r["seed"] for r in runs],
                "monodromy_loops": [r["loops"] for r in runs],
                "complex_solutions_per_seed": [N_SOLUTIONS, N_SOLUTIONS],
                "real_solutions_per_seed": [len(x) for x in reals],
                "max_difference_real": float(maxdiff),
                "max_difference_complex": float(cmax),
            },
            "solutions": solutions,
        }
        if "generating_pose" in case:
            entry["generating_pose"] = case["generating_pose"]
        if case.get("stability_test"):
            entry["stability_test"] = True
            entry["lambda"] = case["lambda"]
            entry["lambda_merge"] = case["lambda_merge"]
        if closest is not None:
            entry["closest_real_pair"] = {"indices": [closest[1], closest[2]],
                                          "distance_position_plus_rotation_frobenius": closest[0]}
        out_cases.append(entry)
        log(f"  {case['name']}: 40 complex, {len(solutions)} real; runs agree to {mp.nstr(maxdiff, 3)}")

    out = {
        "mechanism": st.u.name,
        "urdf": args.urdf,
        "generator": "scripts/dev/stewart_fk.py (Study-parameter formulation, monodromy + parameter homotopy in "
                     "complex128, endpoints refined by Newton in mpmath at 60 digits, two independent seeds)",
        "units": "metres, radians",
        "frames": "platform pose = pose of the platform link frame in the root frame (base): position of its origin, "
                  "quaternion [w,x,y,z] (w >= 0), rotation matrix (rows), URDF rpy; a platform ball centre p (platform "
                  "frame, from the URDF) is at R p + t; legs leg1..leg6 are the prismatic joints, their value is the "
                  "ball-to-ball length",
        "leg_length_values": "decimal strings: the references solve exactly these decimals",
        "base_ball_centres": [fl(l["base"]) for l in st.legs],
        "platform_ball_centres_in_platform_frame": [fl(l["top"]) for l in st.legs],
        "cases": out_cases,
        "seconds": round(time.time() - t_start, 1),
    }
    target = os.path.join(REPO, args.out)
    with open(target, "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")
    log(f"wrote {os.path.relpath(target, REPO)}")


if __name__ == "__main__":
    main()
