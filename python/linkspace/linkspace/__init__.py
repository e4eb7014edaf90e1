"""linkspace: every configuration a mechanism can take, and where it goes singular, with
guarantees: branch-and-prune over interval boxes, from URDF, in process.

>>> import linkspace
>>> m = linkspace.load("urdf/double_butterfly.urdf")
>>> r = m.solve(fix={"joint6": 1.1760052070951352}, precision=1e-4)
>>> len(r.solutions), r.completeness.complete
(6, True)

``load`` reads a file (or URDF text) into a :class:`Mechanism`, which has one method per
question of the CLI (``solve``, ``singularities``, ``ik``, ``ik6``, ``path_check``,
``collisions``, ``loop_singularities``, ``distances``) with the CLI's options as keyword
arguments; ``sweep`` runs a design sweep. Results are typed objects with numpy box sets (:class:`BoxSet`), verdicts
(:class:`Verdict`) and ``to_dict()``, equal to the CLI's ``--json`` report of the same run.
"""

from ._boxes import BoxSet
from ._errors import AnalysisError, Error, InputError, InternalError, UnsupportedError
from ._mechanism import Joint, Loop, Mechanism, Progress, defaults, load
from ._native import __version__
from ._sweep import SweepResult, sweep
from ._results import (
    CollisionsResult, Completeness, DistancesResult, Ik6Result, IkResult, LoopSingularitiesResult, Node, PathCheckResult, Result, Scope,
    Segment, SelfMotionResult, SingularitiesResult, SingularSet, SolveResult, Verdict,
)

__all__ = [
    "load", "defaults", "sweep", "SweepResult", "Mechanism", "Joint", "Loop", "Progress", "BoxSet", "Completeness", "Scope", "Verdict", "Result", "SolveResult",
    "SingularitiesResult", "Node", "IkResult", "Ik6Result", "SelfMotionResult", "PathCheckResult", "Segment", "CollisionsResult", "DistancesResult",
    "SingularSet", "LoopSingularitiesResult", "Error", "InputError", "UnsupportedError", "AnalysisError", "InternalError", "__version__",
]
