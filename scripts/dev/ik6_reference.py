#!/usr/bin/env python3
"""Reference inverse kinematics of 6R arms: EVERY solution of a pose, by homotopy.

No interval solver and no linkspace code. Geometry is read from the URDF (scripts/dev/urdf_mp.py).

Chain (as in the URDF): tip = Pre1 R1(q1) Pre2 R2(q2) ... Pre6 R6(q6) Post, Pre_k = the origin
of revolute joint k preceded by the fixed joints since joint k-1, Post = the fixed joints after
joint 6 down the single line of fixed children; R_k(q) = P + cos q Q + sin q S about the unit axis
a (P = a a^T, Q = I - P, S = [a]x). Rotations the file writes as quarter turns up to 1e-5 are
taken as exact quarter turns (as linkspace's default rounding policy does).

Formulation: unknowns x = (c1, s1, ..., c6, s6) in C^12; equations (square, 12 x 12)
    c_k^2 + s_k^2 - 1 = 0                                   (6)
    A = Pre1 R1 Pre2 R2 Pre3 R3 Pre4,  B = G R6^T Pre6^-1 R5^T Pre5^-1 R4^T,  G = T Post^-1
    M = rot(B)^T rot(A):  M12 = M13 = M23 = 0               (3)
    trans(A) - trans(B) = 0                                 (3)
With the circle equations rot(A), rot(B) are (complex) orthogonal, so M is orthogonal and upper
triangular: M = diag(+-1, +-1, +-1) with det 1. The system's solutions are thus the IK solutions
(M = I) and three extraneous branches (M a half-turn about a coordinate axis). The IK branch is
the graph of forward kinematics over the torus, irreducible, so monodromy from an IK solution
stays on it: the extraneous branches are never met (and every endpoint is checked: M = I).

The pose T is the parameter, as (quaternion u in C^4, translation t in C^3), R(u) = N(u)/(u.u)
with N the quadratic quaternion-to-matrix form, orthogonal for every complex u with u.u != 0.

Method (as scripts/dev/stewart_fk.py):
 1. Monodromy: a random complex joint vector gives a pose T0 and one solution; loops
    T0 -> T1 -> T2 -> T0 over random complex poses, tracking every known solution; new endpoints
    join the set; stop when the count has not grown for STALL loops (16 for a general 6R).
 2. Parameter homotopy from T0 (random complex, so the straight segment misses the discriminant)
    to each real target pose, RK4 predictor / Newton corrector, adaptive step; a run in which a
    path fails or two paths end together is repeated through a random complex point (gamma
    trick) with smaller steps. Paths whose solution goes to
    infinity (special geometry: fewer finite solutions) are dropped as diverging; a path that
    fails otherwise is re-tracked through another random point.
 3. Endpoints polished by Newton in complex128; real ones (imaginary part < 1e-8 relative) refined
    by Newton in mpmath at 60 digits, each checked: c^2 + s^2 = 1 and the forward kinematics equal
    to the pose at 50 digits (< 1e-40); angles atan2(s, c) in (-pi, pi].
 4. Cross-check: the whole computation (start pose, monodromy loops, gamma points) repeated with a
    second seed; both must give the same number of finite solutions and the same real set.

Joint limits are read with one-turn semantics (linkspace's Chain6R::within_one_turn): a joint
whose limits span a full turn covers the whole circle; otherwise the range is the limits cut to
[-pi, pi]. Every real solution is reported with `in_limits`.

Run:  /tmp/ikvenv/bin/python scripts/dev/ik6_reference.py [--poses 30] [--out FILE]
(numpy, mpmath; writes tests/data/ik6_reference.json by default)
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
from urdf_mp import Urdf, axis_angle, rpy_matrix, triple  # noqa: E402

STALL = 5           # monodromy loops without a new solution before stopping
REAL_TOL = 1e-8     # relative imaginary part below which a solution is real
DIVERGED = 1e7      # |x| beyond which a path is taken to go to infinity
PRED_TOL = 1e-4     # largest Newton correction of a predicted point (relative) for the step to count
SNAP = mp.mpf("1e-5")
SEEDS = (20250101, 4242)

FIXTURES = {
    "general_6r": "tests/data/ik6_general_6r.urdf",
    "crx": "tests/data/fanuc_crx10ial_style.urdf",
    "irb140": "tests/data/abb_irb140_style.urdf",
    "doosan": "tests/data/doosan_style_6r.urdf",
    "ur5": "urdf/ur5.urdf",
    "ur5_ros": "tests/data/ur5_ros_style.urdf",
}

# ----------------------------------------------------------------------------------------------
# the chain from the URDF, in mpmath
# ----------------------------------------------------------------------------------------------


def snapped(v):
    k = mp.nint(v / (mp.pi / 2))
    return k * mp.pi / 2 if abs(v - k * mp.pi / 2) <= SNAP else v


def hom(R, t):
    H = mp.eye(4)
    for i in range(3):
        for j in range(3):
            H[i, j] = R[i, j]
        H[i, 3] = t[i]
    return H


def origin_of(j):
    o = j["origin_el"]
    if o is None:
        return mp.eye(4)
    xyz = triple(o.get("xyz"))
    rpy = [snapped(v) for v in triple(o.get("rpy"))]
    return hom(rpy_matrix(*rpy), xyz)


def hinv(H):
    R = H[:3, :3]
    t = H[:3, 3]
    return hom(R.T, -(R.T * t))


class Chain:
    """Pre_k, axes, Post, limits of the six revolute joints (root to tip, as linkspace picks it)."""

    def __init__(self, path):
        u = Urdf(path)
        rev = lambda j: j["type"] in ("revolute", "continuous")
        kids = {}
        for j in u.joints.values():
            kids.setdefault(j["parent"], []).append(j)

        def walk(link, path):
            n = sum(rev(j) for j in path)
            if n == 6 and path and rev(path[-1]):
                return [path]
            out = []
            for j in kids.get(link, []):
                out += walk(j["child"], path + [j])
            return out

        paths = walk(u.root, [])
        assert len(paths) == 1, f"{len(paths)} paths of six revolute joints"
        path = paths[0]
        at = path[-1]["child"]
        while len(kids.get(at, [])) == 1 and kids[at][0]["type"] == "fixed":
            path.append(kids[at][0])
            at = kids[at][0]["child"]
        self.tip = at
        self.pre, self.axes, self.names, self.limits = [], [], [], []
        acc = mp.eye(4)
        for j in path:
            acc = acc * origin_of(j)
            if rev(j):
                self.pre.append(acc)
                acc = mp.eye(4)
                n = mp.sqrt(sum(a * a for a in j["axis"]))
                self.axes.append([a / n for a in j["axis"]])
                self.names.append(j["name"])
                self.limits.append(j["limits"] if j["type"] == "revolute" else None)
            else:
                assert j["type"] == "fixed", j["type"]
        self.post = acc
        self.pre_inv = [hinv(p) for p in self.pre]
        self.post_inv = hinv(self.post)
        # one-turn ranges
        self.ranges = []
        for lim in self.limits:
            if lim is None or lim[1] - lim[0] >= 2 * mp.pi:
                self.ranges.append(None)
            else:
                self.ranges.append((max(lim[0], -mp.pi), min(lim[1], mp.pi)))
        self.np = NpChain(self)

    def rot(self, k, q):
        return hom(axis_angle(self.axes[k], q), [0, 0, 0])

    def fk(self, q):
        T = mp.eye(4)
        for k in range(6):
            T = T * self.pre[k] * self.rot(k, q[k])
        return T * self.post

    def in_limits(self, q):
        return all(r is None or r[0] <= x <= r[1] for r, x in zip(self.ranges, q))


def c128(M):
    return np.array([[complex(M[i, j]) for j in range(M.cols)] for i in range(M.rows)])


def rot_parts(a, dtype):
    """P4, Q4, S4 (4x4 homogeneous) of the rotation about unit axis a: R = P + c Q + s S."""
    a = np.array(a, dtype=dtype)
    P = np.zeros((4, 4), dtype=dtype)
    Q = np.zeros((4, 4), dtype=dtype)
    S = np.zeros((4, 4), dtype=dtype)
    P[:3, :3] = np.outer(a, a)
    P[3, 3] = 1
    Q[:3, :3] = np.eye(3, dtype=dtype) - np.outer(a, a)
    S[:3, :3] = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]], dtype=dtype)
    return P, Q, S


class NpChain:
    """The constant matrices of the system, in complex128 and (for refinement) in mpmath objects."""

    def __init__(self, ch, mpobj=False):
        if mpobj:
            conv = lambda M: np.array([[mp.mpc(M[i, j]) for j in range(4)] for i in range(4)], dtype=object)
            dtype = object
            axes = [[mp.mpc(x) for x in a] for a in ch.axes]
        else:
            conv = c128
            dtype = complex
            axes = [[complex(x) for x in a] for a in ch.axes]
        self.dtype = dtype
        parts = [rot_parts(a, dtype) for a in axes]
        if mpobj:
            for p in parts:
                for M in p:
                    for idx in np.ndindex(M.shape):
                        M[idx] = mp.mpc(M[idx])
        pre = [conv(p) for p in ch.pre]
        pre_inv = [conv(p) for p in ch.pre_inv]
        self.pre1 = pre[0]
        # left factors L_k = R_k Pre_{k+1} (k = 0, 1, 2), as (const, cos, sin) parts
        self.left = [tuple(M @ pre[k + 1] for M in parts[k]) for k in range(3)]
        # right factors Y = R_6(-) Pre6^-1, R_5(-) Pre5^-1, R_4(-): sin part negated
        self.right = []
        for k, nxt in ((5, pre_inv[5]), (4, pre_inv[4]), (3, None)):
            P, Q, S = parts[k]
            trio = (P, Q, -S) if nxt is None else (P @ nxt, Q @ nxt, -S @ nxt)
            self.right.append((k, trio))
        self.post_inv = conv(ch.post_inv)


def chain_products(factors):
    """factors: list of (n,4,4); returns prefix[i] = f0..f_{i-1}, suffix[i] = f_i..f_end."""
    n = factors[0].shape[0]
    eye = np.broadcast_to(np.eye(4, dtype=factors[0].dtype), (n, 4, 4))
    pre = [eye]
    for f in factors:
        pre.append(pre[-1] @ f)
    suf = [eye]
    for f in reversed(factors):
        suf.append(f @ suf[-1])
    return pre, suf[::-1]


def evaluate(nc, X, G, dG=None, jac=True):
    """X (n,12); G (n,4,4) = T Post^-1; dG optional (n,4,4) derivative of G along the path.
    Returns F (n,12), J (n,12,12) (or None without jac), Fs (n,12) (dF/ds, or None)."""
    n = X.shape[0]
    dt = X.dtype
    c = X[:, 0::2]
    s = X[:, 1::2]

    def fac(trio, k):
        P, Q, S = trio
        return P[None] + c[:, k, None, None] * Q[None] + s[:, k, None, None] * S[None]

    Lf = [fac(nc.left[k], k) for k in range(3)]
    Lpre, Lsuf = chain_products(Lf)
    A = nc.pre1[None] @ Lpre[3]
    Yf = [fac(trio, k) for k, trio in nc.right]
    Ypre, Ysuf = chain_products(Yf)
    Xr = Ypre[3]
    B = G @ Xr
    Ra, ta = A[:, :3, :3], A[:, :3, 3]
    Rb, tb = B[:, :3, :3], B[:, :3, 3]
    M = np.swapaxes(Rb, 1, 2) @ Ra
    F = np.empty((n, 12), dtype=dt)
    F[:, :6] = c * c + s * s - 1
    F[:, 6], F[:, 7], F[:, 8] = M[:, 0, 1], M[:, 0, 2], M[:, 1, 2]
    F[:, 9:12] = ta - tb
    if not jac:
        return F, None, None
    J = np.zeros((n, 12, 12), dtype=dt)
    for k in range(6):
        J[:, k, 2 * k] = 2 * c[:, k]
        J[:, k, 2 * k + 1] = 2 * s[:, k]
    for k in range(3):
        for part, col in ((1, 2 * k), (2, 2 * k + 1)):
            dA = nc.pre1[None] @ Lpre[k] @ nc.left[k][part][None] @ Lsuf[k + 1]
            dM = np.swapaxes(Rb, 1, 2) @ dA[:, :3, :3]
            J[:, 6, col], J[:, 7, col], J[:, 8, col] = dM[:, 0, 1], dM[:, 0, 2], dM[:, 1, 2]
            J[:, 9:12, col] = dA[:, :3, 3]
    for i, (k, trio) in enumerate(nc.right):
        for part, col in ((1, 2 * k), (2, 2 * k + 1)):
            dB = G @ Ypre[i] @ trio[part][None] @ Ysuf[i + 1]
            dM = np.swapaxes(dB[:, :3, :3], 1, 2) @ Ra
            J[:, 6, col], J[:, 7, col], J[:, 8, col] = dM[:, 0, 1], dM[:, 0, 2], dM[:, 1, 2]
            J[:, 9:12, col] = -dB[:, :3, 3]
    if dG is None:
        return F, J, None
    dB = dG @ Xr
    dM = np.swapaxes(dB[:, :3, :3], 1, 2) @ Ra
    Fs = np.zeros((n, 12), dtype=dt)
    Fs[:, 6], Fs[:, 7], Fs[:, 8] = dM[:, 0, 1], dM[:, 0, 2], dM[:, 1, 2]
    Fs[:, 9:12] = -dB[:, :3, 3]
    return F, J, Fs


# ----------------------------------------------------------------------------------------------
# pose parameters: p = (u in C^4 quaternion, t in C^3)
# ----------------------------------------------------------------------------------------------


def quat_N(u):
    w, x, y, z = u[..., 0], u[..., 1], u[..., 2], u[..., 3]
    N = np.empty(u.shape[:-1] + (3, 3), dtype=u.dtype)
    N[..., 0, 0] = w * w + x * x - y * y - z * z
    N[..., 0, 1] = 2 * (x * y - w * z)
    N[..., 0, 2] = 2 * (x * z + w * y)
    N[..., 1, 0] = 2 * (x * y + w * z)
    N[..., 1, 1] = w * w - x * x + y * y - z * z
    N[..., 1, 2] = 2 * (y * z - w * x)
    N[..., 2, 0] = 2 * (x * z - w * y)
    N[..., 2, 1] = 2 * (y * z + w * x)
    N[..., 2, 2] = w * w - x * x - y * y + z * z
    return N


def pose_of_param(P, D=None):
    """T (n,4,4) and dT/ds along D, for parameter vectors P (n,7)."""
    u, t = P[:, :4], P[:, 4:]
    uu = (u * u).sum(-1)
    N = quat_N(u)
    T = np.zeros((P.shape[0], 4, 4), dtype=complex)
    T[:, :3, :3] = N / uu[:, None, None]
    T[:, :3, 3] = t
    T[:, 3, 3] = 1
    if D is None:
        return T, None
    du, dt = D[:, :4], D[:, 4:]
    dN = (quat_N(u + du) - quat_N(u - du)) / 4 * 2    # polarisation: exact for a quadratic form
    duu = 2 * (u * du).sum(-1)
    dT = np.zeros_like(T)
    dT[:, :3, :3] = (dN * uu[:, None, None] - N * duu[:, None, None]) / (uu ** 2)[:, None, None]
    dT[:, :3, 3] = dt
    return T, dT


def param_of_pose(R, t):
    """A quaternion u with R(u) = R (u.u = 1), any complex orthogonal R with 1 + tr R != 0."""
    w = np.sqrt(1 + R[0, 0] + R[1, 1] + R[2, 2] + 0j) / 2
    x = (R[2, 1] - R[1, 2]) / (4 * w)
    y = (R[0, 2] - R[2, 0]) / (4 * w)
    z = (R[1, 0] - R[0, 1]) / (4 * w)
    return np.array([w, x, y, z, *t], dtype=complex)


class System:
    def __init__(self, chain):
        self.ch = chain
        self.nc = chain.np

    def eval(self, X, Pv, Dv=None):
        T, dT = pose_of_param(Pv, Dv)
        G = T @ self.nc.post_inv[None]
        dG = None if dT is None else dT @ self.nc.post_inv[None]
        return evaluate(self.nc, X, G, dG)


# ----------------------------------------------------------------------------------------------
# tracking
# ----------------------------------------------------------------------------------------------


def track(system, X0, Pa, Pb, tol=1e-9, h0=0.02, hmin=1e-12, max_steps=20000, hmax=0.05):
    """Track solutions X0 (n,12) of F(.;Pa)=0 along the segment Pa->Pb (parameter vectors).
    Returns (X (n,12), ok (n,) bool, diverged (n,) bool)."""
    n = X0.shape[0]
    X = X0.copy()
    s = np.zeros(n)
    h = np.full(n, h0)
    active = np.ones(n, bool)
    ok = np.zeros(n, bool)
    div = np.zeros(n, bool)
    D = (Pb - Pa)[None, :]

    def field(Xa, sa):
        Pv = Pa[None, :] + sa[:, None] * D
        with np.errstate(all="ignore"):
            F, J, Fs = system.eval(Xa, Pv, np.repeat(D, len(sa), 0))
            try:
                return -np.linalg.solve(J, Fs[..., None])[..., 0]
            except np.linalg.LinAlgError:
                out = np.full_like(Xa, np.nan)
                for i in range(len(sa)):
                    try:
                        out[i] = -np.linalg.solve(J[i], Fs[i])
                    except np.linalg.LinAlgError:
                        pass
                return out

    def newton_step(Y, Pv):
        with np.errstate(all="ignore"):
            F, J, _ = system.eval(Y, Pv)
            try:
                return np.linalg.solve(J, F[..., None])[..., 0]
            except np.linalg.LinAlgError:
                out = np.full_like(Y, np.nan)
                for i in range(len(Y)):
                    try:
                        out[i] = np.linalg.solve(J[i], F[i])
                    except np.linalg.LinAlgError:
                        pass
                return out

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
            dY = newton_step(np.where(good[:, None], Y, 0), Pv)
            Y = Y - dY
            with np.errstate(all="ignore"):
                nrm = np.linalg.norm(dY, axis=1) / (1 + np.linalg.norm(Y, axis=1))
            norms.append(nrm)
            good &= np.isfinite(nrm)
        conv = good & (norms[0] < PRED_TOL) & (norms[1] < 1e-6) & (norms[2] < np.maximum(tol, 1e-1 * norms[1]))
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
        big = acc[np.abs(X[acc]).max(1) > DIVERGED]
        div[big] = True
        active[big] = False
        dead = rej[h[rej] < hmin]
        active[dead] = False
    return X, ok & ~div, div


def newton_np(system, X, Pv, iters=6):
    P = np.repeat(Pv[None, :], X.shape[0], 0)
    with np.errstate(all="ignore"):
        for _ in range(iters):
            F, J, _ = system.eval(X, P)
            X = X - np.linalg.solve(J, F[..., None])[..., 0]
        F, J, _ = system.eval(X, P)
    return X, np.linalg.norm(F, axis=1)


def distinct(X, tol=1e-6):
    keep = []
    for x in X:
        if not any(np.linalg.norm(x - y) <= tol * (1 + np.linalg.norm(x)) for y in keep):
            keep.append(x)
    return np.array(keep).reshape(-1, X.shape[1] if X.ndim == 2 else 12)


def crandn(rng, *shape):
    return rng.standard_normal(shape) + 1j * rng.standard_normal(shape)


def random_param(rng):
    return crandn(rng, 7)


def start(system, rng):
    """A random complex joint vector and the pose it gives: (P0, x0)."""
    z = crandn(rng, 6) * 0.7
    c, s = np.cos(z), np.sin(z)
    nc = system.nc
    # forward kinematics in complex128 via the left/right factors: T = A * (R4 Pre5 R5 Pre6 R6) * Post
    mpq = [mp.mpc(v.real, v.imag) for v in z]
    T = system.ch.fk(mpq)
    Tn = c128(T)
    P0 = param_of_pose(Tn[:3, :3], Tn[:3, 3])
    x0 = np.empty(12, complex)
    x0[0::2], x0[1::2] = c, s
    F, _, _ = system.eval(x0[None], P0[None])
    assert np.abs(F).max() < 1e-10, F
    del nc
    return P0, x0


def monodromy(system, P0, x0, rng, log):
    sols = np.array([x0])
    stall, loops = 0, 0
    while stall < STALL:
        loops += 1
        P1, P2 = random_param(rng), random_param(rng)
        X = sols
        okall = np.ones(len(X), bool)
        for a, b in ((P0, P1), (P1, P2), (P2, P0)):
            X, ok, _ = track(system, X, a, b)
            okall &= ok
        X, res = newton_np(system, X[okall], P0)
        X = X[(res < 1e-10) & np.isfinite(res)]
        before = len(sols)
        sols = distinct(np.concatenate([sols, X]))
        stall = stall + 1 if len(sols) == before else 0
        log(f"  monodromy loop {loops}: {len(sols)} solutions ({int((~okall).sum())} paths failed)")
        if loops > 60:
            break
    return sols, loops


def to_target(system, sols, P0, Pt, rng, hmax=0.25, tries=4):
    """Track every start solution to the target parameter: straight from the random start point
    P0, then (if needed) through another random complex point (gamma trick). A run counts when every path ends (finite or diverging) and the finite endpoints are
    distinct (two paths meeting is path jumping); otherwise the whole run is repeated through
    another point with half the largest step. Returns (finite endpoints, number diverged,
    number failed, runs)."""
    best = None
    for attempt in range(tries):
        if attempt == 0:
            # P0 is a random complex point: the segment to Pt already misses the
            # discriminant (a real codimension-2 set) with probability one
            Y, ok1, div1 = sols, np.ones(len(sols), bool), np.zeros(len(sols), bool)
            Pg = P0
        else:
            # near the segment's middle: a random point far away (tiny u.u on the way) makes
            # slow paths
            Pg = (P0 + Pt) / 2 + 0.5 * crandn(rng, 7)
            Y, ok1, div1 = track(system, sols, P0, Pg, hmax=hmax)
        Z = np.full_like(Y, np.nan)
        ok2 = np.zeros(len(sols), bool)
        div2 = np.zeros(len(sols), bool)
        if ok1.any():
            Z[ok1], ok2[ok1], div2[ok1] = track(system, Y[ok1], Pg, Pt, hmax=hmax)
        X, res = newton_np(system, Z[ok2], Pt, iters=3)
        X = X[np.isfinite(res) & (res < 1e-8)]
        D = distinct(X, 1e-7)
        failed = len(sols) - len(D) - int(div2.sum()) - int(div1.sum())
        if best is None or failed < best[2]:
            best = (D, int(div1.sum() + div2.sum()), failed, attempt + 1)
        if failed == 0:
            break
        hmax /= 2
    return best


# ----------------------------------------------------------------------------------------------
# refinement in mpmath
# ----------------------------------------------------------------------------------------------


def mp_refine(chain, ncmp, x, T, iters=12):
    """Chord-Newton at the working precision on the same system, pose T (mp 4x4, real): the
    Jacobian at the start point only (x is accurate to ~1e-15, so each step gains ~15 digits)."""
    G = c_obj(T * chain.post_inv)
    X = np.array([[mp.mpc(v.real, v.imag) for v in x]], dtype=object)
    F, J, _ = evaluate(ncmp, X, G[None])
    Jinv = mp.inverse(mp.matrix(J[0].tolist()))
    for _ in range(iters):
        dx = Jinv * mp.matrix(F[0].tolist())
        X = X - np.array([[dx[k] for k in range(12)]], dtype=object)
        F, _, _ = evaluate(ncmp, X, G[None], jac=False)
        if mp.norm(dx) < mp.mpf(10) ** (-mp.mp.dps + 8):
            break
    return list(X[0]), max(abs(v) for v in F[0])


def c_obj(M):
    return np.array([[mp.mpc(M[i, j]) for j in range(M.cols)] for i in range(M.rows)], dtype=object)


def random_q(chain, rng):
    out = []
    for r in chain.ranges:
        lo, hi = (-3.1, 3.1) if r is None else (max(float(r[0]), -3.1), min(float(r[1]), 3.1))
        out.append(rng.uniform(lo, hi))
    return out


def fmt(x):
    return float(mp.nstr(x, 17)) if not isinstance(x, float) else x


def solve_pose(chain, systems, P0s, sols_list, T_mp, rngs, log):
    """Solve one pose with every seed's start system. Returns per-seed float solutions and the
    refined real solutions of the first seed."""
    Tn = np.array([[float(T_mp[i, j]) for j in range(4)] for i in range(4)])
    Pt = param_of_pose(Tn[:3, :3], Tn[:3, 3]).real.astype(complex)
    per_seed = []
    for system, P0, sols, rng in zip(systems, P0s, sols_list, rngs):
        D, div, failed, runs = to_target(system, sols, P0, Pt, rng)
        per_seed.append({"X": D, "diverged": div, "failed": failed, "runs": runs})
    return per_seed, Pt


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--poses", type=int, default=30)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--fixtures", default=",".join(FIXTURES))
    ap.add_argument("--out", default=os.path.join(REPO, "tests", "data", "ik6_reference.json"))
    ap.add_argument("--quiet", action="store_true")
    ap.add_argument("--second-seed", choices=("always", "incomplete"), default="always",
                    help="track every pose with the second seed's start system too, or only when the first "
                         "finds fewer finite solutions than the generic count")
    ap.add_argument("--checkpoint", action="store_true", help="write the poses so far to OUT.partial every 50")
    ap.add_argument("--compact", action="store_true",
                    help="joint vectors q with 9 decimals, solutions in limits with 9 significant digits, "
                         "no pose (it is the forward kinematics of q), no solutions outside the limits")
    args = ap.parse_args()
    t_start = time.time()
    log = (lambda *a: None) if args.quiet else (lambda m: print(f"[{time.time() - t_start:7.1f}s] {m}", flush=True))
    mp.mp.dps = 60
    out_fixtures = []
    for name in args.fixtures.split(","):
        rel = FIXTURES[name]
        t_fix = time.time()
        chain = Chain(os.path.join(REPO, rel))
        ncmp = NpChain(chain, mpobj=True)
        systems, P0s, sols_list, rngs, loops = [], [], [], [], []
        for seed in SEEDS:
            rng = np.random.default_rng(seed)
            system = System(chain)
            P0, x0 = start(system, rng)
            log(f"{name}: monodromy, seed {seed}")
            sols, nl = monodromy(system, P0, x0, rng, log)
            systems.append(system)
            P0s.append(P0)
            sols_list.append(sols)
            rngs.append(rng)
            loops.append(nl)
        generic = [len(s) for s in sols_list]
        assert generic[0] == generic[1], generic
        t_mono = time.time() - t_fix
        prng = np.random.default_rng(args.seed + 1000 * list(FIXTURES).index(name))

        def entry():
            return {
                "name": name,
                "urdf": rel,
                "joints": chain.names,
                "tip": chain.tip,
                "ranges": [None if r is None else [float(r[0]), float(r[1])] for r in chain.ranges],
                "generic_finite_solutions": generic[0],
                "monodromy_loops": loops,
                "solutions_in_limits_histogram": {str(k): v for k, v in sorted(hist.items())},
                "max_fk_residual_50_digits": float(worst_res),
                "max_seed_difference": float(worst_diff),
                "second_seed": args.second_seed,
                "tracking_runs_histogram": {str(k): v for k, v in sorted(runs_hist.items())},
                "unresolved_poses": unresolved,
                "seconds": round(time.time() - t_fix, 1),
                "seconds_monodromy": round(t_mono, 1),
                "poses": poses,
            }

        poses = []
        hist = {}
        worst_res, worst_diff = mp.mpf(0), 0.0
        unresolved, runs_hist = [], {}
        ip = -1
        while len(poses) < args.poses:
            ip += 1
            q = random_q(chain, prng)
            if args.compact:
                q = [round(v, 9) for v in q]
            T = chain.fk([mp.mpf(v) for v in q])
            use = 2 if args.second_seed == "always" else 1
            per_seed, Pt = solve_pose(chain, systems[:use], P0s[:use], sols_list[:use], T, rngs[:use], log)
            if use == 1 and (len(per_seed[0]["X"]) < generic[0] or per_seed[0]["failed"]):
                per_seed += solve_pose(chain, systems[1:], P0s[1:], sols_list[1:], T, rngs[1:], log)[0]
            counts = [len(p["X"]) for p in per_seed]
            reals = []
            for k, p in enumerate(per_seed):
                X = p["X"]
                im = np.abs(X.imag).max(1) / (1 + np.abs(X).max(1))
                reals.append(X[im < REAL_TOL].real)
            problem = None
            if any(p["failed"] for p in per_seed):
                problem = f"paths failed: {[p['failed'] for p in per_seed]}"
            elif len(set(counts)) > 1:
                problem = f"finite solutions per seed {counts}"
            elif len(set(len(r) for r in reals)) > 1:
                problem = f"real solutions per seed {[len(r) for r in reals]}"
            else:
                for x in reals[0]:
                    d = min(np.abs(x - y).max() for y in reals[-1]) if len(reals[-1]) else np.inf
                    worst_diff = max(worst_diff, d)
                    if d > 1e-8:
                        problem = f"seeds disagree by {d}"
            if problem:
                log(f"{name} pose {ip}: UNRESOLVED, {problem}; q = {q}")
                unresolved.append({"q": q, "problem": problem})
                continue
            runs_hist[max(p["runs"] for p in per_seed)] = runs_hist.get(max(p["runs"] for p in per_seed), 0) + 1
            sols = []
            for x in reals[0]:
                xr, res = mp_refine(chain, ncmp, x + 0j, T)
                assert res < mp.mpf(10) ** -45, res
                assert max(abs(v.imag) for v in xr) < mp.mpf(10) ** -40
                cs = [v.real for v in xr]
                ang = [mp.atan2(cs[2 * k + 1], cs[2 * k]) for k in range(6)]
                Tq = chain.fk(ang)
                err = mp.mnorm(Tq - T, 1)
                assert err < mp.mpf(10) ** -40, err
                worst_res = max(worst_res, err)
                sols.append((ang, chain.in_limits(ang)))
            assert any(all(abs(mp.atan2(mp.sin(a - mp.mpf(b)), mp.cos(a - mp.mpf(b)))) < 1e-20 for a, b in zip(s[0], q)) for s in sols), \
                f"pose {ip}: the generating joint vector is not among the solutions"
            sols.sort(key=lambda s: [float(v) for v in s[0]])
            inl = [s for s in sols if s[1]]
            hist[len(inl)] = hist.get(len(inl), 0) + 1
            if args.compact:
                poses.append({"q": q, "solutions": [[float(f"{float(v):.9g}") for v in s[0]] for s in inl]})
            else:
                poses.append({
                    "q": q,
                    "pose": [[float(T[i, j]) for j in range(4)] for i in range(4)],
                    "finite_solutions": counts[0],
                    "real_solutions": len(sols),
                    "solutions": [[float(v) for v in s[0]] for s in inl],
                    "outside_limits": [[float(v) for v in s[0]] for s in sols if not s[1]],
                })
            if args.checkpoint and len(poses) % 50 == 0:
                write(args, out_fixtures + [entry()], args.out + ".partial")
            log(f"{name} pose {ip}: {counts[0]} finite ({per_seed[0]['diverged']} to infinity), "
                f"{len(sols)} real, {len(inl)} in limits")
        seconds = time.time() - t_fix
        out_fixtures.append(entry())
        log(f"{name}: generic {generic[0]}, histogram {hist}, {seconds:.0f} s")
    write(args, out_fixtures, args.out)
    log(f"wrote {args.out} ({os.path.getsize(args.out)} bytes)")


def write(args, fixtures, path):
    out = {
        "generator": "scripts/dev/ik6_reference.py (monodromy + parameter homotopy in complex128, real solutions "
                     "refined by Newton in mpmath at 60 digits, two independent seeds)",
        "units": "metres, radians",
        "pose": "4x4 homogeneous matrix of the tip link in the root frame (rows), forward kinematics of q at 60 digits",
        "solutions": "every real solution with each angle in (-pi, pi] inside the joint's one-turn range "
                     "(range = limits cut to [-pi, pi]; a joint whose limits span a turn: the whole circle); "
                     "outside_limits: the other real solutions",
        "seeds": list(SEEDS),
        "fixtures": fixtures,
    }
    if args.compact:
        out["compact"] = True
        out["pose"] = "not stored: the forward kinematics of q (decimals as written) at 60 digits"
        out["solutions"] += " (9 significant digits); outside_limits not stored"
    with open(path, "w") as f:
        json.dump(out, f, separators=(",", ":"))
        f.write("\n")


if __name__ == "__main__":
    main()
