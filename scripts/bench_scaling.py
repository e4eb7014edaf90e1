#!/usr/bin/env python3
"""Whole runs on threads and MPI ranks: wall time, the search's share of it, and each rank's peak
memory, for `linkspace solve` on the same problem in one invocation.

For each problem, one after another (never two runs at once):
- one process on 1 and on 2 threads (`--threads N`);
- `mpirun -np 1` and `mpirun -np 2`, one thread per rank, each rank under `/usr/bin/time`
  (its peak resident memory, read from a file per rank).
Wall time is the whole command, start-up, post-processing and the JSON report included; the
search's own seconds are the report's `stats.seconds`. Efficiency at 2 is the 1-worker wall
time over twice the 2-worker one, each against its own kind (threads against one thread,
ranks against `mpirun -np 1`). Every report is compared with the others of its problem (times
and the thread count left out): a difference is printed, since the boxes must be the same.

    sh scripts/mpi_env.sh && cargo build --release --features mpi --bin linkspace --target-dir target/mpi
    python3 scripts/bench_scaling.py --linkspace target/mpi/release/linkspace [--repeat 3]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

PROBLEMS = [
    ("five-bar, sigma 0.1", ["urdf/five_bar.urdf", "--sigma", "0.1"]),
    ("five-bar, sigma 0.05", ["urdf/five_bar.urdf", "--sigma", "0.05"]),
    ("mobile double butterfly, sigma 0.05", ["urdf/double_butterfly.urdf", "--sigma", "0.05"]),
    ("mobile double butterfly, sigma 0.01", ["urdf/double_butterfly.urdf", "--sigma", "0.01"]),
]


def strip(v):
    """The report without what depends on the run: times, counters, the thread count."""
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if k not in ("stats", "seconds", "cpu_seconds", "threads")}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v


def run(binary, args, threads, ranks, tmp):
    """One run: (wall seconds, search seconds, peak KB per rank, stripped report)."""
    report = os.path.join(tmp, "r.json")
    memory = os.path.join(tmp, "mem")
    cmd = [binary, "solve", *args, "--threads", str(threads), "--json", report]
    env = dict(os.environ)
    if ranks:
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        # Each rank under its own /usr/bin/time, writing its peak to a file named by its rank.
        timed = f'exec /usr/bin/time -f %M -o {memory}.$OMPI_COMM_WORLD_RANK "$@"'
        cmd = ["mpirun", "--oversubscribe", "-np", str(ranks), "sh", "-c", timed, "sh", *cmd]
    else:
        cmd = ["/usr/bin/time", "-f", "%M", "-o", memory + ".0", *cmd]
    t0 = time.perf_counter()
    done = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed: {done.stderr.strip()[-400:]}")
    with open(report) as f:
        r = json.load(f)
    peaks = []
    for k in range(max(ranks, 1)):
        with open(f"{memory}.{k}") as f:
            peaks.append(int(f.read().split()[-1]))
    return wall, r["stats"]["seconds"], peaks, strip(r)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--linkspace", default="target/mpi/release/linkspace", help="a linkspace built with --features mpi")
    ap.add_argument("--repeat", type=int, default=1, help="runs per setting; the median is shown")
    ap.add_argument("--only", help="problems whose label contains this text")
    a = ap.parse_args()
    print(f"# {time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores, {a.linkspace}")
    print("| problem | run | wall (median) | search | efficiency at 2 | peak memory per rank |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for label, args in PROBLEMS:
            if a.only and a.only not in label:
                continue
            reference = None
            walls = {}
            for name, threads, ranks in [("1 thread", 1, 0), ("2 threads", 2, 0), ("1 rank", 1, 1), ("2 ranks", 1, 2)]:
                runs = [run(a.linkspace, args, threads, ranks, tmp) for _ in range(a.repeat)]
                wall = statistics.median(r[0] for r in runs)
                search = statistics.median(r[1] for r in runs)
                peaks = runs[-1][2]
                walls[name] = wall
                one = {"2 threads": "1 thread", "2 ranks": "1 rank"}.get(name)
                eff = f"{100 * walls[one] / (2 * wall):.0f} %" if one else ""
                mem = ", ".join(f"{p / 1024:.0f} MB" for p in peaks)
                # One thread walks depth first, more threads and ranks level by level: the same
                # boxes, in another order; the level-by-level runs must agree exactly.
                if threads > 1 or ranks > 1:
                    if reference is None:
                        reference = runs[-1][3]
                    elif runs[-1][3] != reference:
                        print(f"REPORTS DIFFER: {label}, {name}", file=sys.stderr)
                print(f"| {label} | {name} | {wall:.2f} s | {search:.2f} s | {eff} | {mem} |", flush=True)


if __name__ == "__main__":
    main()
