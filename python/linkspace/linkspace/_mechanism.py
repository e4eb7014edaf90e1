"""``load`` and ``Mechanism``: one method per question, the CLI's options as keyword arguments.

Every method mirrors its CLI subcommand (``linkspace solve``, ``linkspace singularities``, ...):
the same option names in snake case, the same defaults (a ``None`` argument takes the CLI's
default, which each docstring gives) and the same messages on bad input. The run releases the
GIL; Ctrl-C cancels it (the search stops within its cancel latency) and raises
``KeyboardInterrupt``; ``timeout=``, ``max_boxes=`` and ``max_memory=`` (MiB) bound it as on the
CLI, and a limit reached makes the result incomplete rather than raising.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any, TypeVar, Union

import numpy as np
import numpy.typing as npt

from . import _native
from ._errors import InputError
from ._results import CollisionsResult, DistancesResult, Ik6Result, IkResult, LoopSingularitiesResult, PathCheckResult, Result, SelfMotionResult, SingularitiesResult, SolveResult, result_of

__all__ = ["load", "defaults", "Mechanism", "Joint", "Loop", "Progress"]

PathLike = Union[str, os.PathLike[str]]


@dataclass(frozen=True)
class Progress:
    """How far a run has got: ``decided`` is the share of the search space already decided (in
    [0, 1]; NaN when unknown), ``processed`` the boxes processed, ``pending`` those waiting."""

    decided: float
    processed: int
    pending: int


#: ``progress=``: a callable taking a :class:`Progress`, or ``True`` for a bar (tqdm when it is
#: installed, else a line on stderr as the CLI prints).
ProgressArg = Union[Callable[[Progress], object], bool, None]


@dataclass(frozen=True)
class Joint:
    """A tree joint as the file states it: ``type`` is ``revolute``, ``continuous``,
    ``prismatic``, ``fixed``, ``spherical`` or ``floating``; ``limits`` (lower, upper) in
    radians or metres, or ``None``; ``mimic`` (joint, multiplier, offset) or ``None``."""

    name: str
    type: str
    limits: tuple[float, float] | None
    parent: str
    child: str
    axis: tuple[float, float, float]
    mimic: tuple[str, float, float] | None = None

    @property
    def moves(self) -> bool:
        """False for a fixed joint."""
        return self.type != "fixed"


@dataclass(frozen=True)
class Loop:
    """A loop closure (``<loop>``): its type as written, the links of its two frames, and the
    limits of its (first) motion, if any."""

    name: str
    type: str
    predecessor: str
    successor: str
    limits: tuple[float, float] | None = None


def defaults(question: str) -> dict[str, float]:
    """The defaults of ``question`` (``"solve"``, ``"ik6"``, ``"path-check"``, ...) that the
    library sets: ``precision``, ``max_boxes`` and ``max_memory`` (MiB)."""
    return dict(_native.defaults(question))


class _Reporter:
    """``progress=`` as the extension calls it: ``(decided, processed, pending)``, on the calling
    thread; ``close()`` ends a bar or the stderr line once the run is over."""

    def __init__(self, progress: ProgressArg) -> None:
        self._bar: Any = None
        self._line = False
        self._callback: Callable[[Progress], object] | None = None
        if progress is True:
            try:
                from tqdm.auto import tqdm  # type: ignore[import-untyped, import-not-found, unused-ignore]
            except ImportError:
                self._line = True
            else:
                self._bar = tqdm(total=1000, unit="‰", leave=False)
        elif callable(progress):
            self._callback = progress

    def __call__(self, decided: float, processed: int, pending: int) -> None:
        if self._callback is not None:
            self._callback(Progress(decided, processed, pending))
        elif self._bar is not None:
            if not math.isnan(decided):
                self._bar.n = int(1000 * decided)
            self._bar.set_postfix(processed=processed, pending=pending, refresh=False)
            self._bar.refresh()
        elif self._line:
            sys.stderr.write(f"\r{100.0 * decided:5.1f}% decided, {processed} boxes processed, {pending} pending   ")
            sys.stderr.flush()

    def active(self) -> bool:
        return self._callback is not None or self._bar is not None or self._line

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
        elif self._line:
            sys.stderr.write("\n")


def _progress_callback(progress: ProgressArg) -> _Reporter | None:
    reporter = _Reporter(progress)
    return reporter if reporter.active() else None


def _tip_point(tip_point: str | tuple[str, Sequence[float]] | None) -> str | None:
    if tip_point is None or isinstance(tip_point, str):
        return tip_point
    link, xyz = tip_point
    return f"{link}@{','.join(repr(float(v)) for v in xyz)}"


def _read(source: PathLike) -> tuple[str, str, str]:
    """(name, text, how messages name it) of a path, or of URDF or distance-file text."""
    if isinstance(source, str) and source.lstrip().startswith(("<", "{")):
        return ("", source, "<text>")
    path = os.fspath(source)
    try:
        with open(path, encoding="utf-8") as f:
            return (path, f.read(), path)
    except OSError as e:
        raise InputError(f"reading {path}: {e.strerror} (os error {e.errno})") from None
    except UnicodeDecodeError as e:
        raise InputError(f"reading {path}: stream did not contain valid UTF-8 ({e.reason})") from None


#: The options ``load`` takes as defaults for every question that has them.
LOAD_OPTIONS = frozenset({"base", "tip", "tip_point", "fix", "exact_geometry", "snap_tolerance", "ignore_limits", "uncertainty", "max_boxes", "timeout", "max_memory", "threads"})


def load(source: PathLike, **options: Any) -> Mechanism:
    """Reads a mechanism: a URDF file (loops closed with ``<loop>``, see the README), URDF text
    (a string starting with ``<``), or a distance file (JSON, for ``distances`` only).

    ``options`` are defaults for every later question that takes them: the chain
    (``base``, ``tip``, ``tip_point``, ``fix``, ``exact_geometry``, ``snap_tolerance``,
    ``ignore_limits``), ``uncertainty`` and the limits (``max_boxes``, ``timeout``,
    ``max_memory``, ``threads``). Raises ``InputError`` with the CLI's message when the file
    cannot be read or does not parse.
    """
    unknown = sorted(set(options) - LOAD_OPTIONS)
    if unknown:
        raise TypeError(f"load() got unexpected options {', '.join(unknown)} (it takes {', '.join(sorted(LOAD_OPTIONS))})")
    name, text, label = _read(source)
    native = _native.load(name, text, label)
    return Mechanism(native, options)


class Mechanism:
    """A loaded mechanism (or distance problem), and the questions one may ask it.

    Attributes read from the file: ``name``, ``links``, ``joints`` (:class:`Joint`), ``loops``
    (:class:`Loop`), ``actuated`` (the ``<transmission>`` joints); and the node's view of it:
    ``kind`` (``planar_linkage``, ``spatial_linkage``, ``manipulator_3r``,
    ``parallel_platform``, ``unsupported``, or ``distance_problem`` for a distance file),
    ``services``, ``free_joints`` and ``limitation``.
    """

    def __init__(self, native: _native.Model, options: Mapping[str, Any] | None = None) -> None:
        self._native = native
        self._options = dict(options or {})
        info = native.describe()
        self.source: str = native.source
        if info is None:
            self.name = os.path.splitext(os.path.basename(native.source))[0]
            self.links: list[str] = []
            self.joints: list[Joint] = []
            self.loops: list[Loop] = []
            self.actuated: list[str] = []
        else:
            self.name = str(info["name"])
            self.links = list(info["links"])
            self.joints = [Joint(j["name"], j["type"], j["limits"], j["parent"], j["child"], tuple(j["axis"]), j["mimic"]) for j in info["joints"]]
            self.loops = [Loop(lp["name"], lp["type"], lp["predecessor"], lp["successor"], lp["limits"]) for lp in info["loops"]]
            self.actuated = list(info["actuated"])

    @cached_property
    def _analysis(self) -> dict[str, Any]:
        return dict(self._native.analysis())

    @property
    def kind(self) -> str:
        """What the node would load it as (its ``MechanismInfo.kind``)."""
        return str(self._analysis["kind"])

    @property
    def services(self) -> list[str]:
        """The node's services that answer for it."""
        return list(self._analysis["services"])

    @property
    def free_joints(self) -> list[str]:
        return list(self._analysis["free_joints"])

    @property
    def limitation(self) -> str:
        """What the analyses do not answer for it, in one line (empty when nothing)."""
        return str(self._analysis["limitation"])

    def joint(self, name: str) -> Joint:
        """The joint called ``name``."""
        for j in self.joints:
            if j.name == name:
                return j
        raise KeyError(name)

    def __repr__(self) -> str:
        moving = sum(j.moves for j in self.joints)
        return f"<Mechanism {self.name}: {moving} moving joints, {len(self.loops)} loops, {len(self.links)} links>"

    def _run(self, question: str, given: dict[str, Any], progress: ProgressArg) -> Result:
        options = {k: (v if v is not None else self._options.get(k)) for k, v in given.items()}
        reporter = _progress_callback(progress)
        try:
            return result_of(self._native.run(question, options, reporter))
        finally:
            if reporter is not None:
                reporter.close()

    # The questions. Each keyword argument is the CLI flag of the same name; `None` takes its
    # default. The chain options of the arm questions and the limits are described once, in
    # `ARM_OPTIONS` and `LIMITS` of the docs (docs/manual/python.md) and in each docstring.

    def solve(
        self, fix: Mapping[str, float] | None = None, *, precision: float | None = None, sigma: float | None = None, rho: float | None = None,
        trace: Sequence[str] | None = None, model: str | None = None, no_lp: bool | None = None, newton_width: float | None = None, lp: str | None = None,
        max_boxes: int | None = None, timeout: float | None = None, max_memory: int | None = None, threads: int | None = None, progress: ProgressArg = None,
    ) -> SolveResult:
        """Every configuration of a closed-loop linkage (``linkspace solve``).

        ``fix``: joints (or loops) held at a value, radians or metres. ``precision`` (alias
        ``sigma``, default 1e-3): the largest width of a solution box in every primary
        variable. ``rho`` (0.95), ``trace`` (``["LINK@X,Y[,Z]", ...]``), ``model``
        (``auto``, ``planar``, ``spatial``, ``pose``, ``distances``), ``no_lp``,
        ``newton_width`` (0.25), ``lp`` (``simplex``, ``clarabel``) as on the CLI. Limits:
        ``max_boxes`` (1,000,000), ``timeout`` (seconds, none), ``max_memory`` (MiB, 2048),
        ``threads`` (1).
        """
        if precision is not None and sigma is not None and precision != sigma:
            raise TypeError("give precision or its alias sigma, not both")
        given = dict(fix=fix, precision=precision if precision is not None else sigma, rho=rho, trace=list(trace) if trace is not None else None, model=model, no_lp=no_lp,
                     newton_width=newton_width, lp=lp, max_boxes=max_boxes, timeout=timeout, max_memory=max_memory, threads=threads)
        return _as(SolveResult, self._run("solve", given, progress))

    def singularities(
        self, *, kind: str | None = None, nodes: bool | None = None, precision: float | None = None, uncertainty: float | None = None,
        search_anyway: bool | None = None, arm_budget: float | None = None,
        base: str | None = None, tip: str | None = None, tip_point: str | tuple[str, Sequence[float]] | None = None, fix: Mapping[str, float] | None = None,
        exact_geometry: bool | None = None, snap_tolerance: float | None = None, ignore_limits: bool | None = None,
        max_boxes: int | None = None, timeout: float | None = None, max_memory: int | None = None, threads: int | None = None, progress: ProgressArg = None,
    ) -> SingularitiesResult:
        """Cusps, nodes, internal motions and the cuspidality verdict of an arm's 3R positioning
        structure, and a six-joint arm's whole-arm verdict (``linkspace singularities``).

        ``kind``: ``all`` (default: cusps, internal motions, the verdict, and nodes with
        ``nodes=True``), ``cusps`` or ``nodes``. ``precision`` (1e-4 rad), ``uncertainty``
        (metres, 0), ``search_anyway``, ``arm_budget`` (seconds, 2). The chain: ``base``,
        ``tip``, ``tip_point`` (``"LINK@X,Y,Z"`` or ``(link, (x, y, z))``), ``fix`` (joints
        held), ``exact_geometry``, ``snap_tolerance`` (1e-5 rad), ``ignore_limits``. Limits:
        ``max_boxes`` (5,000,000 per search), ``timeout``, ``max_memory`` (MiB, 256),
        ``threads``.
        """
        given = dict(kind=kind, nodes=nodes, precision=precision, uncertainty=uncertainty, search_anyway=search_anyway, arm_budget=arm_budget,
                     **_chain(base, tip, tip_point, fix, exact_geometry, snap_tolerance, ignore_limits), **_limits(max_boxes, timeout, max_memory, threads))
        return _as(SingularitiesResult, self._run("singularities", given, progress))

    def ik(
        self, point: npt.ArrayLike, *, precision: float | None = None, uncertainty: float | None = None,
        base: str | None = None, tip: str | None = None, tip_point: str | tuple[str, Sequence[float]] | None = None, fix: Mapping[str, float] | None = None,
        exact_geometry: bool | None = None, snap_tolerance: float | None = None, ignore_limits: bool | None = None,
        max_boxes: int | None = None, timeout: float | None = None, max_memory: int | None = None, threads: int | None = None, progress: ProgressArg = None,
    ) -> IkResult:
        """Every joint solution of an arm's 3R positioning structure for a point
        (``linkspace ik``): ``point`` is (x, y, z) in the root frame, or (r, z) in the first
        joint's frame. ``precision`` (1e-6 rad), ``uncertainty``; chain options and limits as
        for :meth:`singularities` (``max_boxes`` 200,000)."""
        given = dict(point=_floats(point), precision=precision, uncertainty=uncertainty,
                     **_chain(base, tip, tip_point, fix, exact_geometry, snap_tolerance, ignore_limits), **_limits(max_boxes, timeout, max_memory, threads))
        return _as(IkResult, self._run("ik", given, progress))

    def ik6(
        self, pose: npt.ArrayLike | None = None, *, xyz: Sequence[float] | None = None, rpy: Sequence[float] | None = None, quaternion: Sequence[float] | None = None,
        precision: float | None = None,
        base: str | None = None, tip: str | None = None, fix: Mapping[str, float] | None = None,
        exact_geometry: bool | None = None, snap_tolerance: float | None = None, ignore_limits: bool | None = None,
        max_boxes: int | None = None, timeout: float | None = None, max_memory: int | None = None, threads: int | None = None, progress: ProgressArg = None,
    ) -> Ik6Result:
        """Every joint solution of a six-revolute arm for a pose of its tip frame, each certified
        (``linkspace ik6``).

        ``pose``: a 4x4 homogeneous transform (rotation orthonormal, last row 0, 0, 0, 1 to
        within 1e-6), 6 numbers (x, y, z, roll, pitch, yaw; URDF's Rz·Ry·Rx) or 7 (x, y, z, qx,
        qy, qz, qw); or ``xyz=`` with ``rpy=`` or ``quaternion=`` (x, y, z, w). ``precision``
        (1e-9 rad); chain options and limits as for :meth:`singularities` (``max_boxes``
        20,000,000).
        """
        numbers = _pose(pose, xyz, rpy, quaternion)
        given = dict(pose=numbers, precision=precision, **_chain(base, tip, None, fix, exact_geometry, snap_tolerance, ignore_limits), **_limits(max_boxes, timeout, max_memory, threads))
        return _as(Ik6Result, self._run("ik6", given, progress))

    def ik6_many(
        self, poses: npt.ArrayLike | Sequence[npt.ArrayLike], *, precision: float | None = None,
        base: str | None = None, tip: str | None = None, fix: Mapping[str, float] | None = None,
        exact_geometry: bool | None = None, snap_tolerance: float | None = None, ignore_limits: bool | None = None,
        max_boxes: int | None = None, timeout: float | None = None, max_memory: int | None = None, threads: int | None = None, progress: ProgressArg = None,
    ) -> list[Ik6Result]:
        """:meth:`ik6` at every pose of ``poses``, in order (``linkspace ik6 --poses``): an
        (N, 4, 4) array of transforms, an (N, 6) or (N, 7) array, or a sequence of anything
        :meth:`ik6` takes as ``pose``. The mechanism is read once; every pose's form is checked
        before the first is solved (an :class:`InputError` names the pose), and the limits
        bound each pose's answer."""
        if isinstance(poses, np.ndarray) and poses.ndim < 2:
            raise InputError(f"ik6_many takes a list of poses (an array of {poses.ndim} dimensions is one pose at most: call ik6)")
        items = list(poses)  # type: ignore[arg-type]
        numbers = []
        for k, pose in enumerate(items):
            try:
                flat = _floats(pose)
            except (TypeError, ValueError) as e:
                raise InputError(f"ik6_many: pose {k}: {e}") from None
            if flat.size not in (6, 7, 16):
                raise InputError(f"ik6_many: pose {k} has {flat.size} numbers: give 6 (xyz + rpy), 7 (xyz + quaternion) or a 4x4 transform")
            numbers.append(flat)
        chain = _chain(base, tip, None, fix, exact_geometry, snap_tolerance, ignore_limits)
        limits = _limits(max_boxes, timeout, max_memory, threads)
        results = []
        for k, flat in enumerate(numbers):
            try:
                results.append(_as(Ik6Result, self._run("ik6", dict(pose=flat, precision=precision, **chain, **limits), progress)))
            except InputError as e:
                raise type(e)(f"ik6_many: pose {k}: {e}") from None
        return results

    def self_motion(
        self, pose: npt.ArrayLike | None = None, *, xyz: Sequence[float] | None = None, rpy: Sequence[float] | None = None, quaternion: Sequence[float] | None = None,
        parameter: str | None = None, range: Sequence[float] | None = None, cell: float | None = None, precision: float | None = None,
        base: str | None = None, tip: str | None = None,
        exact_geometry: bool | None = None, snap_tolerance: float | None = None, ignore_limits: bool | None = None,
        max_boxes: int | None = None, timeout: float | None = None, max_memory: int | None = None, threads: int | None = None, progress: ProgressArg = None,
    ) -> SelfMotionResult:
        """Every configuration of a seven-revolute arm at a pose of its tip, a union of curves
        (``linkspace self-motion``): ``pose`` as for :meth:`ik6`; ``parameter`` the joint whose
        range (or ``range=(lo, hi)`` of it) is cut into cells ``cell`` wide (0.002 rad), the
        curves' parameter (default: the third joint); ``precision`` (0.1 rad) bounds the boxes
        that are not certified. Limits as for :meth:`ik6`; ``threads`` search cells side by side.
        """
        numbers = _pose(pose, xyz, rpy, quaternion)
        given = dict(pose=numbers, parameter=parameter, range=_floats(range) if range is not None else None, cell=cell, precision=precision,
                     **_chain(base, tip, None, None, exact_geometry, snap_tolerance, ignore_limits), **_limits(max_boxes, timeout, max_memory, threads))
        return _as(SelfMotionResult, self._run("self-motion", given, progress))

    def path_check(
        self, waypoints: npt.ArrayLike, *, joint_names: Sequence[str] | None = None, singular_set: str | None = None, precision: float | None = None,
        base: str | None = None, tip: str | None = None, tip_point: str | tuple[str, Sequence[float]] | None = None, fix: Mapping[str, float] | None = None,
        exact_geometry: bool | None = None, snap_tolerance: float | None = None, ignore_limits: bool | None = None,
        max_boxes: int | None = None, timeout: float | None = None, max_memory: int | None = None, threads: int | None = None, progress: ProgressArg = None,
    ) -> PathCheckResult:
        """Where a joint path (straight segments between waypoints) meets a singularity
        (``linkspace path-check``): of the six-revolute arm (det J = 0, ``singular_set="6r"``)
        or of its 3R positioning structure (det Df = 0, ``"3r"``); by default 6r when the arm
        has six revolute joints and no sub-chain is chosen.

        ``waypoints``: an (n, k) array, one row of joint values (radians) per waypoint, in the
        order of ``joint_names`` (a trajectory's columns, any order, more joints allowed) or,
        without it, as ``ik6`` orders them. ``precision`` (1e-9 rad): crossings are narrowed to
        this width. Bounded by ``timeout`` and its pieces per segment.
        """
        given = dict(waypoints=np.atleast_2d(np.asarray(waypoints, dtype=np.float64)), joint_names=list(joint_names) if joint_names is not None else None, singular_set=singular_set,
                     precision=precision, **_chain(base, tip, tip_point, fix, exact_geometry, snap_tolerance, ignore_limits), **_limits(max_boxes, timeout, max_memory, threads))
        return _as(PathCheckResult, self._run("path-check", given, progress))

    def collisions(
        self, *, precision: float | None = None,
        base: str | None = None, tip: str | None = None, tip_point: str | tuple[str, Sequence[float]] | None = None, fix: Mapping[str, float] | None = None,
        exact_geometry: bool | None = None, snap_tolerance: float | None = None, ignore_limits: bool | None = None,
        max_boxes: int | None = None, timeout: float | None = None, max_memory: int | None = None, threads: int | None = None, progress: ProgressArg = None,
    ) -> CollisionsResult:
        """The configurations (joint 2, joint 3) of a 3R chain where its collision capsules meet
        (``linkspace collisions``). ``precision`` (1e-2 rad): the largest width of undecided
        boxes; chain options and limits as for :meth:`singularities` (``max_boxes``
        5,000,000)."""
        given = dict(precision=precision, **_chain(base, tip, tip_point, fix, exact_geometry, snap_tolerance, ignore_limits), **_limits(max_boxes, timeout, max_memory, threads))
        return _as(CollisionsResult, self._run("collisions", given, progress))

    def loop_singularities(
        self, *, kind: str | None = None, actuated: Sequence[str] | str | None = None, output: Sequence[str] | str | None = None, fix: Mapping[str, float] | None = None,
        precision: float | None = None, grid: int | None = None, from_: float | None = None, to: float | None = None, assembly: Sequence[float] | None = None,
        max_step: float | None = None, min_step: float | None = None,
        max_boxes: int | None = None, timeout: float | None = None, max_memory: int | None = None, threads: int | None = None, progress: ProgressArg = None,
    ) -> LoopSingularitiesResult:
        """Certified singular sets of a closed-loop linkage (``linkspace loop-singularities``).

        ``kind``: ``all`` (default: C-space, input and output sets), ``cspace``, ``input``,
        ``output``, ``image`` (2-dof: the type-II image in actuator space, on a ``grid``
        of 128 cells per side), ``cusps``, ``nodes``, or ``motion`` (1-dof: follow the actuated
        joint from ``from_`` to ``to`` starting at ``assembly``, one value per free joint, with
        steps between ``min_step`` (1e-6) and ``max_step`` (0.05)). ``actuated``: joints
        (default: the file's transmissions); ``output``: ``"LINK@X,Y"`` or joints;
        ``precision`` (1e-4).
        """
        given = dict(kind=kind, actuated=actuated, output=output, fix=fix, precision=precision, grid=grid, from_=from_, to=to,
                     assembly=_floats(assembly) if assembly is not None else None, max_step=max_step, min_step=min_step, **_limits(max_boxes, timeout, max_memory, threads))
        return _as(LoopSingularitiesResult, self._run("loop-singularities", given, progress))

    def distances(
        self, fix: Mapping[str, float] | None = None, *, precision: float | None = None, sigma: float | None = None, rho: float | None = None,
        redundant: bool | None = None, formulation: str | None = None, faces: str | None = None,
        max_boxes: int | None = None, timeout: float | None = None, max_memory: int | None = None, threads: int | None = None, progress: ProgressArg = None,
    ) -> DistancesResult:
        """A distance problem by Cayley–Menger determinants (``linkspace distances``): a
        platform read from URDF (``fix``: each leg's squared length) or a distance file (``fix``:
        named squared distances). ``precision`` (alias ``sigma``, 0.01), ``rho`` (0.99 for the
        determinants, 0.9 for coordinates), ``redundant``, ``formulation`` (``auto``,
        ``points``, ``line``, ``shared``, ``split``), ``faces`` (``corners``, ``interval``)."""
        if precision is not None and sigma is not None and precision != sigma:
            raise TypeError("give precision or its alias sigma, not both")
        given = dict(fix=fix, precision=precision if precision is not None else sigma, rho=rho, redundant=redundant, formulation=formulation, faces=faces, **_limits(max_boxes, timeout, max_memory, threads))
        return _as(DistancesResult, self._run("distances", given, progress))


R = TypeVar("R", bound=Result)


def _as(cls: type[R], r: Result) -> R:
    if not isinstance(r, cls):
        raise TypeError(f"expected a {cls.__name__}, the library answered {type(r).__name__}")
    return r


def _chain(base: str | None, tip: str | None, tip_point: str | tuple[str, Sequence[float]] | None, fix: Mapping[str, float] | None,
           exact_geometry: bool | None, snap_tolerance: float | None, ignore_limits: bool | None) -> dict[str, Any]:
    return dict(base=base, tip=tip, tip_point=_tip_point(tip_point), fix=fix, exact_geometry=exact_geometry, snap_tolerance=snap_tolerance, ignore_limits=ignore_limits)


def _limits(max_boxes: int | None, timeout: float | None, max_memory: int | None, threads: int | None) -> dict[str, Any]:
    return dict(max_boxes=max_boxes, timeout=timeout, max_memory=max_memory, threads=threads)


def _floats(values: npt.ArrayLike) -> npt.NDArray[np.float64]:
    try:
        return np.asarray(values, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError) as e:
        raise TypeError(f"expected numbers, got {values!r}") from e


def _pose(pose: npt.ArrayLike | None, xyz: Sequence[float] | None, rpy: Sequence[float] | None, quaternion: Sequence[float] | None) -> npt.NDArray[np.float64]:
    if pose is not None:
        if xyz is not None or rpy is not None or quaternion is not None:
            raise TypeError("give pose, or xyz with rpy or quaternion, not both")
        return _floats(pose)
    rotation = rpy if rpy is not None else quaternion
    if xyz is None or rotation is None or (rpy is not None and quaternion is not None):
        raise TypeError("ik6 needs pose, or xyz with one of rpy and quaternion")
    return np.concatenate([_floats(xyz), _floats(rotation)])
