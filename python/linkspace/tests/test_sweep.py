"""`linkspace.sweep` runs a design sweep as `linkspace sweep SPEC --out DIR` does: the same
result lines, table, summary and map (times aside), in the same files."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import linkspace
from conftest import ROOT, cli_binary

TIMES = ("seconds", "task_seconds", "wall_seconds")


def small_spec(tmp_path: Path) -> Path:
    """The bundled cuspidality sweep on a 3 × 3 grid at precision 1e-3."""
    spec = json.loads((ROOT / "examples/sweeps/orthogonal_3r_cuspidality.json").read_text())
    spec["urdf"] = str(ROOT / "examples/sweeps" / spec["urdf"])
    for p in spec["parameters"]:
        p["steps"] = 3
    spec["precision"] = 1e-3
    path = tmp_path / "spec.json"
    path.write_text(json.dumps(spec))
    return path


def timeless(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: timeless(x) for k, x in v.items() if k not in TIMES}
    return v


def test_a_sweep_writes_what_the_cli_writes(tmp_path: Path) -> None:
    spec = small_spec(tmp_path)
    p = subprocess.run([str(cli_binary()), "sweep", str(spec), "--out", str(tmp_path / "cli")], capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert p.returncode == 0, p.stderr
    seen: list[linkspace.Progress] = []
    r = linkspace.sweep(spec, out=tmp_path / "py", progress=seen.append)
    cli_lines = (tmp_path / "cli/results.jsonl").read_text().splitlines()
    py_lines = (tmp_path / "py/results.jsonl").read_text().splitlines()
    assert py_lines[0] == cli_lines[0], "the same header (fingerprint, parameters, tasks)"
    by_index = lambda lines: sorted((json.loads(x) for x in lines[1:]), key=lambda d: d["index"])  # noqa: E731
    assert [timeless(d) for d in by_index(py_lines)] == [timeless(d) for d in by_index(cli_lines)]
    assert [timeless(d) for d in r.rows] == [timeless(d) for d in by_index(cli_lines)]
    assert timeless(json.loads((tmp_path / "py/summary.json").read_text())) == timeless(json.loads((tmp_path / "cli/summary.json").read_text())) == timeless(r.summary)
    strip = lambda csv: [",".join(c for i, c in enumerate(line.split(",")) if i != 9) for line in csv.splitlines()]  # noqa: E731
    assert strip(r.csv) == strip((tmp_path / "cli/results.csv").read_text())
    assert (tmp_path / "py/map.svg").exists() and r.map_svg is not None and r.map_svg.startswith("<svg")
    assert r.labels == ("d3", "d4") and r.values.shape == (9, 2)
    assert np.array_equal(r.values, [d["values"] for d in by_index(cli_lines)])
    assert set(r.column("verdict")) <= {"cuspidal", "non_cuspidal", "undecided"}
    assert seen and seen[-1].processed <= 9
    # A directory holding results is not overwritten.
    with pytest.raises(linkspace.InputError, match="exists"):
        linkspace.sweep(spec, out=tmp_path / "py")


def test_a_bad_spec_raises_with_the_cli_message(tmp_path: Path) -> None:
    spec = tmp_path / "bad.json"
    spec.write_text(json.dumps({"urdf": str(ROOT / "urdf/orthogonal_3r_a.urdf"), "analysis": "cuspidality", "parameters": []}))
    p = subprocess.run([str(cli_binary()), "sweep", str(spec), "--out", str(tmp_path / "o")], capture_output=True, text=True, cwd=ROOT)
    assert p.returncode != 0
    message = p.stderr.strip().splitlines()[-1].removeprefix("error: ")
    with pytest.raises(linkspace.InputError) as raised:
        linkspace.sweep(spec)
    assert str(raised.value) == message
