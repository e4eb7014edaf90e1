#!/usr/bin/env python3
"""Leg lengths of a 6-6 Stewart-Gough platform at which two real assemblies lie a given distance apart.

No interval solver and no linkspace code: mpmath at 50 digits, geometry read from the URDF
(scripts/dev/urdf_mp.py through the Stewart reader of scripts/dev/stewart_fk.py).

Pose coordinates x = (t, w): platform position t and rotation R0 Rod(w), w a rotation vector
about the rotation R0 of a starting assembly; f(x) = the six ball-to-ball leg lengths.
 1. Start: real assembly --solution of a reference JSON (stewart_fk.py's output); v0 the right
    singular vector of its 6x6 leg Jacobian Df for the smallest singular value.
 2. Fold: a nearby solution (x_s, v_s) of  Df(x) v = 0, v0.v = 1  (7 equations in 12 unknowns,
    Newton with minimum-norm steps, i.e. the pseudo-inverse); there two assemblies of equal leg
    lengths merge.
 3. Pair: for a half-width h, the solution (m, v) near (x_s, v_s) of
        (f(m + h v) - f(m - h v)) / (2 h) = 0,   v0.v = 1
    (again minimum-norm Newton): x_a = m + h v and x_b = m - h v are two real poses with the same
    leg lengths L = f(x_a).
 4. L is rounded to --digits significant digits and each pose refined by Newton on f(x) = L for
    exactly these decimals; h is rescaled until the refined pair's distance
    |t_a - t_b| + |R_a - R_b|_F (Frobenius; the measure of `closest_real_pair` in stewart_fk.py's
    JSON) is within 10% of --distance. Printed: the distance, the leg Jacobian's smallest singular
    value at both poses, the leg limits, and the lengths as --case for stewart_fk.py and as --fix.

The default start, solution 20 of tests/data/stewart_40_fk.json: the folds nearest the least
singular assemblies (solutions 0, 21, 5, smallest singular values 1.1e-3 to 3.3e-3, lengths 0.002 to
0.009 from the URDF's) bend so little along the null direction that a pair 5e-5 apart has a leg
Jacobian singular to 1e-7, and rounding the lengths to 12 digits moves each pose by up to the
pair's distance. Solution 20's fold (lengths 0.016 from the URDF's) gives a pair 5.4e-5 apart with
smallest singular value 8.8e-7, which the rounding moves by 9e-7
(tests/data/stewart_40_close_pair_fk.json).

Run: python3 scripts/dev/stewart_close_pair.py   (numpy, mpmath; ~10 s; defaults:
         --urdf urdf/stewart_40.urdf --json tests/data/stewart_40_fk.json --solution 20 --distance 5e-5 --digits 12)
     python3 scripts/dev/stewart_fk.py --urdf urdf/stewart_40.urdf --out tests/data/stewart_40_close_pair_fk.json \
         --case close_pair=L1,...,L6 --note "..."   (the lengths printed; every assembly, ~1.5 min)
"""
import argparse
import json
import os
import sys

import mpmath as mp

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
from stewart_fk import Stewart  # noqa: E402


def skew(w):
    return mp.matrix([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def rodrigues(w):
    th = mp.sqrt(sum(c * c for c in w))
    K = skew(w)
    if th < mp.mpf(10) ** -30:
        return mp.eye(3) + K + K * K / 2
    return mp.eye(3) + (mp.sin(th) / th) * K + ((1 - mp.cos(th)) / (th * th)) * (K * K)


def quat_matrix(q):
    w, x, y, z = q
    return mp.matrix([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


class Poses:
    """Pose coordinates x = (t, w) about a rotation R0 and the leg-length map f."""

    def __init__(self, st, R0):
        self.st, self.R0 = st, R0

    def pose(self, x):
        return self.R0 * rodrigues(x[3:6]), mp.matrix(x[0:3])

    def f(self, x):
        R, t = self.pose(x)
        return self.st.lengths(R, t)

    def jac(self, x):
        """Df(x), 6x6, by central differences at step 1e-20 (error 1e-40 at 50 digits)."""
        h = mp.mpf(10) ** -20
        J = mp.matrix(6, 6)
        for j in range(6):
            xp, xm = list(x), list(x)
            xp[j] += h
            xm[j] -= h
            fp, fm = self.f(xp), self.f(xm)
            for i in range(6):
                J[i, j] = (fp[i] - fm[i]) / (2 * h)
        return J

    def distance(self, xa, xb):
        (Ra, ta), (Rb, tb) = self.pose(xa), self.pose(xb)
        return mp.norm(ta - tb) + mp.mnorm(Ra - Rb, "f")


def min_norm_newton(F, z, iters=40, tol=None):
    """Newton with minimum-norm steps for F: R^n -> R^m, m <= n (Jacobian by central differences)."""
    tol = tol or mp.mpf(10) ** (-mp.mp.dps + 10)
    h = mp.mpf(10) ** -20
    for _ in range(iters):
        r = mp.matrix(F(z))
        J = mp.matrix(len(r), len(z))
        for j in range(len(z)):
            zp, zm = list(z), list(z)
            zp[j] += h
            zm[j] -= h
            fp, fm = F(zp), F(zm)
            for i in range(len(r)):
                J[i, j] = (fp[i] - fm[i]) / (2 * h)
        dz = J.T * mp.lu_solve(J * J.T, r)
        z = [z[k] - dz[k] for k in range(len(z))]
        if mp.norm(dz) < tol:
            break
    return z, mp.norm(mp.matrix(F(z)))


def smallest_singular(J):
    return min(mp.svd_r(J, compute_uv=False))


def right_null(J):
    U, S, V = mp.svd_r(J)
    k = min(range(len(S)), key=lambda i: S[i])
    return [V[k, j] for j in range(V.cols)]


def pair_at(P, v0, z, h):
    """(m, v) with f(m + h v) = f(m - h v), v0.v = 1, from z; returns z, x_a, x_b, residual."""
    def pair(z):
        m, v = z[:6], z[6:]
        fa = P.f([a + h * b for a, b in zip(m, v)])
        fb = P.f([a - h * b for a, b in zip(m, v)])
        return [(a - b) / (2 * h) for a, b in zip(fa, fb)] + [sum(a * b for a, b in zip(v0, v)) - 1]

    z, res = min_norm_newton(pair, z, tol=mp.mpf(10) ** -30)
    m, v = z[:6], z[6:]
    return z, [a + h * b for a, b in zip(m, v)], [a - h * b for a, b in zip(m, v)], res


def assembly(P, L, x):
    """The assembly of leg lengths L (mp) nearest x, by Newton on f(y) = L; (y, residual)."""
    return min_norm_newton(lambda y: [a - b for a, b in zip(P.f(y), L)], x, tol=mp.mpf(10) ** -35)


def arguments():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--urdf", default="urdf/stewart_40.urdf", help="the platform (path from the repository root)")
    ap.add_argument("--json", default="tests/data/stewart_40_fk.json", help="a reference of that platform (stewart_fk.py)")
    ap.add_argument("--case", type=int, default=0, help="case index in the reference")
    ap.add_argument("--solution", type=int, default=20, help="the starting assembly (index in the case's solutions)")
    ap.add_argument("--distance", type=float, default=5e-5, help="target distance of the pair")
    ap.add_argument("--digits", type=int, default=12, help="significant digits of the leg lengths")
    return ap.parse_args()


def main():
    args = arguments()
    mp.mp.dps = 50
    st = Stewart(os.path.join(REPO, args.urdf))
    case = json.load(open(os.path.join(REPO, args.json)))["cases"][args.case]
    sols = case["solutions"]
    k = args.solution
    s = sols[k]
    R0 = quat_matrix([mp.mpf(v) for v in s["platform_quaternion_wxyz_40_digits"]])
    t0 = [mp.mpf(v) for v in s["platform_position_40_digits"]]
    P = Poses(st, R0)
    x0 = t0 + [mp.mpf(0)] * 3
    J0 = P.jac(x0)
    v0 = right_null(J0)
    print(f"start: solution {k} of {args.json} case {args.case}, smallest singular value "
          f"{mp.nstr(smallest_singular(J0), 4)} (pose coordinates)")

    # fold: Df(x) v = 0, v0.v = 1
    def fold(z):
        x, v = z[:6], mp.matrix(z[6:])
        return list(P.jac(x) * v) + [sum(a * b for a, b in zip(v0, z[6:])) - 1]

    z, res = min_norm_newton(fold, x0 + v0, tol=mp.mpf(10) ** -30)
    xs, vs = z[:6], z[6:]
    Ls = P.f(xs)
    print(f"fold: residual {mp.nstr(res, 3)}, |x_s - x0| {mp.nstr(mp.norm(mp.matrix(xs) - mp.matrix(x0)), 4)}, "
          f"|L_s - L0| {mp.nstr(mp.norm(mp.matrix(Ls) - mp.matrix(P.f(x0))), 4)}")

    # pair at half-width h, rescaled until the pair at the rounded lengths is at the target distance
    target = mp.mpf(args.distance)
    h = target / 2 / mp.norm(mp.matrix(vs))
    z = xs + vs
    for _ in range(8):
        z, xa, xb, res = pair_at(P, v0, z, h)
        L = [mp.nstr(x, args.digits) for x in P.f(xa)]
        ends = [assembly(P, [mp.mpf(x) for x in L], x) for x in (xa, xb)]
        d_exact, d = P.distance(xa, xb), P.distance(ends[0][0], ends[1][0])
        print(f"pair: h {mp.nstr(h, 6)}, residual {mp.nstr(res, 3)}, distance {mp.nstr(d_exact, 6)}, "
              f"{mp.nstr(d, 6)} at the rounded lengths")
        if abs(d / target - 1) < mp.mpf("0.1"):
            break
        h = h * target / d
    Lm = [mp.mpf(x) for x in L]
    print("lengths:", ",".join(L))
    for (y, res), x in zip(ends, (xa, xb)):
        print(f"  assembly: residual {mp.nstr(res, 3)}, moved {mp.nstr(mp.norm(mp.matrix(y) - mp.matrix(x)), 3)} "
              f"by the rounding, smallest singular value {mp.nstr(smallest_singular(P.jac(y)), 4)}, "
              f"position {[mp.nstr(c, 12) for c in y[:3]]}")
    print(f"distance of the pair at these lengths: {mp.nstr(d, 8)}")
    limits = all(l["limits"][0] <= x <= l["limits"][1] for l, x in zip(st.legs, Lm))
    print(f"within the leg limits: {limits}")
    print("--case close_pair=" + ",".join(L))
    print("--fix " + " --fix ".join(f"{l['name']}={x}" for l, x in zip(st.legs, L)))


if __name__ == "__main__":
    main()
