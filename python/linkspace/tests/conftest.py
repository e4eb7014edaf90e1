"""Shared helpers: the repository's files, the CLI binary, and references computed without the
solver (forward kinematics read straight from the URDF with numpy)."""

from __future__ import annotations

import json
import math
import os
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[3]
URDF = ROOT / "urdf"


def urdf(name: str) -> str:
    return str(URDF / name)


def cli_binary() -> Path:
    """The `linkspace` binary: $LINKSPACE_CLI (the Rust test that runs this suite sets it to the
    binary cargo built), else the release build."""
    path = Path(os.environ.get("LINKSPACE_CLI", ROOT / "target" / "release" / "linkspace"))
    if not path.exists():
        pytest.skip(f"no linkspace binary at {path} (cargo build --release, or set LINKSPACE_CLI)")
    return path


def run_cli(args: list[str], tmp_path: Path) -> tuple[Any, str]:
    """Runs `linkspace ARGS --json FILE` in the repository: (the report, or None when the command
    failed, and its error line without `error: `)."""
    out = tmp_path / f"report-{len(list(tmp_path.iterdir()))}.json"
    p = subprocess.run([str(cli_binary()), *args, "--json", str(out)], cwd=ROOT, capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        lines = [ln for ln in p.stderr.splitlines() if ln.startswith("error: ")]
        assert lines, f"{args}: exit {p.returncode} without an error line: {p.stderr}"
        return None, lines[-1][len("error: "):]
    return json.loads(out.read_text()), ""


TIMING = ("seconds", "cpu_seconds")


def without_timing(value: Any) -> Any:
    """A report without its wall and CPU times, at any depth (the rest is the same for the same
    run on one thread)."""
    if isinstance(value, dict):
        return {k: without_timing(v) for k, v in value.items() if k not in TIMING}
    if isinstance(value, list):
        return [without_timing(v) for v in value]
    return value


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _axis_angle(axis: np.ndarray, q: float) -> np.ndarray:
    k = axis / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(q) * kx + (1 - math.cos(q)) * kx @ kx


def forward_kinematics(path: str, link: str, values: dict[str, float]) -> np.ndarray:
    """The 4x4 pose of `link` in the root frame, from the URDF's joint origins and axes alone
    (revolute and continuous joints turn by `values`, fixed ones not)."""
    tree = ET.parse(path).getroot()
    by_child = {j.find("child").get("link"): j for j in tree.findall("joint")}  # type: ignore[union-attr]
    chain = []
    while link in by_child:
        j = by_child[link]
        chain.append(j)
        link = j.find("parent").get("link")  # type: ignore[union-attr]
    T = np.eye(4)
    for j in reversed(chain):
        o = j.find("origin")
        xyz = [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
        rpy = [float(v) for v in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
        step = np.eye(4)
        step[:3, :3] = _rpy(*rpy)
        step[:3, 3] = xyz
        if j.get("type") in ("revolute", "continuous"):
            a = j.find("axis")
            axis = np.array([float(v) for v in (a.get("xyz") if a is not None else "1 0 0").split()])  # type: ignore[union-attr]
            turn = np.eye(4)
            turn[:3, :3] = _axis_angle(axis, values[j.get("name")])  # type: ignore[index]
            step = step @ turn
        T = T @ step
    return T
