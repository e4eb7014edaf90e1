#!/usr/bin/env python3
"""CPU seconds per pose of `linkspace ik6` on the poses of tests/data/ik6_reference.json.

    python3 scripts/dev/ik6_cpu.py BIN [BIN ...] [--fixture general_6r|crx] [--poses N]

Each binary solves every pose (4x4 matrix as written in the reference) with one thread; the
process's user CPU (resource.getrusage of the child) is recorded. Prints, per binary, the median
and maximum, and the certified boxes per pose; binaries given together run in one invocation on
the same poses, so their figures compare. The CLI keeps the file's joint ranges (continuous joints
over more than a turn give a solution's copies), so its counts may exceed the reference's.
"""
import argparse
import json
import os
import resource
import statistics
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("binaries", nargs="+")
    ap.add_argument("--fixture", default="general_6r")
    ap.add_argument("--poses", type=int, default=30)
    args = ap.parse_args()
    ref = json.load(open(os.path.join(ROOT, "tests", "data", "ik6_reference.json")))
    fixture = next(f for f in ref["fixtures"] if f["name"] == args.fixture)
    poses = [p["pose"] for p in fixture["poses"][: args.poses]]
    out = os.path.join(tempfile.mkdtemp(), "ik6.json")
    for binary in args.binaries:
        times, counts = [], []
        for m in poses:
            before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
            subprocess.run([binary, "ik6", os.path.join(ROOT, fixture["urdf"]), "--threads", "1", "--pose",
                            ",".join(repr(x) for row in m for x in row), "--json", out], capture_output=True, check=True)
            times.append(resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime - before)
            counts.append(len(json.load(open(out))["unique"]))
        print(f"{binary}: {args.fixture}, {len(times)} poses, CPU median {statistics.median(times):.4f} s, "
              f"max {max(times):.4f} s; certified boxes {counts}")


if __name__ == "__main__":
    main()
