"""A small use of the package that `mypy --strict` checks against its stubs and annotations."""

from __future__ import annotations

import numpy as np

import linkspace


def assemblies(path: str, joint6: float) -> np.ndarray:
    """The midpoints of the double butterfly's assemblies at one value of joint 6."""
    m: linkspace.Mechanism = linkspace.load(path)
    r: linkspace.SolveResult = m.solve(fix={"joint6": joint6}, precision=1e-4, timeout=10.0)
    if not r.completeness:
        raise RuntimeError(f"incomplete: {r.completeness.reason}")
    boxes: linkspace.BoxSet = r.solutions
    return boxes.midpoints()


def cuspidal(path: str) -> bool | None:
    v = linkspace.load(path).singularities(kind="all").verdict
    return None if v is None else v.value


def first_pose_solution(path: str, pose: np.ndarray) -> list[float] | None:
    r = linkspace.load(path).ik6(pose, precision=1e-9)
    unique = r.solutions.with_tag("unique")
    return [float(x) for x in unique.midpoints()[0]] if len(unique) else None


def on_progress(p: linkspace.Progress) -> None:
    print(f"{p.decided:.0%} decided, {p.processed} boxes")


if __name__ == "__main__":
    print(assemblies("urdf/double_butterfly.urdf", 1.1760052070951352))
    print(cuspidal("urdf/orthogonal_3r_a.urdf"))
    print(first_pose_solution("urdf/ur5.urdf", np.eye(4)))
    try:
        linkspace.load("urdf/four_bar.urdf").ik([1.0, 2.0, 3.0], progress=on_progress)
    except linkspace.UnsupportedError as e:
        print(e)
    d: dict[str, object] = linkspace.load("urdf/four_bar.urdf").solve(max_boxes=10).to_dict()
    print(sorted(d))
