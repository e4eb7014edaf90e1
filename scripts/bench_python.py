"""The Python binding's overhead per call: each bundled problem asked through `linkspace` (the
Python package) against the library's own time for the same job in the same process
(`Result.seconds`: `app::prepare` to the end of `Prepared::run`, on the worker thread), and the
CLI's wall time for the same command beside it. A benchmark, not a test.

Usage (from the repository root, in the venv of scripts/python_env.sh):
    target/py-venv/bin/python scripts/bench_python.py [REPEATS]
Prints a Markdown table: median Python call, median library time, their difference (the
binding's overhead, in microseconds) and its share of the call, and the CLI's median wall time.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Callable

import linkspace

ROOT = Path(__file__).resolve().parents[1]
CLI = ROOT / "target" / "release" / "linkspace"

PROBLEMS: list[tuple[str, Callable[[], Any], list[str]]] = []


def problem(label: str, file: str, method: str, args: tuple[Any, ...], kwargs: dict[str, Any], cli: list[str]) -> None:
    m = linkspace.load(str(ROOT / file))
    PROBLEMS.append((label, lambda: getattr(m, method)(*args, **kwargs), cli))


problem("solve double_butterfly (fixed joint6, 1e-4)", "urdf/double_butterfly.urdf", "solve", ({"joint6": 1.1760052070951352},), {"precision": 1e-4},
        ["solve", "urdf/double_butterfly.urdf", "--fix", "joint6=1.1760052070951352", "--precision", "1e-4"])
problem("solve four_bar (fixed crank)", "urdf/four_bar.urdf", "solve", ({"crank_joint": 0.5},), {}, ["solve", "urdf/four_bar.urdf", "--fix", "crank_joint=0.5"])
problem("solve four_bar curve (2e-3)", "urdf/four_bar.urdf", "solve", (), {"precision": 2e-3}, ["solve", "urdf/four_bar.urdf", "--precision", "2e-3"])
problem("singularities orthogonal_3r_e --nodes", "urdf/orthogonal_3r_e.urdf", "singularities", (), {"nodes": True}, ["singularities", "urdf/orthogonal_3r_e.urdf", "--nodes"])
problem("ik orthogonal_3r_a", "urdf/orthogonal_3r_a.urdf", "ik", ([2.0, 0.5, 1.0],), {}, ["ik", "urdf/orthogonal_3r_a.urdf", "--point", "2,0.5,1"])
problem("ik6 ur5", "urdf/ur5.urdf", "ik6", ([0.3, 0.2, 0.4, 0.0, 1.5, 0.0],), {}, ["ik6", "urdf/ur5.urdf", "--pose", "0.3,0.2,0.4,0,1.5,0"])
problem("path-check ur5 (1 segment)", "urdf/ur5.urdf", "path_check", ([[0, -1, 1, 0, -0.4, 0], [0, -1, 1, 0, 0.6, 0]],), {},
        ["path-check", "urdf/ur5.urdf", "--waypoints", "0,-1,1,0,-0.4,0;0,-1,1,0,0.6,0"])
problem("distances four_spheres", "urdf/four_spheres.json", "distances", (), {}, ["distances", "urdf/four_spheres.json"])
problem("loop-singularities four_bar", "urdf/four_bar.urdf", "loop_singularities", (), {}, ["loop-singularities", "urdf/four_bar.urdf"])


def main() -> None:
    repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    print(f"| problem | Python call (ms) | library (ms) | overhead (µs) | overhead / call | CLI wall (ms) |")
    print("|---|---:|---:|---:|---:|---:|")
    for label, call, cli in PROBLEMS:
        call()  # warm: page in the code, fill the allocator
        walls, libs = [], []
        deadline = time.monotonic() + 60
        for _ in range(repeats):
            t0 = time.perf_counter()
            r = call()
            walls.append(time.perf_counter() - t0)
            libs.append(r.seconds)
            if time.monotonic() > deadline:
                break
        over = [w - s for w, s in zip(walls, libs)]
        cli_walls = []
        for _ in range(min(5, len(walls))):
            t0 = time.perf_counter()
            subprocess.run([str(CLI), *cli], cwd=ROOT, capture_output=True, check=True)
            cli_walls.append(time.perf_counter() - t0)
        wall, lib, o = statistics.median(walls), statistics.median(libs), statistics.median(over)
        print(f"| {label} | {1e3 * wall:.3f} | {1e3 * lib:.3f} | {1e6 * o:.0f} | {100 * o / wall:.2f} % | {1e3 * statistics.median(cli_walls):.1f} |", flush=True)


if __name__ == "__main__":
    main()
