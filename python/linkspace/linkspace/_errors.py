"""The exceptions of linkspace: one hierarchy under :class:`Error`.

Expected outcomes of a search are results, not exceptions: nothing found is an empty box set,
and a limit reached (``timeout=``, ``max_boxes=``, ``max_memory=``) is a result whose
``completeness`` is incomplete, with the limit as its reason. Each message is the one line the
CLI prints after ``error:`` for the same request.
"""

from __future__ import annotations

__all__ = ["Error", "InputError", "UnsupportedError", "AnalysisError", "InternalError"]


class Error(Exception):
    """Every error linkspace raises (``KeyboardInterrupt`` aside, which stays itself)."""


class InputError(Error, ValueError):
    """The file or the request is wrong: a URDF that does not parse, an unknown joint in
    ``fix=``, a precision out of range, a point with the wrong number of coordinates."""


class UnsupportedError(InputError):
    """The mechanism lies outside what the question's analysis takes: not a serial chain for
    an arm question, not a linkage for ``solve``, no collision geometry for ``collisions``."""


class AnalysisError(Error):
    """The analysis itself found the request impossible while running (a geometry degenerate
    where it looked regular); rare."""


class InternalError(Error):
    """A defect of linkspace (a Rust panic, caught before it reached Python)."""
