"""Bad input raises under `linkspace.Error`, the right class, with the CLI's one-line message."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import pytest

import linkspace
from conftest import ROOT, run_cli

# (what Python is asked, the CLI's arguments for the same request, the class raised).
CASES: list[tuple[Callable[[], Any], list[str], type[linkspace.Error]]] = [
    (lambda: linkspace.load("urdf/four_bar.urdf").solve(fix={"nope": 1.0}), ["solve", "urdf/four_bar.urdf", "--fix", "nope=1"], linkspace.InputError),
    (lambda: linkspace.load("urdf/four_bar.urdf").solve(precision=-1), ["solve", "urdf/four_bar.urdf", "--precision", "-1"], linkspace.InputError),
    (lambda: linkspace.load("urdf/four_bar.urdf").solve(rho=1.5), ["solve", "urdf/four_bar.urdf", "--rho", "1.5"], linkspace.InputError),
    (lambda: linkspace.load("urdf/four_bar.urdf").solve(max_boxes=0), ["solve", "urdf/four_bar.urdf", "--max-boxes", "0"], linkspace.InputError),
    (lambda: linkspace.load("urdf/four_bar.urdf").solve(timeout=-2), ["solve", "urdf/four_bar.urdf", "--timeout", "-2"], linkspace.InputError),
    (lambda: linkspace.load("urdf/four_bar.urdf").solve(max_memory=0), ["solve", "urdf/four_bar.urdf", "--max-memory", "0"], linkspace.InputError),
    (lambda: linkspace.load("urdf/four_bar.urdf").solve(trace=["coupler@2"]), ["solve", "urdf/four_bar.urdf", "--trace", "coupler@2"], linkspace.InputError),
    (lambda: linkspace.load("urdf/four_bar.urdf").ik([1, 2, 3]), ["ik", "urdf/four_bar.urdf", "--point", "1,2,3"], linkspace.UnsupportedError),
    (lambda: linkspace.load("urdf/orthogonal_3r_a.urdf").singularities(precision=2.0), ["singularities", "urdf/orthogonal_3r_a.urdf", "--precision", "2"], linkspace.InputError),
    (lambda: linkspace.load("urdf/orthogonal_3r_a.urdf").singularities(kind="cusps", nodes=True), ["singularities", "urdf/orthogonal_3r_a.urdf", "--kind", "cusps", "--nodes"], linkspace.InputError),
    (lambda: linkspace.load("urdf/orthogonal_3r_a.urdf").singularities(tip_point="tool@1,2"), ["singularities", "urdf/orthogonal_3r_a.urdf", "--tip-point", "tool@1,2"], linkspace.InputError),
    (lambda: linkspace.load("urdf/orthogonal_3r_a.urdf").singularities(base="nowhere"), ["singularities", "urdf/orthogonal_3r_a.urdf", "--base", "nowhere"], linkspace.Error),
    (lambda: linkspace.load("urdf/orthogonal_3r_a.urdf").collisions(), ["collisions", "urdf/orthogonal_3r_a.urdf"], linkspace.UnsupportedError),
    (lambda: linkspace.load("urdf/iiwa14.urdf").singularities(), ["singularities", "urdf/iiwa14.urdf"], linkspace.UnsupportedError),
    (lambda: linkspace.load("urdf/iiwa14.urdf").ik6([0.4, 0.2, 0.5, 0, 1.5, 0]), ["ik6", "urdf/iiwa14.urdf", "--pose", "0.4,0.2,0.5,0,1.5,0"], linkspace.InputError),
    (lambda: linkspace.load("urdf/ur5.urdf").path_check([[0, 1, 2]]), ["path-check", "urdf/ur5.urdf", "--waypoints", "0,1,2"], linkspace.InputError),
    (lambda: linkspace.load("urdf/four_bar.urdf").loop_singularities(kind="motion"), ["loop-singularities", "urdf/four_bar.urdf", "--kind", "motion"], linkspace.InputError),
    (lambda: linkspace.load("urdf/four_bar.urdf").loop_singularities(actuated=["nope"]), ["loop-singularities", "urdf/four_bar.urdf", "--actuated", "nope"], linkspace.InputError),
    (lambda: linkspace.load("urdf/octahedral.urdf").distances(), ["distances", "urdf/octahedral.urdf"], linkspace.InputError),
    (lambda: linkspace.load("urdf/nonexistent.urdf"), ["solve", "urdf/nonexistent.urdf"], linkspace.InputError),
    (lambda: linkspace.load("README.md").distances(), ["distances", "README.md"], linkspace.InputError),
]


@pytest.mark.parametrize(("ask", "args", "cls"), CASES, ids=[" ".join(c[1])[:60] for c in CASES])
def test_bad_input_raises_with_the_cli_message(ask: Callable[[], Any], args: list[str], cls: type[linkspace.Error], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    report, message = run_cli(args, tmp_path)
    assert report is None, f"the CLI accepted {args}"
    with pytest.raises(cls) as raised:
        ask()
    assert str(raised.value) == message
    assert isinstance(raised.value, linkspace.Error)


def test_input_errors_are_value_errors_and_the_classes_nest() -> None:
    assert issubclass(linkspace.InputError, ValueError)
    assert issubclass(linkspace.UnsupportedError, linkspace.InputError)
    for cls in (linkspace.InputError, linkspace.UnsupportedError, linkspace.AnalysisError, linkspace.InternalError):
        assert issubclass(cls, linkspace.Error)


def test_wrong_types_and_values_of_python_arguments() -> None:
    m = linkspace.load(str(ROOT / "urdf/four_bar.urdf"))
    with pytest.raises(TypeError):
        m.solve(fix={"crank_joint": "a lot"})  # type: ignore[dict-item]
    with pytest.raises(TypeError):
        m.solve(max_boxes=1.5)  # type: ignore[arg-type]
    with pytest.raises(linkspace.InputError, match="model 'curved': expected one of auto, planar, spatial, pose, distances"):
        m.solve(model="curved")
    with pytest.raises(TypeError):
        m.solve(precision=1e-3, sigma=1e-2)
    with pytest.raises(linkspace.InputError, match="only `distances` reads it"):
        linkspace.load(str(ROOT / "urdf/four_spheres.json")).solve()
    with pytest.raises(linkspace.InputError, match="malformed URDF"):
        linkspace.load("<robot name='x'><link name='a'/><joint name='j' type='revolute'></joint></robot>").solve()
