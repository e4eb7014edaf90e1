#!/usr/bin/env python3
"""Second, independent check of a Stewart reference (tests/data/stewart_6_6_fk.json by default): real Newton from many random poses.

Different formulation from stewart_fk.py: unknowns = rotation vector (exponential map) and
translation, six equations |R p_i + t - b_i|^2 - L_i^2 = 0, plain float64 Newton (damped) from
20000 random starts per case (fixed seed). Every real assembly it converges to must be one of the
JSON's; it reports how many of the JSON's it rediscovered. (Evidence, not a completeness proof:
completeness comes from the 40 complex solutions of the homotopy.)

Run: python3 scripts/dev/stewart_newton_check.py  (exit status 1 on a real solution not in the JSON)
     python3 scripts/dev/stewart_newton_check.py --json tests/data/stewart_40_fk.json --centre 0.7,0,0 --spread 0.7
     (the URDF is the one the JSON names; starts: translations about --centre, --spread wide)
"""
import argparse
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
from stewart_fk import Stewart  # noqa: E402  (URDF read-back only)


def rot(w):
    th = np.linalg.norm(w, axis=-1)[..., None, None]
    K = np.zeros(w.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -w[..., 2], w[..., 1], -w[..., 0]
    K = K - np.swapaxes(K, -1, -2)
    th = np.maximum(th, 1e-300)
    return np.eye(3) + np.sin(th) / th * K + (1 - np.cos(th)) / th ** 2 * K @ K


def residual(z, b, p, L2):
    R = rot(z[..., :3])
    x = np.einsum("nij,kj->nki", R, p) + z[..., None, 3:] - b
    return (x * x).sum(-1) - L2


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", default="tests/data/stewart_6_6_fk.json", help="the reference (path from the repository root)")
    ap.add_argument("--centre", default="0,0,0.3", help="mean of the start translations")
    ap.add_argument("--spread", type=float, default=0.6, help="standard deviation of the start translations")
    args = ap.parse_args()
    data = json.load(open(os.path.join(REPO, args.json)))
    st = Stewart(os.path.join(REPO, data["urdf"]))
    centre = [float(v) for v in args.centre.split(",")]
    rng = np.random.default_rng(99)
    fail = False
    for case in data["cases"]:
        L2 = np.array([float(v) ** 2 for v in case["leg_lengths"].values()])
        n = 20000
        z = np.concatenate([rng.normal(0, 1.2, (n, 3)), rng.normal(0, args.spread, (n, 3)) + centre], 1)
        for _ in range(60):
            F = residual(z, st.b, st.p, L2)
            J = np.empty((n, 6, 6))
            h = 1e-7
            for k in range(6):
                dz = np.zeros(6)
                dz[k] = h
                J[:, :, k] = (residual(z + dz, st.b, st.p, L2) - residual(z - dz, st.b, st.p, L2)) / (2 * h)
            with np.errstate(all="ignore"):
                try:
                    step = np.linalg.solve(J, F[..., None])[..., 0]
                except np.linalg.LinAlgError:
                    step = np.array([np.linalg.lstsq(Jk, Fk, rcond=None)[0] for Jk, Fk in zip(J, F)])
            nrm = np.linalg.norm(step, axis=1, keepdims=True)
            z = z - step * np.minimum(1, 0.5 / np.maximum(nrm, 1e-300))
            z = np.where(np.isfinite(z), z, 0)
        F = residual(z, st.b, st.p, L2)
        conv = np.abs(F).max(1) < 1e-10
        R = rot(z[conv, :3])
        t = z[conv, 3:]
        ref = [(np.array(s["platform_rotation_matrix"]), np.array(s["platform_position"])) for s in case["solutions"]]
        found = set()
        extra = 0
        for Rk, tk in zip(R, t):
            d = [np.abs(Rk - Rr).max() + np.abs(tk - tr).max() for Rr, tr in ref]
            if min(d) < 1e-6:
                found.add(int(np.argmin(d)))
            else:
                extra += 1
        print(f"{case['name']}: {conv.sum()} of {n} starts converged; rediscovered {len(found)} of "
              f"{len(ref)} real assemblies; {extra} converged to a pose not in the JSON")
        fail |= extra > 0
    sys.exit(1 if fail else 0)


if __name__ == "__main__":
    main()
