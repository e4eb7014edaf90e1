#!/usr/bin/env python3
"""linkspace side by side with Ibex (`ibexsolve`) and PHCpack (`phc -b`).

    python3 scripts/peers/side_by_side.py                 # the table (CPU s, median of --repeat)
    python3 scripts/peers/side_by_side.py --check-models  # the peer models against known solutions
    python3 scripts/peers/side_by_side.py --write-models  # regenerate scripts/peers/models/
    python3 scripts/peers/side_by_side.py --write-references  # linkspace's solutions -> references.json

Times are CPU seconds (user + system) of the child process (getrusage RUSAGE_CHILDREN deltas),
the median of --repeat runs, linkspace with --threads 1; the solvers run interleaved per case.
A ratio is printed only when linkspace and the peer both ran in this invocation on the same
problem; otherwise the peer column shows the stored figure as a dated reference.
The 3R cusp and node rows come from `linkspace-lab bench3r` (--bench3r), which writes its own
Minibex models and runs `ibexsolve` when it is on PATH.
"""

import argparse
import json
import math
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import models as m  # noqa: E402

ROOT = m.ROOT
HERE = Path(__file__).resolve().parent
MODELS = HERE / "models"
REFERENCES = HERE / "references.json"

STORED_IBEX = "Ibex 2.9.1, 2026-11-25, {}, stored (docs/peers.md)"
STORED_PHC = "PHCpack 2.4.86, 2026-11-25, {}, stored (docs/peers.md)"


def fix_args(fixed):
    return [a for k, v in fixed.items() for a in ("--fix", f"{k}={v}")]


STEWART_LEGS = {f"leg{i}": v for i, v in
                enumerate(["0.7345220735", "0.7652225701", "0.7353460099", "0.7030942876", "0.7062382101", "0.7364750265"], 1)}

# name, linkspace arguments, Ibex model, PHC model, expected peer solutions (Ibex, PHC real),
# stored peer figures (peers-side-by-side.md, 2026-11-25, CPU s median of 3).
CASES = [
    {
        "name": "butterfly rigid 1e-4",
        "linkspace": ["solve", "urdf/double_butterfly.urdf", "--fix", "joint6=1.1760052070951352", "--sigma", "1e-4"],
        "ibex": lambda: m.butterfly(True),
        "phc": lambda: m.butterfly(False),
        "expect": {"ibex": 6, "phc_real": 6},
        "stored": {"ibex": STORED_IBEX.format("0.0631 s, 6 sol")},
    },
    {
        "name": "four spheres σ 0.01",
        "linkspace": ["distances", "urdf/four_spheres.json", "--sigma", "0.01"],
        "ibex": m.four_spheres,
        "phc": m.four_spheres,
        # PHC has no inequality: both orientations of each line, 24 real roots (a wider problem).
        "expect": {"ibex": 12, "phc_real": 24},
        "phc_same": False,
        "stored": {"ibex": STORED_IBEX.format("0.5261 s, 12 sol")},
    },
    {
        "name": "octahedral a",
        "linkspace": ["distances", "urdf/octahedral.urdf"] + fix_args(m.OCTAHEDRAL_FIXED["a"]),
        "ibex": lambda: m.octahedral("a"),
        "phc": lambda: m.octahedral("a"),
        "expect": {"ibex": 4, "phc_real": 4},
        "stored": {"ibex": STORED_IBEX.format("0.0209 s, 4 sol")},
    },
    {
        "name": "octahedral b",
        "linkspace": ["distances", "urdf/octahedral.urdf"] + fix_args(m.OCTAHEDRAL_FIXED["b"]),
        "ibex": lambda: m.octahedral("b"),
        "phc": lambda: m.octahedral("b"),
        "expect": {"ibex": 16, "phc_real": 16},
        "stored": {"ibex": STORED_IBEX.format("0.2269 s, 16 sol")},
    },
    {
        "name": "Stewart 6-6 from_pose",
        "linkspace": ["solve", "urdf/stewart_6_6.urdf"] + fix_args(STEWART_LEGS),
        "ibex": lambda: m.stewart_ibex(m.stewart_data()),
        "phc": lambda: m.stewart_phc(m.stewart_data()),
        "ibex_args": ["-t", "600"],
        "expect": {"ibex": 8, "phc_real": 8, "phc_complex": 40},
        "stored": {"ibex": STORED_IBEX.format("7.681 s, 8 sol, 0 unk"),
                   "phc": STORED_PHC.format("3.191 s, 40 regular, 8 real")},
    },
    {
        "name": "delta",
        "linkspace": ["solve", "urdf/delta.urdf"] + fix_args(m.DELTA_FIXED),
        "ibex": m.delta,
        "phc": m.delta,
        "expect": {"ibex": 2, "phc_real": 2},
        "stored": {"ibex": STORED_IBEX.format("0.0065 s, 2 sol")},
    },
    {
        "name": "spherical four-bar, crank 0.4",
        "linkspace": ["solve", "urdf/spherical_four_bar.urdf", "--fix", f"crank_joint={m.SPHERICAL_CRANK}"],
        "ibex": lambda: m.spherical_four_bar(True),
        "phc": lambda: m.spherical_four_bar(False),
        # PHC has no inequality: the closing axis from either side, x components of either sign.
        "expect": {"ibex": 2, "phc_real": 4},
        "phc_same": False,
        "stored": {"ibex": STORED_IBEX.format("0.0078 s, 2 sol")},
    },
    {
        "name": "3-RPR cusps (rho3 = 17)",
        "linkspace": ["loop-singularities", "urdf/three_rpr.urdf", "--fix", f"rho3={m.RPR_RHO3}", "--actuated", "rho1,rho2",
                      "--kind", "cusps", "--sigma", "1e-3", "--timeout", "180"],
        "ibex": m.three_rpr,
        "phc": None,
        # Ibex's G1 system also holds points that are not cusps (grad rho1^2 parallel to grad g,
        # or rho outside [1, 40]): 11 solutions, 6 of them the cusps.
        "expect": {"ibex": 11},
        "stored": {"ibex": STORED_IBEX.format("0.604 s, 11 sol (6 cusps)")},
    },
]


def slug(name):
    return re.sub(r"[^a-z0-9]+", "_", name.lower()).strip("_")


def model_files(case):
    """(file name, text) of the case's models."""
    out = [(f"{slug(case['name'])}.mbx", m.minibex(case["ibex"]()))]
    if case["phc"]:
        out.append((f"{slug(case['name'])}.phc", m.phc(case["phc"]())))
    return out


# ---------------------------------------------------------------- running a child


def measure(cmd, cwd=ROOT):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, proc


def linkspace_summary(kind, report):
    if kind == "solve":
        st = report["stats"]
        return (f"{len(report['solutions'])} boxes, {st.get('certified', 0)} certified, {report.get('clusters')} clusters, "
                f"{len(report['undecided'])} undecided, {st['processed']} processed")
    if kind == "distances":
        return f"{report['placements']} placements, {report['proven']} proven, {len(report['undecided'])} undecided"
    cusps = report.get("cusps", [])
    return f"{len(cusps)} cusps, status {report.get('status')}"


def run_linkspace(exe, case, repeat):
    times, summary = [], None
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "report.json"
        cmd = [str(exe)] + case["linkspace"] + ["--threads", "1", "--json", str(out)]
        for _ in range(repeat):
            cpu, proc = measure(cmd)
            if proc.returncode != 0:
                return None, f"failed: {proc.stderr.strip()[-200:]}"
            times.append(cpu)
            summary = linkspace_summary(case["linkspace"][0], json.loads(out.read_text()))
    return statistics.median(times), summary


def parse_ibex(text):
    """(solutions, unknown) from ibexsolve's report (inner + boundary boxes; unknown + pending)."""
    sol, unk, seen = 0, 0, False
    for line in text.lower().splitlines():
        if "number of" not in line:
            continue
        words = line.split()
        if not words or not words[-1].isdigit():
            continue
        n = int(words[-1])
        if "inner" in line or "boundary" in line or "solution" in line:
            sol, seen = sol + n, True
        elif "unknown" in line or "pending" in line:
            unk += n
    return (sol, unk) if seen else None


def run_ibex(exe, case, path, precision=1e-4):
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [str(exe), "-e", f"{precision:g}"] + case.get("ibex_args", []) + ["-o", str(Path(tmp) / "out.cov"), str(path)]
        cpu, proc = measure(cmd, cwd=tmp)
    counts = parse_ibex(proc.stdout)
    if counts is None:
        return cpu, f"no report ({proc.stderr.strip()[-200:]})"
    return cpu, f"{counts[0]} sol, {counts[1]} unk"


def parse_phc(text):
    def count(label):
        mm = re.search(rf"Number of {label}\s*:\s*(\d+)", text)
        return int(mm.group(1)) if mm else None

    mv = re.search(r"mixed volume : (\d+)", text)
    return {"mixed volume": int(mv.group(1)) if mv else None, "regular": count("regular solutions"),
            "real": count("real solutions"), "failures": count("failures")}


def run_phc(exe, path):
    with tempfile.TemporaryDirectory() as tmp:
        # phc -b appends its solutions to the input file: it runs on a copy.
        model = Path(tmp) / path.name
        shutil.copyfile(path, model)
        out = Path(tmp) / "out.phc"
        cpu, proc = measure([str(exe), "-b", str(model), str(out)], cwd=tmp)
        text = out.read_text() if out.exists() else ""
    c = parse_phc(text)
    if c["regular"] is None:
        return cpu, f"no report ({proc.stderr.strip()[-200:]})", c
    return cpu, f"mixed volume {c['mixed volume']}, {c['regular']} regular, {c['real']} real, {c['failures']} failed paths", c


# ---------------------------------------------------------------- the model check


def newton(residual, names, point, iterations=30):
    """Newton on a square system given by `residual(point) -> list`, central-difference Jacobian."""
    x = [point[n] for n in names]
    for _ in range(iterations):
        f = residual(dict(zip(names, x)))
        if max(abs(v) for v in f) < 1e-14:
            break
        J = []
        for j in range(len(x)):
            h = 1e-7 * max(1.0, abs(x[j]))
            xp, xm = list(x), list(x)
            xp[j] += h
            xm[j] -= h
            fp, fm = residual(dict(zip(names, xp))), residual(dict(zip(names, xm)))
            J.append([(a - b) / (2 * h) for a, b in zip(fp, fm)])
        J = [list(r) for r in zip(*J)]  # rows: equations
        step = solve_linear(J, [-v for v in f])
        x = [a + b for a, b in zip(x, step)]
    return dict(zip(names, x))


def solve_linear(A, b):
    n = len(b)
    M = [row[:] + [b[i]] for i, row in enumerate(A)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(M[r][c]))
        M[c], M[p] = M[p], M[c]
        for r in range(c + 1, n):
            f = M[r][c] / M[c][c]
            for k in range(c, n + 1):
                M[r][k] -= f * M[c][k]
    x = [0.0] * n
    for r in reversed(range(n)):
        x[r] = (M[r][n] - sum(M[r][k] * x[k] for k in range(r + 1, n))) / M[r][r]
    return x


def scaled(residual, names, x):
    """Each residual over the size of its first-order terms at x, 1 + sum_j |df/dx_j| |x_j|: the
    systems' scales differ by orders of magnitude (the 3-RPR cusp rows reach 1e10)."""
    f = residual(x)
    size = [1.0] * len(f)
    for n in names:
        h = 1e-7 * max(1.0, abs(x[n]))
        fp = residual(dict(x, **{n: x[n] + h}))
        fm = residual(dict(x, **{n: x[n] - h}))
        size = [s + abs((a - b) / (2 * h)) * abs(x[n]) for s, a, b in zip(size, fp, fm)]
    return max(abs(v) / s for v, s in zip(f, size))


def write_references(exe):
    """linkspace's solutions of each case, as points of the Ibex models (box midpoints and
    half-widths, or the reported pose where there is no box)."""
    refs = {}
    with tempfile.TemporaryDirectory() as tmp:
        for case in CASES:
            if case["name"].startswith("Stewart"):
                continue  # the JSON references of tests/data are used
            out = Path(tmp) / "r.json"
            subprocess.run([str(exe)] + case["linkspace"] + ["--threads", "1", "--json", str(out)], cwd=ROOT,
                           check=True, capture_output=True)
            rep = json.loads(out.read_text())
            mid = lambda iv: 0.5 * (iv[0] + iv[1])
            half = lambda iv: 0.5 * (iv[1] - iv[0])
            pts = []
            if case["name"].startswith("butterfly"):
                for s in rep["solutions"]:
                    a = s["link_angles"]
                    pts.append({"point": {f"th{i}": mid(a[f"link{i}"]) for i in (1, 2, 3, 4, 5, 7)},
                                "tolerance": max(half(a[f"link{i}"]) for i in (1, 2, 3, 4, 5, 7))})
            elif case["name"].startswith("four spheres"):
                for s in rep["solutions"]:
                    for p in s["points"]:
                        t, u = p["t"], p["u"]
                        pt = {f"x{k + 1}": t[k] - p["c1"][k] for k in range(3)}
                        pt.update({f"d{k + 1}": u[k] - t[k] for k in range(3)})
                        pts.append({"point": pt, "tolerance": 1e-3})
            elif case["name"].startswith("octahedral"):
                for s in rep["solutions"]:
                    for pose in s["poses"]:
                        pts.append({"point": m.octahedral_platform_points(pose), "tolerance": 1e-2})
            elif case["name"] == "delta":
                for s in rep["solutions"]:
                    j = s["joints"]
                    pts.append({"point": {"px": mid(j["platform_x"]), "py": mid(j["platform_y"]), "pz": mid(j["platform_z"])},
                                "tolerance": max(half(j[k]) for k in ("platform_x", "platform_y", "platform_z"))})
            elif case["name"].startswith("spherical"):
                for s in rep["solutions"]:
                    j = s["joints"]
                    pts.append({"point": {"coupler": mid(j["coupler_joint"]), "rocker": mid(j["rocker_joint"])},
                                "tolerance": max(half(j["coupler_joint"]), half(j["rocker_joint"]))})
            elif case["name"].startswith("3-RPR"):
                for c in rep["cusps"]:
                    j = c["joints"]
                    a1, b1, r1 = mid(j["a1_joint"]), mid(j["b1_joint"]), mid(j["rho1"])
                    phi = math.remainder(a1 + b1, 2 * math.pi)
                    pts.append({"point": {"x": r1 * math.cos(a1), "y": r1 * math.sin(a1), "phi": phi},
                                "tolerance": max(half(j["rho1"]), half(j["a1_joint"]) * r1, half(j["b1_joint"]) + half(j["a1_joint"]))})
            refs[case["name"]] = pts
    REFERENCES.write_text(json.dumps(refs, indent=1) + "\n")
    print(f"wrote {REFERENCES.relative_to(ROOT)}")


def ibex_to_phc(case, point):
    """A point of the Ibex model as a point of the PHC model (cos/sin variables for angle models)."""
    name = case["name"]
    if name.startswith("butterfly"):
        out = {}
        for i in (1, 2, 3, 4, 5, 7):
            out[f"c{i}"], out[f"s{i}"] = math.cos(point[f"th{i}"]), math.sin(point[f"th{i}"])
        return out
    if name.startswith("spherical"):
        c, r = point["coupler"], point["rocker"]
        return {"cc": math.cos(c), "sc": math.sin(c), "cr": math.cos(r), "sr": math.sin(r)}
    return point


def check_models(verbose=True):
    refs = json.loads(REFERENCES.read_text())
    data = m.stewart_data()
    failures = []
    for case in CASES:
        files = model_files(case)
        for fname, text in files:
            stored = MODELS / fname
            if not stored.exists() or stored.read_text() != text:
                failures.append(f"{fname}: differs from the generated model (run --write-models)")
        mbx = files[0][1]
        names = list(m.minibex_domain(mbx))
        n_eq = len(m.eval_minibex(mbx, {n: 0.5 for n in names})[0])
        if case["name"].startswith("Stewart"):
            pairs = m.stewart_references(data)
            points = [{"point": p, "tolerance": 1e-12} for p, _ in pairs]
        else:
            points = refs[case["name"]]
        worst_res, worst_move, found = 0.0, 0.0, []
        for ref in points:
            start = ref["point"]
            fn = (lambda p: m.eval_minibex(mbx, p)[0])
            x = newton(fn, names, start) if n_eq == len(names) else start
            _, ineqs = m.eval_minibex(mbx, x)
            res = scaled(fn, names, x)
            move = max(abs(x[n] - start[n]) for n in names)
            worst_res, worst_move = max(worst_res, res), max(worst_move, move)
            if res > 1e-12:
                failures.append(f"{case['name']}: Minibex residual {res:.1e} at a reference")
            if move > ref["tolerance"] + 1e-9:
                failures.append(f"{case['name']}: Newton moved {move:.1e} from a reference (tolerance {ref['tolerance']:.1e})")
            if any(v < -1e-12 for v in ineqs):
                failures.append(f"{case['name']}: an inequality fails at a reference")
            dom = m.minibex_domain(mbx)
            if any(not (dom[n][0] <= x[n] <= dom[n][1]) for n in names):
                failures.append(f"{case['name']}: a reference lies outside the variables' ranges")
            if all(max(abs(x[n] - y[n]) for n in names) > 1e-6 for y in found):
                found.append(x)
            if len(files) > 1:
                if case["name"].startswith("Stewart"):
                    pp = next(q for p, q in pairs if p is start)
                else:
                    pp = ibex_to_phc(case, x)
                pres = scaled(lambda p: m.eval_phc(files[1][1], p), list(pp), pp)
                worst_res = max(worst_res, pres)
                if pres > 1e-12:
                    failures.append(f"{case['name']}: PHC residual {pres:.1e} at a reference")
        want = case["expect"]["ibex"]
        real_sought = 6 if case["name"].startswith("3-RPR") else want
        if len(found) != real_sought:
            failures.append(f"{case['name']}: {len(found)} distinct references, {real_sought} expected")
        if verbose:
            print(f"{case['name']}: {len(found)} distinct known solutions; max residual {worst_res:.1e} "
                  f"(Minibex{' and PHC' if len(files) > 1 else ''} text); max Newton move {worst_move:.1e}")
    for f in failures:
        print("FAIL", f)
    print("models: ok" if not failures else f"models: {len(failures)} failures")
    return not failures


# ---------------------------------------------------------------- the table


def fmt_ratio(peer, ours):
    if not peer or not ours:
        return "-"
    r = peer / ours
    return f"{r:.2f}x" if r < 10 else f"{r:.1f}x"


def table(args):
    exe = ROOT / args.linkspace
    ibex = shutil.which("ibexsolve")
    phc = shutil.which("phc")
    print(f"linkspace: {exe.relative_to(ROOT) if exe.is_relative_to(ROOT) else exe} --threads 1; "
          f"ibexsolve: {ibex or 'not on PATH'}; phc: {phc or 'not on PATH'}; CPU s of the child, median of {args.repeat}\n")
    rows = []
    for case in CASES:
        if args.only and not any(o.lower() in case["name"].lower() for o in args.only):
            continue
        names = dict(model_files(case))
        stem = slug(case["name"])
        ours, peers = [], {"ibex": [], "phc": []}
        summary = {"ibex": None, "phc": None}
        ls_summary = None
        for _ in range(args.repeat):  # interleaved: one run of each solver per repetition
            t, ls_summary = run_linkspace(exe, case, 1)
            if t is None:
                break
            ours.append(t)
            if ibex:
                t, summary["ibex"] = run_ibex(ibex, case, MODELS / f"{stem}.mbx")
                peers["ibex"].append(t)
            if phc and f"{stem}.phc" in names:
                t, summary["phc"], counts = run_phc(phc, MODELS / f"{stem}.phc")
                peers["phc"].append(t)
                want = case["expect"].get("phc_real")
                if counts["real"] is not None and want is not None and counts["real"] != want:
                    summary["phc"] += f" (documented: {want} real)"
        t_ours = statistics.median(ours) if ours else None
        ours_text = f"{t_ours:.4f}" if t_ours is not None else "-"
        peer_cells = []
        for key, label in (("ibex", "Ibex"), ("phc", "PHCpack")):
            if peers[key]:
                t = statistics.median(peers[key])
                same = key == "ibex" or case.get("phc_same", True)
                ratio = fmt_ratio(t, t_ours) if same else "- (a wider problem)"
                peer_cells.append((label, f"{t:.4f}", summary[key], ratio))
            elif key in case["stored"]:
                peer_cells.append((label, "-", case["stored"][key], "-"))
            elif key == "phc" and f"{stem}.phc" in names:
                peer_cells.append((label, "-", "phc not on PATH", "-"))
        for i, (label, t, s, r) in enumerate(peer_cells or [("-", "-", "-", "-")]):
            rows.append((case["name"] if i == 0 else "", ours_text if i == 0 else "", ls_summary if i == 0 else "", label, t, s, r))
    print("| case | linkspace CPU s | linkspace result | peer | peer CPU s | peer result | peer / linkspace |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join(str(c) for c in r) + " |")
    print("\nRatios only where both ran here on the same problem; \"stored\" cells are dated references "
          "from the 2026-11-25 runs (2 shared vCPUs, CPU s median of 3), not measured now.")
    print("PHC solves the complex system without inequalities (all real roots, every branch), Ibex and linkspace the real one in its ranges.")
    if args.bench3r:
        lab = ROOT / args.linkspace_lab
        print(f"\n3R cusps and nodes: {lab.name} bench3r --repeat {args.repeat}\n")
        proc = subprocess.run([str(lab), "bench3r", "--repeat", str(args.repeat)], cwd=ROOT, capture_output=True, text=True)
        print(proc.stdout)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check-models", action="store_true", help="evaluate the peer models at the known solutions and exit")
    ap.add_argument("--write-models", action="store_true", help="regenerate scripts/peers/models/ and exit")
    ap.add_argument("--write-references", action="store_true", help="record linkspace's solutions in references.json and exit")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--only", nargs="*", help="cases whose name contains one of these words")
    ap.add_argument("--bench3r", action="store_true", help="append linkspace-lab bench3r's 3R cusp and node rows")
    ap.add_argument("--linkspace", default="target/release/linkspace")
    ap.add_argument("--linkspace-lab", default="target/release/linkspace-lab")
    args = ap.parse_args()
    if args.write_models:
        MODELS.mkdir(exist_ok=True)
        for case in CASES:
            for fname, text in model_files(case):
                (MODELS / fname).write_text(text)
                print(f"wrote {(MODELS / fname).relative_to(ROOT)}")
        return 0
    if args.write_references:
        write_references(ROOT / args.linkspace)
        return 0
    if args.check_models:
        return 0 if check_models() else 1
    table(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
