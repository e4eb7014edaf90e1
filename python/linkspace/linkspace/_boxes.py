"""Box sets: interval boxes as numpy arrays, with their tags and clusters."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = ["BoxSet"]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
StrArray = npt.NDArray[np.str_]

#: Colours of the tags in :meth:`BoxSet.plot` (proven, proven unique, open, and the
#: collision classes).
TAG_COLOURS = {"unique": "tab:blue", "solution": "tab:cyan", "undecided": "tab:red", "colliding": "tab:red", "free": "tab:green"}


class BoxSet:
    """Boxes that together enclose every point sought, one row per box.

    ``lo[i, j]`` and ``hi[i, j]`` bound column ``columns[j]`` (a joint, in radians or metres,
    or another named quantity) over box ``i``. ``tags[i]`` says what is known of box ``i``:
    ``"unique"`` (proven to hold exactly one point sought), ``"solution"`` (kept at the
    precision: it may hold points sought) or ``"undecided"`` (a limit or the precision left it
    open); a collision map tags its boxes ``"colliding"``, ``"free"`` or ``"undecided"``.
    ``clusters[i]`` is the box's connected component (``-1`` when it has none, e.g. undecided
    boxes); ``cluster_count`` counts the components.
    """

    __slots__ = ("columns", "lo", "hi", "tags", "clusters", "cluster_count")

    columns: tuple[str, ...]
    lo: FloatArray
    hi: FloatArray
    tags: StrArray
    clusters: IntArray
    cluster_count: int

    def __init__(self, columns: Sequence[str], lo: npt.ArrayLike, hi: npt.ArrayLike, tags: Sequence[str] | npt.ArrayLike, clusters: npt.ArrayLike | None = None, cluster_count: int | None = None) -> None:
        self.columns = tuple(columns)
        d = len(self.columns)
        self.tags = np.asarray(tags, dtype=np.str_).reshape(-1)
        n = self.tags.shape[0]
        self.lo = np.asarray(lo, dtype=np.float64).reshape(n, d)
        self.hi = np.asarray(hi, dtype=np.float64).reshape(n, d)
        self.clusters = np.full(n, -1, dtype=np.int64) if clusters is None else np.asarray(clusters, dtype=np.int64).reshape(n)
        if cluster_count is None:
            cluster_count = int(self.clusters.max()) + 1 if n and self.clusters.max() >= 0 else 0
        self.cluster_count = cluster_count

    @classmethod
    def from_records(cls, records: Iterable[Mapping[str, Any]], columns: Sequence[str], tag: Callable[[Mapping[str, Any]], str], key: str = "joints", cluster: Callable[[Mapping[str, Any]], int] | None = None, cluster_count: int | None = None) -> BoxSet:
        """The boxes of report records, each holding ``{column: [lo, hi]}`` under ``key``."""
        rows = list(records)
        cols = list(columns)
        if rows:
            present = rows[0][key]
            cols = [c for c in cols if c in present] + sorted(c for c in present if c not in cols)
        bounds = np.array([[r[key][c] for c in cols] for r in rows], dtype=np.float64).reshape(len(rows), len(cols), 2)
        clusters = [cluster(r) for r in rows] if cluster is not None else None
        return cls(cols, bounds[:, :, 0], bounds[:, :, 1], [tag(r) for r in rows], clusters, cluster_count)

    @classmethod
    def concat(cls, sets: Sequence[BoxSet]) -> BoxSet:
        """The rows of ``sets`` (same columns, or empty) one after another."""
        nonempty = [s for s in sets if len(s)] or list(sets[:1])
        if not nonempty:
            return cls((), np.empty((0, 0)), np.empty((0, 0)), [])
        columns = nonempty[0].columns
        if any(s.columns != columns for s in nonempty):
            raise ValueError("box sets over different columns")
        return cls(columns, np.vstack([s.lo for s in nonempty]), np.vstack([s.hi for s in nonempty]), np.concatenate([s.tags for s in nonempty]), np.concatenate([s.clusters for s in nonempty]), max(s.cluster_count for s in nonempty))

    def __len__(self) -> int:
        return int(self.lo.shape[0])

    def __repr__(self) -> str:
        counts = ", ".join(f"{int((self.tags == t).sum())} {t}" for t in dict.fromkeys(self.tags.tolist()))
        return f"BoxSet({len(self)} boxes over ({', '.join(self.columns)}){': ' + counts if counts else ''})"

    def __getitem__(self, rows: int | slice | npt.ArrayLike) -> BoxSet:
        """The boxes picked by an index, a slice or a boolean mask (e.g. ``boxes[boxes.tags == "unique"]``)."""
        index = np.atleast_1d(np.arange(len(self))[rows if isinstance(rows, (int, slice)) else np.asarray(rows)])
        return BoxSet(self.columns, self.lo[index], self.hi[index], self.tags[index], self.clusters[index], self.cluster_count)

    def midpoints(self) -> FloatArray:
        """The middle of each box, shape (n, d): one point per box (per solution, where every
        box is one)."""
        return (self.lo + self.hi) / 2

    def widths(self) -> FloatArray:
        """The width of each box in each column, shape (n, d)."""
        return self.hi - self.lo

    def column(self, name: str) -> FloatArray:
        """Column ``name`` as an (n, 2) array of [lo, hi]."""
        j = self.columns.index(name)
        return np.stack([self.lo[:, j], self.hi[:, j]], axis=1)

    def with_tag(self, *tags: str) -> BoxSet:
        """The boxes tagged with one of ``tags``."""
        return self[np.isin(self.tags, list(tags))]

    @property
    def solutions(self) -> BoxSet:
        """The proven boxes (tagged unique or solution)."""
        return self.with_tag("unique", "solution")

    @property
    def undecided(self) -> BoxSet:
        """The boxes left open."""
        return self.with_tag("undecided")

    def contains(self, point: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """For each box, whether it holds ``point`` (one value per column)."""
        p = np.asarray(point, dtype=np.float64).reshape(1, -1)
        inside: npt.NDArray[np.bool_] = np.all((self.lo <= p) & (p <= self.hi), axis=1)
        return inside

    def plot(self, x: str | None = None, y: str | None = None, ax: Any = None, color_by: str = "tag", **patch: Any) -> Any:
        """Draws the boxes' projections on columns ``x`` and ``y`` (the first two by default) as
        rectangles, coloured by tag or by cluster (``color_by="cluster"``), on ``ax`` (a new
        figure's when ``None``); returns the axes. Needs matplotlib."""
        try:
            import matplotlib.pyplot as plt
            from matplotlib.collections import PatchCollection
            from matplotlib.patches import Patch, Rectangle
        except ImportError as e:
            raise ImportError("BoxSet.plot needs matplotlib: pip install matplotlib") from e
        if len(self.columns) < 2 and (x is None or y is None):
            raise ValueError(f"plot needs two columns, the box set has {len(self.columns)}")
        x = self.columns[0] if x is None else x
        y = self.columns[1] if y is None else y
        i, j = self.columns.index(x), self.columns.index(y)
        if ax is None:
            _, ax = plt.subplots()
        if color_by == "cluster":
            cmap = plt.get_cmap("tab10")
            colours = ["0.6" if c < 0 else cmap(int(c) % 10) for c in self.clusters]
            legend = [Patch(color=cmap(c % 10), label=f"cluster {c}") for c in sorted({int(c) for c in self.clusters if c >= 0})[:10]]
        elif color_by == "tag":
            colours = [TAG_COLOURS.get(str(t), "0.5") for t in self.tags]
            legend = [Patch(color=TAG_COLOURS.get(t, "0.5"), label=t) for t in dict.fromkeys(self.tags.tolist())]
        else:
            raise ValueError(f"color_by '{color_by}': expected tag or cluster")
        rects = [Rectangle((self.lo[k, i], self.lo[k, j]), self.hi[k, i] - self.lo[k, i], self.hi[k, j] - self.lo[k, j]) for k in range(len(self))]
        patch.setdefault("linewidth", 0.5)
        patch.setdefault("alpha", 0.8)
        ax.add_collection(PatchCollection(rects, facecolors=colours, edgecolors=colours, **patch), autolim=True)
        ax.autoscale_view()
        ax.set_xlabel(x)
        ax.set_ylabel(y)
        if legend:
            ax.legend(handles=legend, loc="best", fontsize="small")
        return ax
