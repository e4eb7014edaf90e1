"""The package's surface: what `load` reads, box sets, plots, the stubs under mypy --strict."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import linkspace
from conftest import ROOT, urdf


def test_load_reads_the_joints_loops_and_links_as_the_file_states_them() -> None:
    path = urdf("ur5.urdf")
    m = linkspace.load(path)
    tree = ET.parse(path).getroot()
    assert m.name == tree.get("name") == "ur5"
    joints = tree.findall("joint")
    assert [j.name for j in m.joints] == [j.get("name") for j in joints]
    for j, x in zip(m.joints, joints):
        assert j.type == x.get("type")
        assert j.parent == x.find("parent").get("link") and j.child == x.find("child").get("link")  # type: ignore[union-attr]
        limit = x.find("limit")
        if j.type in ("revolute", "prismatic"):
            assert limit is not None and j.limits == (float(limit.get("lower")), float(limit.get("upper")))  # type: ignore[arg-type]
        else:
            assert j.limits is None
    assert m.loops == [] and set(m.links) == {lk.get("name") for lk in tree.findall("link")}
    assert m.kind == "manipulator_3r" and "inverse_kinematics6" in m.services
    four = linkspace.load(urdf("four_bar.urdf"))
    assert [(lp.name, lp.type, lp.predecessor, lp.successor) for lp in four.loops] == [("loop_coupler_rocker", "revolute", "coupler", "rocker")]
    assert four.kind == "planar_linkage" and four.free_joints
    iiwa = linkspace.load(urdf("iiwa14.urdf"))
    assert iiwa.kind == "manipulator_7r" and iiwa.services == ["self_motion"] and "--fix" in iiwa.limitation
    assert linkspace.load(urdf("four_spheres.json")).kind == "distance_problem"


def test_load_takes_urdf_text_and_path_objects() -> None:
    text = Path(urdf("four_bar.urdf")).read_text()
    a = linkspace.load(text).solve(fix={"crank_joint": 0.7})
    b = linkspace.load(Path(urdf("four_bar.urdf"))).solve(fix={"crank_joint": 0.7})
    assert np.array_equal(a.boxes.lo, b.boxes.lo) and a.clusters == b.clusters == 2


def test_defaults_are_the_jobs() -> None:
    assert linkspace.defaults("ik6")["precision"] == 1e-9
    assert linkspace.defaults("singularities")["max_boxes"] == 5_000_000
    assert linkspace.defaults("singularities")["max_memory"] == 256
    r = linkspace.load(urdf("four_bar.urdf")).solve(fix={"crank_joint": 0.7})
    assert r.to_dict()["settings"]["sigma"] == linkspace.defaults("solve")["precision"] == 1e-3


def test_to_dict_is_the_report_and_results_read_from_it() -> None:
    r = linkspace.load(urdf("double_butterfly.urdf")).solve(fix={"joint6": 1.1760052070951352}, precision=1e-4)
    assert r.to_dict() == json.loads(r.to_json())
    d = r.to_dict()
    d["solutions"].clear()
    assert len(r.to_dict()["solutions"]) == 6, "to_dict returns a copy"
    assert r.question == "solve" and r.complete and r.model == "planar"
    assert "6 solution boxes (6 proven" in repr(r)


def test_box_sets_slice_select_and_measure() -> None:
    r = linkspace.load(urdf("four_bar.urdf")).solve(precision=1e-2, max_boxes=3000)
    b = r.boxes
    assert b.lo.shape == b.hi.shape == (len(b), len(b.columns)) and b.lo.dtype == np.float64
    assert np.all(b.lo <= b.hi)
    assert np.allclose(b.midpoints(), (b.lo + b.hi) / 2) and np.allclose(b.widths(), b.hi - b.lo)
    assert len(b.solutions) + len(b.undecided) == len(b)
    first = b[0]
    assert len(first) == 1 and first.columns == b.columns
    mask = b.tags == "undecided"
    assert len(b[mask]) == int(mask.sum())
    assert np.array_equal(b.column(b.columns[0])[:, 0], b.lo[:, 0])
    mid = b.midpoints()[0]
    assert b.contains(mid)[0]
    both = linkspace.BoxSet.concat([b.solutions, b.undecided])
    assert len(both) == len(b)
    assert r.variables.lo.shape == (len(b), len(r.variables.columns)) and list(r.variables.tags) == list(b.tags)


def test_plot_draws_a_rectangle_per_box() -> None:
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    r = linkspace.load(urdf("four_bar.urdf")).solve(precision=0.05)
    ax = r.boxes.plot(x="crank_joint", y="rocker_joint")
    patches = ax.collections[0].get_paths()
    assert len(patches) == len(r.boxes)
    assert ax.get_xlabel() == "crank_joint" and ax.get_ylabel() == "rocker_joint"
    lo, hi = ax.get_xlim()
    assert lo <= r.boxes.column("crank_joint")[:, 0].min() and hi >= r.boxes.column("crank_joint")[:, 1].max()
    ax2 = r.boxes.plot(color_by="cluster")
    assert len(ax2.collections[0].get_paths()) == len(r.boxes)
    with pytest.raises(ValueError):
        r.boxes.plot(color_by="colour")
    import matplotlib.pyplot as plt

    plt.close("all")


def test_verdicts_carry_value_scope_and_proof() -> None:
    r = linkspace.load(urdf("ur5.urdf")).singularities()
    v = r.verdict
    assert v is not None and v.value is False and v.certified and v.scope.kind == "mechanism" and v.proof
    sub = r.sub_chain_verdict
    assert sub is not None and sub.scope.kind == "sub_chain" and len(sub.scope.joints) == 3 and sub.scope.point
    c = linkspace.load(urdf("orthogonal_3r_a.urdf")).singularities().verdict
    assert c is not None and c.value is True and bool(c) and c.aspects == 2 and c.max_ik_solutions == 4


def test_the_stubs_pass_mypy_strict() -> None:
    mypy = shutil.which("mypy", path=str(Path(sys.executable).parent)) or shutil.which("mypy")
    if mypy is None:
        pytest.skip("mypy is not installed (scripts/python_env.sh installs it)")
    example = ROOT / "python/linkspace/examples/typed_usage.py"
    p = subprocess.run([mypy, "--strict", "--no-incremental", str(example)], capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0, p.stdout + p.stderr
    # The package's own annotations and its extension's stub, from the source tree.
    p = subprocess.run([mypy, "--strict", "--no-incremental", "linkspace"], capture_output=True, text=True, cwd=ROOT / "python/linkspace")
    assert p.returncode == 0, p.stdout + p.stderr
    # A wrong use is caught: a string for a precision.
    bad = Path(example.parent / "_wrong_use.py")
    bad.write_text("import linkspace\nlinkspace.load('x.urdf').solve(precision='fine')\n")
    try:
        p = subprocess.run([mypy, "--strict", "--no-incremental", str(bad)], capture_output=True, text=True, cwd=ROOT)
    finally:
        bad.unlink()
    assert p.returncode != 0 and "precision" in p.stdout, p.stdout


def test_the_example_runs() -> None:
    p = subprocess.run([sys.executable, "python/linkspace/examples/typed_usage.py"], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert p.returncode == 0, p.stderr
    assert "True" in p.stdout and "not a serial chain" in p.stdout


def test_angles_are_radians() -> None:
    # joint6 of the double butterfly fixed at a value in radians lands in the report as given.
    r = linkspace.load(urdf("double_butterfly.urdf")).solve(fix={"joint6": math.pi / 3}, precision=1e-3)
    assert r.fixed_joints == {"joint6": math.pi / 3}
