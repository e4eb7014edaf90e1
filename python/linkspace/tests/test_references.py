"""Answers from Python against references computed without the solver: the four-bar's closed
form, forward kinematics read from the URDF with numpy, the counts of Benoit, Delanoue,
Lagrange and Wenger (2019), Table 1, and the 3R map's Jacobian at the certified cusps."""

from __future__ import annotations

import math

import numpy as np
import pytest

import linkspace
from conftest import forward_kinematics, urdf


def angle_in(value: float, lo: float, hi: float, slack: float = 1e-9) -> bool:
    """Whether `value` (modulo 2π) lies in [lo, hi]."""
    k = math.floor((lo - slack - value) / (2 * math.pi)) + 1
    v = value + 2 * math.pi * k
    return lo - slack <= v <= hi + slack


def test_four_bar_assemblies_match_the_circle_intersection() -> None:
    # Ground pivots (0, 0) and (4, 0), crank 1.5, coupler 4, rocker 3.5 (urdf/four_bar.urdf).
    crank = 0.7
    b = np.array([1.5 * math.cos(crank), 1.5 * math.sin(crank)])
    o4 = np.array([4.0, 0.0])
    d = float(np.linalg.norm(o4 - b))
    a = (4.0**2 - 3.5**2 + d**2) / (2 * d)
    h = math.sqrt(4.0**2 - a**2)
    mid = b + a * (o4 - b) / d
    normal = np.array([-(o4 - b)[1], (o4 - b)[0]]) / d
    expected = []
    for c in (mid + h * normal, mid - h * normal):
        coupler = math.atan2(c[1] - b[1], c[0] - b[0]) - crank
        rocker = math.atan2(c[1] - o4[1], c[0] - o4[0])
        expected.append((coupler, rocker))

    r = linkspace.load(urdf("four_bar.urdf")).solve(fix={"crank_joint": crank}, precision=1e-6)
    assert r.completeness.complete and r.clusters == 2
    s = r.solutions
    i, j = s.columns.index("coupler_joint"), s.columns.index("rocker_joint")
    for coupler, rocker in expected:
        holding = [k for k in range(len(s)) if angle_in(coupler, s.lo[k, i], s.hi[k, i]) and angle_in(rocker, s.lo[k, j], s.hi[k, j])]
        assert holding, f"no box holds the assembly ({coupler}, {rocker})"
    # Each assembly is its own cluster.
    assert len({int(s.clusters[k]) for k in range(len(s))}) == 2


def test_double_butterfly_has_six_proven_assemblies() -> None:
    r = linkspace.load(urdf("double_butterfly.urdf")).solve(fix={"joint6": 1.1760052070951352}, sigma=1e-4)
    assert r.completeness.complete
    assert len(r.solutions) == 6 and set(r.solutions.tags) == {"unique"} and r.clusters == 6
    assert np.all(r.solutions.widths() <= 1e-4)


@pytest.mark.parametrize(("case", "cusps", "nodes", "motions"), [("a", 4, 0, False), ("b", 4, 0, False), ("d", 0, 0, False), ("e", 4, 2, False), ("f", 0, 2, True)])
def test_orthogonal_3r_counts_are_those_of_table_1(case: str, cusps: int, nodes: int, motions: bool) -> None:
    r = linkspace.load(urdf(f"orthogonal_3r_{case}.urdf")).singularities(nodes=True)
    assert r.completeness.complete
    assert len(r.cusps.solutions) == cusps and set(r.cusps.tags) <= {"unique"}
    assert r.nodes is not None and len(r.nodes) == nodes
    assert (len(r.internal_motions) > 0) == motions


def f_3r_a(t2: float, t3: float) -> np.ndarray:
    """The map (rho, z) of urdf/orthogonal_3r_a.urdf: d2 = 1, d3 = 2, d4 = 1.5, r2 = 1, r3 = 0,
    rho = (cos t2 (d4 cos t3 + d3) + d2)^2 + (d4 sin t3 + r2)^2, z = sin t2 (d4 cos t3 + d3)."""
    u = 1.5 * math.cos(t3) + 2.0
    return np.array([(math.cos(t2) * u + 1.0) ** 2 + (1.5 * math.sin(t3) + 1.0) ** 2, math.sin(t2) * u])


def det_3r_a(t2: float, t3: float, h: float = 1e-6) -> float:
    """det Df by central differences."""
    j = np.column_stack([(f_3r_a(t2 + h, t3) - f_3r_a(t2 - h, t3)) / (2 * h), (f_3r_a(t2, t3 + h) - f_3r_a(t2, t3 - h)) / (2 * h)])
    return float(np.linalg.det(j))


def test_certified_cusps_lie_where_the_jacobian_of_the_map_vanishes() -> None:
    det = det_3r_a
    r = linkspace.load(urdf("orthogonal_3r_a.urdf")).singularities(kind="cusps")
    mids = r.cusps.midpoints()
    assert len(mids) == 4
    scale = max(abs(det(a, b)) for a in np.linspace(-3, 3, 7) for b in np.linspace(-3, 3, 7))
    for t2, t3 in mids:
        assert abs(det(t2, t3)) < 1e-3 * scale, (t2, t3, det(t2, t3))


def test_ik_solutions_reach_the_point_by_forward_kinematics() -> None:
    path = urdf("orthogonal_3r_a.urdf")
    point = np.array([1.0, 0.5, 0.3])
    r = linkspace.load(path).ik(point)
    assert r.completeness.complete and len(r.solutions) == 2
    for q in r.solutions.midpoints():
        tip = forward_kinematics(path, "tool", dict(zip(r.solutions.columns, q)))[:3, 3]
        assert np.linalg.norm(tip - point) < 1e-5


def test_ik6_solutions_reach_the_pose_by_forward_kinematics() -> None:
    path = urdf("ur5.urdf")
    q0 = {"joint_1": 0.3, "joint_2": -1.1, "joint_3": 1.4, "joint_4": -0.6, "joint_5": 1.2, "joint_6": 0.4}
    pose = forward_kinematics(path, "tool0", q0)
    r = linkspace.load(path).ik6(pose)
    unique = r.solutions.with_tag("unique")
    # The file's limits are ±2π: each of at most 8 solutions of the torus comes with its copies
    # a turn away.
    distinct = {tuple(np.round(np.mod(q + math.pi, 2 * math.pi) - math.pi, 6)) for q in unique.midpoints()}
    assert r.completeness.complete and 1 <= len(distinct) <= 8 and len(unique) > len(distinct)
    for q in unique.midpoints():
        T = forward_kinematics(path, "tool0", dict(zip(unique.columns, q)))
        assert np.abs(T - pose).max() < 1e-6
    # The configuration the pose was made from is among them (modulo 2π).
    assert any(all(angle_in(q0[c], unique.lo[k, i], unique.hi[k, i], 1e-7) for i, c in enumerate(unique.columns)) for k in range(len(unique)))
    # The same pose as xyz + quaternion and as xyz + rpy gives the same solutions.
    R = pose[:3, :3]
    w = math.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    quaternion = [(R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w), w]
    rpy = [math.atan2(R[2, 1], R[2, 2]), math.asin(-R[2, 0]), math.atan2(R[1, 0], R[0, 0])]
    assert len(r.to_dict()["unique"]) == len(unique)
    for kwargs in ({"quaternion": quaternion}, {"rpy": rpy}):
        again = linkspace.load(path).ik6(xyz=pose[:3, 3], **kwargs).solutions.with_tag("unique")  # type: ignore[arg-type]
        assert len(again) == len(unique)
        assert np.abs(np.sort(again.midpoints(), axis=0) - np.sort(unique.midpoints(), axis=0)).max() < 1e-7


def test_ik6_many_answers_each_pose_in_order_as_ik6_does() -> None:
    path = urdf("ur5.urdf")
    m = linkspace.load(path)
    configurations = [
        {"joint_1": 0.3, "joint_2": -1.1, "joint_3": 1.4, "joint_4": -0.6, "joint_5": 1.2, "joint_6": 0.4},
        {"joint_1": -0.8, "joint_2": -0.5, "joint_3": 0.9, "joint_4": 0.2, "joint_5": -1.0, "joint_6": 1.1},
        {"joint_1": 1.5, "joint_2": -2.0, "joint_3": -1.2, "joint_4": 0.7, "joint_5": 0.5, "joint_6": -0.3},
    ]
    poses = np.stack([forward_kinematics(path, "tool0", q) for q in configurations])
    many = m.ik6_many(poses)
    assert len(many) == len(configurations)
    for q0, pose, r in zip(configurations, poses, many):
        one = m.ik6(pose).solutions.with_tag("unique")
        unique = r.solutions.with_tag("unique")
        assert r.completeness.complete and len(unique) == len(one)
        assert np.array_equal(np.sort(unique.midpoints(), axis=0), np.sort(one.midpoints(), axis=0))
        # Each answer holds the configuration its pose was made from: the order is the poses'.
        assert any(all(angle_in(q0[c], unique.lo[k, i], unique.hi[k, i], 1e-7) for i, c in enumerate(unique.columns)) for k in range(len(unique)))
    # A list of 6-number poses works the same; a bad pose is named before anything is solved.
    assert len(m.ik6_many([[0.3, 0.2, 0.4, 0.0, 0.0, 0.0]])) == 1
    with pytest.raises(linkspace.InputError, match="pose 1 has 5 numbers"):
        m.ik6_many([[0.3, 0.2, 0.4, 0.0, 0.0, 0.0], [1, 2, 3, 4, 5]])
    with pytest.raises(linkspace.InputError, match="a list of poses"):
        m.ik6_many(np.zeros(7))


def test_self_motion_boxes_hold_the_configuration_the_pose_was_made_from() -> None:
    path = urdf("iiwa14.urdf")
    q0 = {"joint_1": 0.3, "joint_2": 0.5, "joint_3": 0.2, "joint_4": -1.2, "joint_5": 0.4, "joint_6": 0.8, "joint_7": -0.3}
    pose = forward_kinematics(path, "tool0", q0)
    r = linkspace.load(path).self_motion(pose, parameter="joint_3", range=(0.1, 0.3), exact_geometry=True)
    boxes = r.boxes
    assert r.parameter == "joint_3" and len(boxes.with_tag("unique")) > 0
    assert r.to_dict()["cells_searched"] == r.to_dict()["cells"]
    holding = [k for k in range(len(boxes)) if all(boxes.lo[k, i] - 1e-9 <= q0[c] <= boxes.hi[k, i] + 1e-9 for i, c in enumerate(boxes.columns))]
    assert holding, "no box holds the configuration the pose was made from"


def test_path_verdicts_agree_with_the_sign_of_det_df() -> None:
    m = linkspace.load(urdf("orthogonal_3r_a.urdf"))
    grid = np.linspace(-3.0, 3.0, 13)
    crossing = clear = None
    for t2 in grid:
        for t3 in grid:
            a, b = np.array([t2, t3]), np.array([t2 + 0.4, t3 + 0.4])
            samples = [det_3r_a(*(a + s * (b - a))) for s in np.linspace(0, 1, 201)]
            if crossing is None and samples[0] * samples[-1] < 0 and abs(samples[0]) > 0.05 and abs(samples[-1]) > 0.05:
                crossing = (a, b)
            if clear is None and min(abs(x) for x in samples) > 0.2 and (all(x > 0 for x in samples) or all(x < 0 for x in samples)):
                clear = (a, b)
    assert crossing is not None and clear is not None
    # Joint 1 does not change the map; the waypoints hold (joint1, joint2, joint3).
    r = m.path_check([[0.0, *crossing[0]], [0.0, *crossing[1]]])
    assert r.segments[0].value == "crosses" and r.segments[0].crossings
    r = m.path_check([[0.0, *clear[0]], [0.0, *clear[1]]])
    assert r.segments[0].clear and r.segments[0].min_abs_det is not None and r.segments[0].min_abs_det > 0


def test_ik6_on_a_ur_arm_with_axis_6_along_axes_2_to_4_returns_the_curve() -> None:
    # The UR5 at (0, -1, 1, 0.3, 0, 0.5): joint 5 at 0 lines axis 6 up with axes 2, 3, 4, and joint 6
    # turns freely with joints 2-4 following. The pose from the file's frames, written out.
    pose = np.array([[0.6967067093471655, -0.7173560908995227, 0.0, -0.5939074924334636], [0.0, 0.0, -1.0, -0.19145], [0.7173560908995228, 0.6967067093471654, 0.0, 0.3563615698083504], [0.0, 0.0, 0.0, 1.0]])
    r = linkspace.load(urdf("ur5.urdf")).ik6(pose)
    assert r.completeness.complete and r.method == "closed_form" and r.curve_kinds == ["wrist_singular"]
    assert r.curve_moving == [["joint_2", "joint_3", "joint_4", "joint_6"]]
    cover = r.curves[0]
    assert cover.contains(np.array([0.0, -1.0, 1.0, 0.3, 0.0, 0.5])).any()
    # Joint 6 over its whole range.
    i6 = cover.columns.index("joint_6")
    assert cover.lo[:, i6].min() == -6.2832 and cover.hi[:, i6].max() == 6.2832


def test_ik6_at_a_wrist_singular_pose_returns_the_curve() -> None:
    # The KR16 at home (every joint at 0) lines axes 4 and 6 up: the matrix its frames give at 0.
    home = np.array([[1.0, 0.0, 0.0, 0.905], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, -1.0, -0.153], [0.0, 0.0, 0.0, 1.0]])
    r = linkspace.load(urdf("kuka_kr16.urdf")).ik6(home)
    assert r.completeness.complete and r.method == "closed_form" and r.curve_kinds == ["wrist_singular"]
    assert r.curve_moving == [["joint_4", "joint_6"]]
    cover = r.curves[0]
    assert len(cover) > 100 and set(cover.tags) == {"solution"}
    assert cover.contains(np.zeros(6)).any()
    # Joint 4 over its whole range, joints 1-3 and 5 pinned at 0.
    i4, i5 = cover.columns.index("joint_4"), cover.columns.index("joint_5")
    assert cover.lo[:, i4].min() == -6.1087 and cover.hi[:, i4].max() == 6.1087
    assert np.abs(np.concatenate([cover.lo[:, i5], cover.hi[:, i5]])).max() < 1e-6
    # The curve's boxes are among the solutions, after the unique ones.
    assert len(r.solutions.with_tag("solution")) == len(cover)
