"""``sweep``: one analysis over a grid (or a list) of design parameters, as ``linkspace sweep``."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Union

import numpy as np
import numpy.typing as npt

from . import _native
from ._mechanism import ProgressArg, _progress_callback

__all__ = ["sweep", "SweepResult"]


@dataclass(frozen=True)
class SweepResult:
    """A sweep's results: ``rows`` (one dict per task, in index order: what ``results.jsonl``
    holds after its header line), ``summary`` (``summary.json``), ``csv`` (``results.csv``),
    ``map_svg`` (``map.svg``, for a sweep of two parameters), ``out`` (where they were
    written, if anywhere) and ``labels`` (the parameters' names, the columns of ``values``)."""

    rows: list[dict[str, Any]]
    summary: dict[str, Any]
    csv: str
    map_svg: str | None
    out: Path | None = None
    labels: tuple[str, ...] = field(default=())

    @property
    def values(self) -> npt.NDArray[np.float64]:
        """The parameter values of every task, shape (tasks, parameters)."""
        return np.array([r["values"] for r in self.rows], dtype=np.float64).reshape(len(self.rows), -1)

    def column(self, key: str) -> list[Any]:
        """Field ``key`` (``verdict``, ``count``, ``status``, ...) of every task."""
        return [r.get(key) for r in self.rows]


def sweep(spec: Union[str, "os.PathLike[str]"], out: Union[str, "os.PathLike[str]", None] = None, *, max_tasks: int | None = None, max_boxes: int | None = None,
          timeout: float | None = None, max_memory: int | None = None, threads: int | None = None, progress: ProgressArg = None) -> SweepResult:
    """Runs the sweep of ``spec`` (JSON; the manual's sweep page) as ``linkspace sweep SPEC --out
    OUT``: every task with its limits (the call's over the spec's; defaults 60 s and 256 MiB per
    task, the analysis's boxes), ``threads`` tasks at a time, each on one thread. With ``out``,
    writes ``results.jsonl``, ``results.csv``, ``summary.json`` and ``map.svg`` there in the
    CLI's formats (a directory that already holds results is refused; the CLI's ``--resume``
    continues such a sweep). ``progress`` sees the share of tasks done. Ctrl-C stops the sweep
    and raises ``KeyboardInterrupt``."""
    options = dict(max_tasks=max_tasks, max_boxes=max_boxes, timeout=timeout, max_memory=max_memory, threads=threads)
    reporter = _progress_callback(progress)
    try:
        rows, summary, csv, map_svg = _native.sweep(os.fspath(spec), None if out is None else os.fspath(out), options, reporter)
    finally:
        if reporter is not None:
            reporter.close()
    parsed = json.loads(summary)
    return SweepResult([json.loads(r) for r in rows], parsed, csv, map_svg, None if out is None else Path(out), tuple(parsed["parameters"]))
