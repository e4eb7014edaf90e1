"""What a question answers, as typed objects over the CLI's JSON report of the same run.

Every result keeps the report (``to_dict()``, equal to ``json.loads`` of what ``--json`` writes
for the same run, and ``to_json()``, its text) and reads its attributes from it; box sets are
numpy arrays. Completeness comes from the library's one rule (``Answer::completeness``).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from . import _native
from ._boxes import BoxSet, FloatArray

__all__ = [
    "Completeness", "Scope", "Verdict", "Result", "SolveResult", "SingularitiesResult", "Node", "IkResult", "Ik6Result",
    "PathCheckResult", "Segment", "CollisionsResult", "DistancesResult", "SingularSet", "LoopSingularitiesResult",
]


def _tag(record: Any) -> str:
    return "unique" if record.get("unique") else "solution"


@dataclass(frozen=True)
class Completeness:
    """Whether an answer is complete: nothing stopped it and nothing is left undecided.

    ``reason`` says why not: the limit that stopped a run (``"boxes"``, ``"time"``,
    ``"memory"``, ``"cancelled"``), or ``"undecided"`` / ``"near_degenerate"`` when the run
    finished with something open. ``bool(c)`` is ``c.complete``.
    """

    complete: bool
    reason: str | None = None

    @property
    def limit(self) -> str | None:
        """The limit that stopped the run, if one did."""
        return self.reason if self.reason in ("boxes", "time", "memory", "cancelled", "sink") else None

    def __bool__(self) -> bool:
        return self.complete

    def __str__(self) -> str:
        return "complete" if self.complete else f"incomplete ({self.reason})"


@dataclass(frozen=True)
class Scope:
    """What a verdict concerns: ``kind`` is ``"mechanism"`` (the arm as a whole) or
    ``"sub_chain"`` (its 3R positioning sub-chain: ``joints`` and ``point``)."""

    kind: str
    joints: tuple[str, ...] = ()
    point: str | None = None

    @classmethod
    def of(cls, record: dict[str, Any]) -> Scope:
        return cls(record["kind"], tuple(record.get("joints") or ()), record.get("point"))


@dataclass(frozen=True)
class Verdict:
    """A cuspidality verdict: ``value`` is ``True`` (cuspidal), ``False`` or ``None``
    (undecided), ``certified`` when it rests on a proof or a certified witness, ``reason`` the
    argument in one line, ``scope`` what it concerns, ``proof`` the theorem a whole-arm
    ``False`` applies and ``witness`` the certified path of a whole-arm ``True`` (as the
    report writes it)."""

    value: bool | None
    certified: bool
    reason: str
    scope: Scope
    proof: str | None = None
    witness: dict[str, Any] | None = None
    aspects: int | None = None
    max_ik_solutions: int | None = None
    record: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def of(cls, r: dict[str, Any]) -> Verdict:
        return cls(r["cuspidal"], r["certified"], r["reason"], Scope.of(r["scope"]), r.get("proof"), r.get("witness"), r.get("aspects"), r.get("max_ik_solutions"), r)

    def __bool__(self) -> bool:
        return self.value is True


class Result:
    """An answer: ``question`` (the CLI's subcommand), ``completeness``, ``notice`` (what the CLI
    prints before such a run, if anything), ``seconds`` (the library's time for the job), the
    report (``to_dict()``, ``to_json()``)."""

    question: str

    def __init__(self, native: _native.NativeAnswer) -> None:
        self._native = native
        self.question = native.name
        word, reason = native.completeness()
        self.completeness = Completeness(word == "complete", reason)
        self.notice: str | None = native.notice
        #: Seconds the library took (preparing and running the job), without the binding.
        self.seconds: float = native.seconds

    @cached_property
    def _text(self) -> str:
        return self._native.json()

    @cached_property
    def _report(self) -> Any:
        return json.loads(self._text)

    def to_json(self) -> str:
        """The JSON report, as ``linkspace <question> ... --json FILE`` writes it."""
        return self._text

    def to_dict(self) -> Any:
        """The JSON report as Python data (a new copy each call): what ``json.load`` reads from
        the CLI's ``--json`` file for the same run (a list of reports for
        ``loop_singularities`` of singular sets)."""
        return json.loads(self._text)

    @property
    def complete(self) -> bool:
        """``completeness.complete``."""
        return self.completeness.complete

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.question}: {self.completeness}>"


class SolveResult(Result):
    """Every configuration of a linkage (``Mechanism.solve``): ``boxes`` over the free joints,
    solution boxes first, then undecided ones; ``variables`` the same boxes over the system's
    variables (the report's ``box``)."""

    def __init__(self, native: _native.NativeAnswer) -> None:
        super().__init__(native)
        a = native.solve_boxes()
        assert a is not None
        count = int(a["cluster_count"])
        self.boxes = BoxSet(a["columns"], a["lo"], a["hi"], a["tags"], a["clusters"], count)
        self.variables = BoxSet(a["variables"], a["variables_lo"], a["variables_hi"], a["tags"], a["clusters"], count)
        self.levels = a["levels"]
        self.mechanism: str = a["mechanism"]

    @property
    def solutions(self) -> BoxSet:
        """The solution boxes (``boxes.solutions``)."""
        return self.boxes.solutions

    @property
    def undecided(self) -> BoxSet:
        """The undecided boxes."""
        return self.boxes.undecided

    @property
    def clusters(self) -> int:
        """Connected components of the solution boxes (assembly modes of a rigid mechanism,
        branches of a curve)."""
        return self.boxes.cluster_count

    @property
    def model(self) -> str:
        """The builder: ``planar``, ``spatial``, ``pose`` or ``distances``; ``model_reason`` says why."""
        return str(self._report["model"])

    @property
    def model_reason(self) -> str:
        return str(self._report["model_reason"])

    @property
    def fixed_joints(self) -> dict[str, float]:
        return dict(self._report["fixed_joints"])

    @property
    def stats(self) -> dict[str, Any]:
        """Counters and times of the search."""
        return dict(self._report["stats"])

    def trace(self, name: str) -> BoxSet:
        """The world coordinates of traced point ``name`` (as given to ``trace=``) over every box:
        columns ``x``, ``y`` (and ``z`` in space), rows as in ``boxes``."""
        records = [r["traces"][name] for r in self._report["solutions"] + self._report["undecided"]]
        columns = ["x", "y"] + (["z"] if records and "z" in records[0] else [])
        rows = [{"joints": {c: r[c] for c in columns}} for r in records]
        lo, hi = _split(rows, columns)
        return BoxSet(columns, lo, hi, self.boxes.tags, self.boxes.clusters, self.boxes.cluster_count)

    def __repr__(self) -> str:
        unique = len(self.boxes.with_tag("unique"))
        return f"<SolveResult {self.mechanism}: {len(self.solutions)} solution boxes ({unique} proven to hold one solution each) in {self.clusters} clusters, {len(self.undecided)} undecided, {self.completeness}>"


def _split(rows: list[dict[str, Any]], columns: list[str]) -> tuple[FloatArray, FloatArray]:
    b = np.array([[r["joints"][c] for c in columns] for r in rows], dtype=np.float64).reshape(len(rows), len(columns), 2)
    return b[:, :, 0], b[:, :, 1]


@dataclass(frozen=True)
class Node:
    """A node of a 3R arm: two singular configurations (``points``, two boxes over joints 2
    and 3) with one image (``workspace``: radius and z)."""

    points: BoxSet
    workspace: BoxSet
    unique: bool


class SingularitiesResult(Result):
    """Cusps, nodes, internal motions and the cuspidality verdict of an arm
    (``Mechanism.singularities``)."""

    @cached_property
    def _columns(self) -> list[str]:
        return list(self._report["joints"][1:3])

    @cached_property
    def cusps(self) -> BoxSet:
        """The cusps (over joints 2 and 3), proven ones first, then undecided boxes."""
        r = self._report
        return BoxSet.concat([BoxSet.from_records(r["cusps"], self._columns, _tag), BoxSet.from_records(r["undecided"]["cusps"], self._columns, lambda _: "undecided")])

    @cached_property
    def cusps_workspace(self) -> BoxSet:
        """The proven cusps' images: columns ``radius`` and ``z``."""
        return BoxSet.from_records(self._report["cusps"], ["radius", "z"], _tag, key="workspace")

    @cached_property
    def nodes(self) -> list[Node] | None:
        """The proven nodes (``None`` when nodes were not searched)."""
        records = self._report["nodes"]
        if records is None:
            return None
        return [Node(BoxSet.from_records([{"joints": p} for p in n["points"]], self._columns, lambda _: _tag(n)), BoxSet.from_records([n], ["radius", "z"], _tag, key="workspace"), bool(n["unique"])) for n in records]

    @cached_property
    def internal_motions(self) -> BoxSet:
        """The internal-motion lines, as boxes over joints 2 and 3."""
        return BoxSet.from_records(self._report["internal_motions"], self._columns, lambda _: "solution")

    @cached_property
    def verdict(self) -> Verdict | None:
        """The arm's cuspidality verdict (``None`` when not asked)."""
        v = self._report.get("verdict")
        return None if v is None else Verdict.of(v)

    @cached_property
    def sub_chain_verdict(self) -> Verdict | None:
        """The 3R positioning sub-chain's verdict, when it is not the arm's."""
        v = self._report.get("sub_chain_verdict")
        return None if v is None else Verdict.of(v)

    @property
    def arm_cuspidality(self) -> dict[str, Any] | None:
        """A six-joint arm's whole-arm section, as the report writes it."""
        v = self._report.get("arm_cuspidality")
        return None if v is None else dict(v)

    @property
    def robot(self) -> str:
        return str(self._report["robot"])

    @property
    def joints(self) -> list[str]:
        """The three joints of the 3R positioning structure, base first."""
        return list(self._report["joints"])

    def __repr__(self) -> str:
        nodes = "not searched" if self.nodes is None else len(self.nodes)
        v = self.verdict
        verdict = "" if v is None else f", cuspidal={v.value}"
        return f"<SingularitiesResult {self.robot}: {len(self.cusps.solutions)} cusps, nodes {nodes}, {len(self.internal_motions)} internal motions{verdict}, {self.completeness}>"


class IkResult(Result):
    """Every solution of an arm's 3R positioning structure for a point (``Mechanism.ik``):
    ``solutions`` over the chain's joints, tagged ``unique`` or ``solution`` (a cluster that
    may hold several, near a singularity, or a line)."""

    @cached_property
    def solutions(self) -> BoxSet:
        return BoxSet.from_records(self._report["solutions"], self._report["chain"]["joints"], _tag)

    def __repr__(self) -> str:
        return f"<IkResult {self._report['robot']}: {len(self.solutions)} solutions, {self.completeness}>"


class Ik6Result(Result):
    """Every solution of a six-revolute arm for a pose (``Mechanism.ik6``): ``solutions``, the
    boxes each proven to hold exactly one, then the hulls of undecided boxes (near singular
    poses), then the boxes of ``curves``."""

    @cached_property
    def solutions(self) -> BoxSet:
        r = self._report
        parts = [BoxSet.from_records([{"joints": b} for b in r["unique"]], r["joints"], lambda _: "unique"), BoxSet.from_records([{"joints": b} for b in r["clusters"]], r["joints"], lambda _: "undecided")]
        return BoxSet.concat(parts + self.curves)

    @cached_property
    def curves(self) -> list[BoxSet]:
        """At a singular pose, one box set per singular curve (``curve_kinds``): at a wrist
        singularity a branch's solutions lie on the curve along which joints 4 and 6 turn
        together (a spherical wrist) or joint 6 turns with joints 2, 3, 4 following (axis 6 along
        three parallel axes, as on a UR; ``curve_moving`` names the joints), at a shoulder
        singularity (the wrist centre on axis 1) joint 1 turns freely with the wrist following
        (or, for a pose just off the singularity, at isolated points on them); the boxes, tagged ``solution`` (each may hold solutions), enclose them all within
        the joint ranges."""
        r = self._report
        return [BoxSet.from_records([{"joints": b} for b in c["cover"]], r["joints"], lambda _: "solution") for c in r.get("curves", [])]

    @property
    def curve_kinds(self) -> list[str]:
        """``"wrist_singular"`` or ``"shoulder_singular"`` for each of ``curves``."""
        return [str(c["kind"]) for c in self._report.get("curves", [])]

    @property
    def curve_moving(self) -> list[list[str]]:
        """The joints that move along each of ``curves`` (the others hold their values)."""
        return [[str(j) for j in c["moving"]] for c in self._report.get("curves", [])]

    @property
    def joints(self) -> list[str]:
        return list(self._report["joints"])

    @property
    def method(self) -> str:
        """Which method answered: ``"closed_form"`` (a recognised geometry: a spherical wrist,
        or axes 2, 3, 4 parallel as on UR arms; every candidate certified), ``"search"``
        (branch and prune), or ``"closed_form_and_search"`` (the candidates the closed form
        certified, and branch and prune on a box about each candidate it could not certify)."""
        return str(self._report["method"])

    def __repr__(self) -> str:
        return f"<Ik6Result {self._report['base']} -> {self._report['tip']}: {len(self.solutions.with_tag('unique'))} unique solutions, {len(self.curves)} singular curves, {len(self.solutions.undecided)} undecided, {self.completeness}>"


class SelfMotionResult(Result):
    """The self-motion set of a seven-revolute arm at a pose (``Mechanism.self_motion``):
    ``boxes`` over the seven joints, tagged ``unique`` (a certified piece of arc: exactly one
    configuration for every parameter angle of its cell), ``solution`` (may hold configurations)
    or ``undecided`` (a cell left unsearched), each with its cluster (touching boxes)."""

    @cached_property
    def boxes(self) -> BoxSet:
        r = self._report
        return BoxSet.from_records(r["boxes"], r["joints"], lambda b: b["tag"], cluster=lambda b: b["cluster"], cluster_count=len(r["clusters"]))

    @property
    def parameter(self) -> str:
        return str(self._report["parameter"])

    def __repr__(self) -> str:
        r = self._report
        return f"<SelfMotionResult {r['parameter']}: {len(r['boxes'])} boxes in {len(r['clusters'])} clusters, {r['certified']} certified, {self.completeness}>"


@dataclass(frozen=True)
class Segment:
    """One segment of a joint path: ``value`` is ``"clear"``, ``"crosses"``,
    ``"touches_or_undecided"`` or ``"not_decided"``; ``proof`` its reason in one line
    (``min_abs_det`` bounds |det| on a clear one); ``crossings`` the proven sign changes, each
    with ``t`` (the segment parameter's enclosure) and ``joints``."""

    start: FloatArray
    end: FloatArray
    value: str
    proof: str
    det_sign: float | None
    min_abs_det: float | None
    crossings: list[dict[str, Any]]
    undecided: list[dict[str, Any]]

    @property
    def clear(self) -> bool:
        return self.value == "clear"


class PathCheckResult(Result):
    """Where a joint path meets a singularity (``Mechanism.path_check``): one ``Segment``
    verdict per segment; ``counts`` by verdict."""

    @cached_property
    def segments(self) -> list[Segment]:
        return [Segment(np.array(s["from"]), np.array(s["to"]), s["verdict"], s["reason"], s.get("det_sign"), s.get("min_abs_det"), list(s.get("crossings", [])), list(s.get("undecided", []))) for s in self._report["segments"]]

    @property
    def counts(self) -> dict[str, int]:
        return dict(self._report["counts"])

    @property
    def joints(self) -> list[str]:
        return list(self._report["joints"])

    @property
    def scope(self) -> str:
        """The singular set checked against, in words (``subject`` of the report)."""
        return str(self._report["subject"])

    def __repr__(self) -> str:
        return f"<PathCheckResult {self._report['singular_set']}: {self.counts}, {self.completeness}>"


class CollisionsResult(Result):
    """Where an arm's collision capsules meet (``Mechanism.collisions``): ``boxes`` over joints
    2 and 3, tagged ``colliding`` (a pair collides everywhere in the box), ``free`` or
    ``undecided``; ``pairs[i]`` names the colliding pair of a colliding box."""

    @cached_property
    def boxes(self) -> BoxSet:
        r = self._report
        columns = list(r["joints"][1:3])
        return BoxSet.concat([BoxSet.from_records(r["colliding"], columns, lambda _: "colliding"), BoxSet.from_records(r["free"], columns, lambda _: "free"), BoxSet.from_records(r["undecided"], columns, lambda _: "undecided")])

    @property
    def colliding(self) -> BoxSet:
        return self.boxes.with_tag("colliding")

    @property
    def pairs(self) -> list[tuple[str, str]]:
        return [(c["pair"][0], c["pair"][1]) for c in self._report["colliding"]]

    @property
    def stats(self) -> dict[str, Any]:
        return dict(self._report["stats"])

    def __repr__(self) -> str:
        return f"<CollisionsResult {self._report['robot']}: {len(self.colliding)} colliding boxes, {len(self.boxes.undecided)} undecided, {self.completeness}>"


class DistancesResult(Result):
    """The solutions of a distance problem (``Mechanism.distances``): ``solutions`` over the
    unknown (squared) distances, each with its cluster; ``placements`` the points placed in
    space per solution, as the report writes them."""

    @cached_property
    def solutions(self) -> BoxSet:
        r = self._report
        columns = sorted(r["solutions"][0]["distances"]) if r["solutions"] else []
        proven = BoxSet.from_records(r["solutions"], columns, _tag, key="distances", cluster=lambda s: int(s["cluster"]), cluster_count=int(r["clusters"]))
        open_ = BoxSet.from_records([u for u in r["undecided"] if "distances" in u], columns, lambda _: "undecided", key="distances")
        return BoxSet.concat([proven, open_]) if len(open_) else proven

    @property
    def clusters(self) -> int:
        return int(self._report["clusters"])

    @property
    def placements(self) -> list[list[dict[str, Any]]]:
        return [list(s.get("points", [])) for s in self._report["solutions"]]

    def __repr__(self) -> str:
        return f"<DistancesResult {self._report['problem']}: {len(self.solutions.solutions)} solutions in {self.clusters} clusters, {self.completeness}>"


class SingularSet:
    """One singular set of a closed loop: ``kind`` (``cspace``, ``input``, ``output``),
    ``boxes`` over the free joints (tags and clusters as reported), ``report`` its dict."""

    def __init__(self, report: dict[str, Any]) -> None:
        self.report = report
        self.kind: str = report["kind"]
        columns = sorted(report["boxes"][0]["joints"]) if report["boxes"] else []
        self.boxes = BoxSet.from_records(report["boxes"], columns, lambda b: str(b["status"]), cluster=lambda b: int(b["cluster"]), cluster_count=len(report["clusters"]))

    def __repr__(self) -> str:
        return f"<SingularSet {self.kind}: {len(self.boxes)} boxes in {self.boxes.cluster_count} clusters, {self.report['status']}>"


class LoopSingularitiesResult(Result):
    """The singular sets, type-II image or input motion of a closed-loop linkage
    (``Mechanism.loop_singularities``): ``sets`` for the singular sets (one per kind asked),
    ``report`` the image's, points' or motion's report otherwise."""

    @cached_property
    def sets(self) -> list[SingularSet]:
        r = self._report
        return [SingularSet(s) for s in r] if isinstance(r, list) else []

    @property
    def report(self) -> Any:
        return self.to_dict()

    def __repr__(self) -> str:
        inner = ", ".join(repr(s) for s in self.sets) or "image/motion report"
        return f"<LoopSingularitiesResult {inner}; {self.completeness}>"


_CLASSES: dict[str, type[Result]] = {
    "solve": SolveResult, "singularities": SingularitiesResult, "ik": IkResult, "ik6": Ik6Result, "self-motion": SelfMotionResult, "path-check": PathCheckResult,
    "collisions": CollisionsResult, "distances": DistancesResult, "loop-singularities": LoopSingularitiesResult,
}


def result_of(native: _native.NativeAnswer) -> Result:
    """The typed result of a native answer."""
    return _CLASSES.get(native.name, Result)(native)
