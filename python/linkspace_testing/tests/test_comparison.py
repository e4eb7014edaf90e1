"""The plugin's comparison rule and its node fixture, against `linkspace serve`.

Test idea: certified roots are compared by containment and the solution boxes of a curve by
enclosure (README.md). The mobile four-bar (urdf/four_bar.urdf, a Grashof crank-rocker) has a
curve of configurations with two branches, its two assembly modes; its closed form (two
circles meeting, for each crank angle) is the reference the box sets are checked against. A
golden set made at sigma 1e-2 and a run at 5e-3 enclose that curve at their two resolutions
and must agree, although most centres of the coarse boxes lie in no fine box; a run of another
mechanism (the rocker 0.1 longer) and a run with one branch removed must not. `box_set` waits
on the latched topic alone, so it works under `--ros-args --log-level warn`, where the node
logs no INFO line. Run with the ROS environment of the node and LINKSPACE_BIN (the Rust test
`topics::the_regression_test_helper...` does).
"""
import math
import os

import pytest

from linkspace_testing import (BOX_SOLUTION, BOX_UNIQUE, assert_matches_golden, compare_by_containment, kind,
                               load_golden, save_golden)
from linkspace_testing import _boxes, _Index

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
FOUR_BAR = os.path.join(ROOT, "urdf", "four_bar.urdf")
VARIABLES = ["cos_crank", "sin_crank", "cos_coupler", "sin_coupler", "cos_rocker", "sin_rocker"]


def four_bar_curve(steps=6283, crank=1.5, coupler=4.0, rocker=3.5, ground=4.0):
    """Points of the four-bar's configuration curve in the node's variables (absolute angles of
    crank, coupler and rocker), by closed form: for each crank angle the coupler's far pin is
    where the circle about the crank tip (radius `coupler`) meets the circle about the rocker's
    pivot (radius `rocker`); the two meetings are the two assembly modes. Returns
    {+1: points, -1: points} by the sign of sin(rocker - coupler) (the transmission angle)."""
    modes = {1: [], -1: []}
    for k in range(steps):
        t2 = 2 * math.pi * k / steps
        ax, ay = crank * math.cos(t2), crank * math.sin(t2)
        dx, dy = ground - ax, -ay
        dist = math.hypot(dx, dy)
        along = (coupler ** 2 - rocker ** 2 + dist ** 2) / (2 * dist)
        across = math.sqrt(coupler ** 2 - along ** 2)
        for sign in (1, -1):
            bx = ax + (along * dx - sign * across * dy) / dist
            by = ay + (along * dy + sign * across * dx) / dist
            t3, t4 = math.atan2(by - ay, bx - ax), math.atan2(by, bx - ground)
            p = [math.cos(t2), math.sin(t2), math.cos(t3), math.sin(t3), math.cos(t4), math.sin(t4)]
            modes[1 if math.sin(t4 - t3) > 0 else -1].append(p)
    return modes


def mode(lower, upper):
    """The assembly mode of a box, by the sign of sin(rocker - coupler) at its centre."""
    _, _, cc, sc, cr, sr = [0.5 * (lo + hi) for lo, hi in zip(lower, upper)]
    return 1 if sr * cc - cr * sc > 0 else -1


def plain(boxes, statuses, sigma, dim=2, names=("x", "y")):
    """A box set in the plugin's plain data from (lower, upper) pairs."""
    return {"mechanism": "m", "analysis": "configuration_space", "status": 0, "limit": "", "dim": dim,
            "variable_names": list(names), "lower": [x for lo, _ in boxes for x in lo],
            "upper": [x for _, up in boxes for x in up], "box_status": list(statuses), "sigma": sigma}


def segment(sigma, offset=0.0, loose=False):
    """The segment y = x / 2 + offset, 0 <= x <= 1, covered by boxes of width sigma: tight ones
    (the segment is their diagonal), or loose ones, twice as high as wide, with the segment in
    their lowest quarter (their centres then lie off it)."""
    n = round(1 / sigma)
    height = 2 * sigma if loose else sigma / 2
    return plain([([k * sigma, k * sigma / 2 + offset], [(k + 1) * sigma, k * sigma / 2 + offset + height]) for k in range(n)],
                 [BOX_SOLUTION] * n, sigma)


def centres_in_no_box(a, b):
    """How many solution-box centres of `a` lie in no box of `b` (a comparison by centres)."""
    index = _Index(_boxes(b))
    centres = [[0.5 * (lo + hi) for lo, hi in zip(l, u)] for l, u in _boxes(a, (BOX_SOLUTION,))]
    return sum(1 for c in centres if not index.meets(c, c, 1e-9))


def test_a_segment_at_two_resolutions_agrees_and_a_shifted_one_does_not():
    coarse, fine = segment(1e-2, loose=True), segment(5e-3)
    # The centres of the coarse boxes lie off the segment, outside the fine boxes: by centres,
    # the two covers would differ.
    assert centres_in_no_box(coarse, fine) > 0
    assert compare_by_containment(fine, coarse) == []
    shifted = segment(5e-3, offset=0.05)
    problems = compare_by_containment(shifted, coarse)
    assert len(problems) == 2 and all("meet no box" in p for p in problems), problems


def test_certified_roots_are_still_compared_by_containment():
    golden = plain([([0.0, 0.0], [1e-6, 1e-6]), ([1.0, 1.0], [1.0 + 1e-6, 1.0 + 1e-6])], [BOX_UNIQUE] * 2, 1e-6)
    assert kind(golden) == "certified"
    assert compare_by_containment(golden, golden) == []
    # A root moved by 1e-3, far below any sigma: containment sees it.
    moved = plain([([1e-3, 0.0], [1e-3 + 1e-6, 1e-6]), ([1.0, 1.0], [1.0 + 1e-6, 1.0 + 1e-6])], [BOX_UNIQUE] * 2, 1e-6)
    problems = compare_by_containment(moved, golden)
    assert len(problems) == 2 and all("certified roots" in p and "lie in no box" in p for p in problems), problems


@pytest.fixture
def curve_golden(linkspace_node, tmp_path):
    """The mobile four-bar's box set at sigma 1e-2, saved as a golden file and loaded again."""
    node = linkspace_node([FOUR_BAR], ["--sigma", "1e-2"])
    path = tmp_path / "four_bar_curve_1e-2.json"
    save_golden(node.box_set("four_bar"), path)
    node.stop()
    return load_golden(path)


def test_the_curve_golden_encloses_the_closed_form_curve(curve_golden):
    g = curve_golden
    assert (g["status"], g["variable_names"], g["sigma"], kind(g)) == (0, VARIABLES, 1e-2, "solution")
    index = _Index(_boxes(g))
    for sign, points in four_bar_curve().items():
        outside = [p for p in points if not index.meets(p, p, 1e-9)]
        assert not outside, f"mode {sign}: {len(outside)} of {len(points)} points of the curve in no box; first {outside[0]}"
    # Both branches are covered, each by its own boxes.
    modes = [mode(l, u) for l, u in _boxes(g)]
    assert modes.count(1) > 100 and modes.count(-1) > 100, (modes.count(1), modes.count(-1))


def test_a_curve_golden_at_sigma_1e_2_matches_a_run_at_5e_3(curve_golden, linkspace_node):
    node = linkspace_node([FOUR_BAR], ["--sigma", "5e-3"])
    got = node.box_set("four_bar")
    assert (got["status"], got["sigma"], kind(got)) == (0, 5e-3, "solution")
    # Compared by centres, most golden boxes would be missing from the finer run.
    assert centres_in_no_box(curve_golden, got) > len(curve_golden["box_status"]) // 2
    assert_matches_golden(got, curve_golden, tol=1e-9)


def test_another_mechanism_or_a_missing_branch_fails(curve_golden, linkspace_node, tmp_path):
    with open(FOUR_BAR) as f:
        xml = f.read()
    longer = xml.replace('<robot name="four_bar">', '<robot name="four_bar_long">').replace(
        '<successor link="rocker"><origin xyz="3.5 0 0"', '<successor link="rocker"><origin xyz="3.6 0 0"')
    assert longer.count("four_bar_long") == 1 and longer.count('xyz="3.6 0 0"') == 1
    (tmp_path / "four_bar_long.urdf").write_text(longer)
    node = linkspace_node([FOUR_BAR, tmp_path / "four_bar_long.urdf"], ["--sigma", "5e-3"])
    other = node.box_set("four_bar_long")
    assert other["variable_names"] == VARIABLES
    problems = compare_by_containment(other, curve_golden)
    assert len(problems) == 2 and all("solution boxes" in p and "meet no box" in p for p in problems), problems
    with pytest.raises(AssertionError, match="meet no box"):
        assert_matches_golden(other, curve_golden)

    # The right mechanism with the boxes of one assembly mode dropped: the golden boxes of
    # that branch meet nothing.
    got = node.box_set("four_bar")
    d = got["dim"]
    keep = [k for k, (l, u) in enumerate(_boxes(got)) if mode(l, u) == 1]
    assert 0 < len(keep) < len(got["box_status"])
    one_branch = dict(got, lower=[x for k in keep for x in got["lower"][k * d:(k + 1) * d]],
                      upper=[x for k in keep for x in got["upper"][k * d:(k + 1) * d]],
                      box_status=[got["box_status"][k] for k in keep])
    assert compare_by_containment(got, curve_golden) == []
    problems = compare_by_containment(one_branch, curve_golden)
    assert len(problems) == 1 and problems[0].startswith(f"{sum(1 for l, u in _boxes(curve_golden) if mode(l, u) == -1)} of "), problems


def test_box_set_waits_on_the_topic_under_log_level_warn(linkspace_node):
    node = linkspace_node([FOUR_BAR], ["--fix", "crank_joint=0.5", "--sigma", "1e-6", "--ros-args", "--log-level", "warn"])
    got = node.box_set("four_bar", timeout=60.0)
    assert (got["status"], kind(got), len(got["box_status"])) == (0, "certified", 2)
    # The INFO line the plugin once waited for never comes at this level.
    assert not any("published configuration_space" in line for line in node.log), node.log
