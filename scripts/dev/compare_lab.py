#!/usr/bin/env python3
"""Two builds of linkspace-lab side by side: each bench command of both binaries, run
alternately in this one invocation (old, new, old, new, ...), every table row's CPU column
compared by its median over the rounds.

    python3 scripts/dev/compare_lab.py OLD_LAB NEW_LAB [--rounds 3] [--commands bench,bench3r,...]

Prints one Markdown table: command, case and variant, the old and new medians, and new/old.
A ratio is only ever between the two binaries run here, never against a stored figure.
"""

import argparse
import statistics
import subprocess
import sys


def rows(text):
    """The data rows of every `a | b | ...` table in a bench's output, keyed by their leading
    text columns, with the first column whose header names CPU or seconds as the time."""
    out = {}
    header = None
    for line in text.splitlines():
        if " | " not in line:
            header = None
            continue
        cells = [c.strip() for c in line.split(" | ")]
        if header is None:
            header = cells
            continue
        timed = [k for k, h in enumerate(header) if "cpu" in h.lower() or h.lower().endswith(" s") or "seconds" in h.lower()]
        if not timed or len(cells) != len(header):
            continue
        k = timed[0]
        try:
            value = float(cells[k])
        except ValueError:
            continue
        key = " / ".join(cells[:k])
        out[key] = value
    return out


def main():
    p = argparse.ArgumentParser()
    p.add_argument("old")
    p.add_argument("new")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--commands", default="bench,bench3r,bench-distances,bench-spatial")
    a = p.parse_args()
    print("| command | case | old s | new s | new/old |")
    print("|---|---|---|---|---|")
    for command in a.commands.split(","):
        times = {"old": {}, "new": {}}
        for _ in range(a.rounds):
            for which in ("old", "new"):
                binary = getattr(a, which)
                run = subprocess.run([binary, command, "--repeat", "1"], capture_output=True, text=True)
                if run.returncode != 0:
                    sys.exit(f"{binary} {command} failed: {run.stderr.strip()[-400:]}")
                for key, value in rows(run.stdout).items():
                    times[which].setdefault(key, []).append(value)
        for key in times["old"]:
            if key not in times["new"]:
                continue
            old, new = statistics.median(times["old"][key]), statistics.median(times["new"][key])
            ratio = new / old if old > 0 else float("nan")
            print(f"| {command} | {key} | {old:.4g} | {new:.4g} | {ratio:.3f} |")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
