"""On every bundled file, a question asked from Python answers what the CLI answers: `to_dict()`
equals the CLI's `--json` report of the same run (times aside), and a request the CLI refuses
raises with the CLI's message. The typed attributes agree with the report they are read from."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import linkspace
from conftest import ROOT, URDF, run_cli, without_timing

LINKAGES = ["bennett", "delta", "double_butterfly", "five_bar", "five_bar_unequal", "four_bar", "rssr", "slider_crank", "spherical_four_bar",
            "stewart_40", "stewart_40_near_singular", "stewart_6_6", "three_rpr", "watt_six_bar"]
ARMS = ["iiwa14", "kuka_kr16", "orthogonal_3r_a", "orthogonal_3r_a_column", "orthogonal_3r_b", "orthogonal_3r_c", "orthogonal_3r_d", "orthogonal_3r_e",
        "orthogonal_3r_f", "orthogonal_3r_near_boundary", "puma560", "staubli_tx90", "ur5"]
SIX_R = ["kuka_kr16", "puma560", "staubli_tx90", "ur5"]
OCTAHEDRAL = {"leg15": 4.25, "leg16": 5.75, "leg26": 4.25, "leg24": 5.75, "leg34": 4.25, "leg35": 5.75}

# (file, method, positional argument, keyword arguments, the CLI's arguments after the file).
CASES: list[tuple[str, str, Any, dict[str, Any], list[str]]] = (
    [(f"{n}.urdf", "solve", None, {"max_boxes": 300}, ["--max-boxes", "300"]) for n in LINKAGES]
    + [
        ("double_butterfly.urdf", "solve", {"joint6": 1.1760052070951352}, {"precision": 1e-4}, ["--fix", "joint6=1.1760052070951352", "--precision", "1e-4"]),
        ("four_bar.urdf", "solve", {"crank_joint": 0.7}, {"trace": ["coupler@2,1"]}, ["--fix", "crank_joint=0.7", "--trace", "coupler@2,1"]),
        ("bennett.urdf", "solve", None, {"model": "spatial", "max_boxes": 300, "no_lp": True}, ["--model", "spatial", "--max-boxes", "300", "--no-lp"]),
    ]
    + [(f"{n}.urdf", "singularities", None, {}, []) for n in ARMS]
    + [
        ("orthogonal_3r_e.urdf", "singularities", None, {"nodes": True}, ["--nodes"]),
        ("orthogonal_3r_f.urdf", "singularities", None, {"kind": "nodes"}, ["--kind", "nodes"]),
        ("iiwa14.urdf", "singularities", None, {"fix": {"joint_3": 0.0}}, ["--fix", "joint_3=0"]),
        ("orthogonal_3r_a.urdf", "singularities", None, {"kind": "cusps", "nodes": True}, ["--kind", "cusps", "--nodes"]),
    ]
    + [(f"{n}.urdf", "ik", [0.5, 0.2, 0.3], {}, ["--point", "0.5,0.2,0.3"]) for n in ARMS]
    + [("orthogonal_3r_a.urdf", "ik", [1.2, 0.3], {}, ["--point", "1.2,0.3"])]
    + [(f"{n}.urdf", "ik6", [0.4, 0.2, 0.5, 0.0, 1.5, 0.0], {}, ["--pose", "0.4,0.2,0.5,0,1.5,0"]) for n in SIX_R]
    + [
        ("ur5.urdf", "ik6", [0.3, 0.2, 0.4, 0.0, 0.0, 0.0, 1.0], {"ignore_limits": True}, ["--pose", "0.3,0.2,0.4,0,0,0,1", "--ignore-limits"]),
        ("four_bar.urdf", "ik6", [0.3, 0.2, 0.4, 0.0, 0.0, 0.0], {}, ["--pose", "0.3,0.2,0.4,0,0,0"]),
        ("ur5.urdf", "path_check", [[0, -1, 1, 0, 1, 0], [0.5, -1, 1.2, 0, 1, 0], [0.5, -1, 1.2, 0, -1, 0]], {}, ["--waypoints", "0,-1,1,0,1,0;0.5,-1,1.2,0,1,0;0.5,-1,1.2,0,-1,0"]),
        ("puma560.urdf", "path_check", [[0, 0.5, 1, 0, 1, 0], [0, 0.5, -1, 0, 1, 0]], {"singular_set": "3r"}, ["--waypoints", "0,0.5,1,0,1,0;0,0.5,-1,0,1,0", "--singular-set", "3r"]),
        ("orthogonal_3r_a.urdf", "path_check", [[0, 0, 0], [0, -1.4, -3.0]], {}, ["--waypoints", "0,0,0;0,-1.4,-3.0"]),
        ("orthogonal_3r_a_column.urdf", "collisions", None, {}, []),
        ("orthogonal_3r_a.urdf", "collisions", None, {}, []),
        ("octahedral.urdf", "distances", OCTAHEDRAL, {}, [a for k, v in OCTAHEDRAL.items() for a in ("--fix", f"{k}={v}")]),
        ("four_spheres.json", "distances", None, {}, []),
        ("four_spheres.json", "distances", None, {"formulation": "shared", "max_boxes": 200}, ["--formulation", "shared", "--max-boxes", "200"]),
        ("four_bar.urdf", "loop_singularities", None, {}, []),
        ("slider_crank.urdf", "loop_singularities", None, {"kind": "input", "actuated": ["crank"]}, ["--kind", "input", "--actuated", "crank"]),
        ("five_bar.urdf", "loop_singularities", None, {"kind": "cusps", "max_boxes": 2000}, ["--kind", "cusps", "--max-boxes", "2000"]),
        ("four_bar.urdf", "loop_singularities", None, {"kind": "motion"}, ["--kind", "motion"]),
    ]
)

SUBCOMMAND = {"path_check": "path-check", "loop_singularities": "loop-singularities"}


def ask(m: linkspace.Mechanism, method: str, positional: Any, kwargs: dict[str, Any]) -> linkspace.Result:
    call = getattr(m, method)
    return call(positional, **kwargs) if positional is not None else call(**kwargs)  # type: ignore[no-any-return]


@pytest.mark.parametrize(("file", "method", "positional", "kwargs", "args"), CASES, ids=[f"{c[1]}-{c[0]}-{i}" for i, c in enumerate(CASES)])
def test_python_answers_what_the_cli_answers(file: str, method: str, positional: Any, kwargs: dict[str, Any], args: list[str], tmp_path: Path) -> None:
    assert (URDF / file).exists()
    cli, message = run_cli([SUBCOMMAND.get(method, method), f"urdf/{file}", *args], tmp_path)
    if cli is None:
        with pytest.raises(linkspace.Error) as raised:
            ask(_load(file), method, positional, kwargs)
        assert str(raised.value) == message
        return
    result = ask(_load(file), method, positional, kwargs)
    got = result.to_dict()
    assert without_timing(got) == without_timing(cli)
    # The report's status is the answer's completeness, by the one rule.
    reports = got if isinstance(got, list) else [got]
    if all("status" in r for r in reports):
        assert result.completeness.complete == all(r["status"] == "complete" for r in reports), (result.completeness, [r["status"] for r in reports])
    check_typed(result, got)


def _load(file: str) -> linkspace.Mechanism:
    # Relative to the repository, as the CLI was given it, so messages name the same path.
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        return linkspace.load(f"urdf/{file}")
    finally:
        os.chdir(cwd)


def _bounds(records: list[dict[str, Any]], key: str, columns: tuple[str, ...]) -> np.ndarray:
    return np.array([[r[key][c] for c in columns] for r in records], dtype=np.float64).reshape(len(records), len(columns), 2)


def check_typed(result: linkspace.Result, report: Any) -> None:
    """The typed attributes say what the report says."""
    if isinstance(result, linkspace.SolveResult):
        records = report["solutions"] + report["undecided"]
        assert result.boxes.columns == tuple(report["free_joints"])
        b = _bounds(records, "joints", result.boxes.columns)
        assert np.array_equal(result.boxes.lo, b[:, :, 0]) and np.array_equal(result.boxes.hi, b[:, :, 1])
        assert np.array_equal(result.variables.lo, np.array([[iv[0] for iv in r["box"]] for r in records]).reshape(len(records), -1))
        assert list(result.boxes.tags) == ["unique" if r["unique"] else "solution" for r in report["solutions"]] + ["undecided"] * len(report["undecided"])
        assert result.clusters == report["clusters"]
        assert result.boxes.clusters.max(initial=-1) + 1 == report["clusters"]
        assert all(c == -1 for c in result.boxes.clusters[len(report["solutions"]):])
        for name in {t for r in records for t in r["traces"]}:
            t = result.trace(name)
            assert np.array_equal(t.lo[:, 0], [r["traces"][name]["x"][0] for r in records])
    elif isinstance(result, linkspace.SingularitiesResult):
        assert len(result.cusps) == len(report["cusps"]) + len(report["undecided"]["cusps"])
        assert (result.nodes is None) == (report["nodes"] is None)
        if report.get("verdict") is not None:
            v = result.verdict
            assert v is not None and v.value == report["verdict"]["cuspidal"] and v.scope.kind == report["verdict"]["scope"]["kind"]
    elif isinstance(result, linkspace.IkResult):
        b = _bounds(report["solutions"], "joints", result.solutions.columns)
        assert np.array_equal(result.solutions.lo, b[:, :, 0])
        assert list(result.solutions.tags) == ["unique" if s["unique"] else "solution" for s in report["solutions"]]
    elif isinstance(result, linkspace.Ik6Result):
        assert result.solutions.columns == tuple(report["joints"])
        assert len(result.solutions.with_tag("unique")) == len(report["unique"])
        assert len(result.solutions.undecided) == len(report["clusters"])
    elif isinstance(result, linkspace.PathCheckResult):
        assert [s.value for s in result.segments] == [s["verdict"] for s in report["segments"]]
        assert sum(result.counts.values()) == len(report["segments"])
    elif isinstance(result, linkspace.CollisionsResult):
        assert len(result.boxes) == len(report["colliding"]) + len(report["free"]) + len(report["undecided"])
    elif isinstance(result, linkspace.DistancesResult):
        assert len(result.solutions.solutions) == len(report["solutions"])
        assert result.clusters == report["clusters"]
    elif isinstance(result, linkspace.LoopSingularitiesResult) and isinstance(report, list):
        assert [s.kind for s in result.sets] == [r["kind"] for r in report]
        assert [len(s.boxes) for s in result.sets] == [len(r["boxes"]) for r in report]
