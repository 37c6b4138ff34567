"""Pipelines: polylines on the sea floor, their files, the built-in layouts and a generator.

A pipeline is a polyline of points ``(x north, y east)`` in metres in the earth frame. The AUV
starts on the first point, heading to the second. Files are JSON ``{"points": [[x, y], ...]}``.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numba import njit

from pipefollow.files.atomic import read_text_file, write_text_atomic

BUILTIN_NAMES = ("paper-left", "paper-right", "paper-validation")


class PipelineError(ValueError):
    """A pipeline (file) that cannot be used; the message names the input and the problem."""


@dataclass(frozen=True, eq=False)
class Pipeline:
    """An immutable polyline with arc length.

    Attributes:
        points: (n, 2) float64 array of vertices (m), earth frame, n ≥ 2, no zero-length segment.
        name: label used in plots and reports.
    """

    points: np.ndarray
    name: str = "pipeline"
    cumulative: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        pts = _validated_points(self.points, self.name)
        pts.setflags(write=False)
        cum = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))))
        cum.setflags(write=False)
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "cumulative", cum)

    @property
    def length(self) -> float:
        """Total arc length (m)."""
        return float(self.cumulative[-1])

    @property
    def start_heading(self) -> float:
        """Heading of the first segment (rad, clockwise from north)."""
        d = self.points[1] - self.points[0]
        return math.atan2(d[1], d[0])

    def point_at(self, s: float) -> np.ndarray:
        """The point at arc length ``s`` (clipped to the pipeline)."""
        return np.array(point_at(self.points, self.cumulative, float(s)))

    def project(self, x: float, y: float) -> tuple[float, float]:
        """Arc length and distance of the closest point of the whole pipeline to ``(x, y)``."""
        s = project(self.points, self.cumulative, x, y, -np.inf, np.inf)
        px, py = point_at(self.points, self.cumulative, s)
        return s, math.hypot(x - px, y - py)

    def mirror(self, name: str | None = None) -> Pipeline:
        """Mirror image across the start heading's axis: left turns become right turns."""
        p0 = self.points[0]
        h = self.start_heading
        axis = np.array([math.cos(h), math.sin(h)])
        rel = self.points - p0
        along = rel @ axis
        mirrored = p0 + 2.0 * np.outer(along, axis) - rel
        return Pipeline(mirrored, name or f"{self.name}-mirrored")

    def to_dict(self) -> dict:
        """The file form ``{"points": [[x, y], ...]}``."""
        return {"points": self.points.tolist()}

    def save(self, path: str | os.PathLike) -> None:
        """Write the pipeline as JSON, atomically."""
        write_text_atomic(Path(path), json.dumps(self.to_dict(), indent=1) + "\n")


def _validated_points(points, source: str) -> np.ndarray:
    try:
        pts = np.array(points, dtype=np.float64)
    except OverflowError:  # a JSON integer beyond float range: not a ValueError
        raise PipelineError(f"{source}: points contain a number too large for a float") from None
    except (TypeError, ValueError):
        raise PipelineError(f"{source}: points must be a list of [x, y] number pairs") from None
    if pts.size == 0:  # an empty list has shape (0,): report the count, not the shape
        raise PipelineError(f"{source}: needs at least two distinct points, got 0")
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise PipelineError(f"{source}: points must be a list of [x, y] pairs, got shape {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise PipelineError(f"{source}: points contain NaN or infinite values")
    if len(pts) < 2:
        raise PipelineError(f"{source}: needs at least two distinct points, got {len(pts)}")
    seg = np.hypot(*np.diff(pts, axis=0).T)
    if np.any(seg <= 1e-9):
        i = int(np.argmax(seg <= 1e-9))
        raise PipelineError(f"{source}: zero-length segment between points {i} and {i + 1}")
    return pts


def load(path: str | os.PathLike) -> Pipeline:
    """Read a pipeline file; any problem raises :class:`PipelineError` naming the file."""
    p = Path(path)
    source = f"pipeline file '{p}'"
    text = read_text_file(p, source, PipelineError)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise PipelineError(f"{source}: not valid JSON ({e.msg} at line {e.lineno})") from None
    if not isinstance(data, dict) or "points" not in data:
        raise PipelineError(f'{source}: expected an object with a "points" list')
    rows = data["points"]
    if not isinstance(rows, list) or not all(
        isinstance(row, list) and len(row) == 2 and all(_is_number(v) for v in row) for row in rows
    ):
        raise PipelineError(f'{source}: "points" must be a list of [x, y] number pairs')
    return Pipeline(_validated_points(rows, source), name=p.stem)


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _polyline(lengths, turns_deg, name: str) -> Pipeline:
    """Polyline from segment lengths and turns (deg, positive to starboard), heading north at 0."""
    pts = [(0.0, 0.0)]
    heading = 0.0
    for i, length in enumerate(lengths):
        if i > 0:
            heading += math.radians(turns_deg[i - 1])
        x, y = pts[-1]
        pts.append((x + length * math.cos(heading), y + length * math.sin(heading)))
    return Pipeline(np.array(pts), name)


def builtin(name: str) -> Pipeline:
    """The built-in pipelines of docs/design.md.

    ``paper-left``: 2 m, 2.5 m, 8 m with 90° left turns (paper §4.1); ``paper-right``: its
    mirror image; ``paper-validation``: mixed ±45° and ±90° turns, segments 3–6 m (paper §4.2).
    """
    if name == "paper-left":
        return _polyline([2.0, 2.5, 8.0], [-90.0, -90.0], name)
    if name == "paper-right":
        return Pipeline(builtin("paper-left").mirror().points, name)
    if name == "paper-validation":
        return _polyline([4.0, 5.0, 3.5, 6.0, 4.5, 5.0, 8.0], [-45.0, 90.0, -90.0, 45.0, -90.0, 45.0], name)
    raise PipelineError(f"pipeline '{name}': unknown built-in (choose from {', '.join(BUILTIN_NAMES)})")


def random_pipeline(
    rng: np.random.Generator,
    n_segments: int = 5,
    length_range: tuple[float, float] = (3.0, 6.0),
    turn_range_deg: tuple[float, float] = (30.0, 90.0),
    name: str = "random",
) -> Pipeline:
    """A random polyline: segment lengths and turn magnitudes uniform in the ranges, random sides."""
    if n_segments < 1:
        raise ValueError(f"n_segments must be at least 1, got {n_segments}")
    lo, hi = length_range
    if not 0.0 < lo <= hi:
        raise ValueError(f"length_range must satisfy 0 < low <= high, got {length_range}")
    tlo, thi = turn_range_deg
    if not 0.0 <= tlo <= thi <= 180.0:
        raise ValueError(f"turn_range_deg must satisfy 0 <= low <= high <= 180, got {turn_range_deg}")
    lengths = rng.uniform(lo, hi, n_segments)
    turns = rng.uniform(tlo, thi, n_segments - 1) * rng.choice([-1.0, 1.0], n_segments - 1)
    return _polyline(lengths, turns, name)


@njit(cache=True)
def point_at(points, cum, s):
    """Point (x, y) at arc length ``s`` along the polyline, clipped to its ends."""
    n = points.shape[0]
    if s <= 0.0:
        return points[0, 0], points[0, 1]
    if s >= cum[n - 1]:
        return points[n - 1, 0], points[n - 1, 1]
    i = np.searchsorted(cum, s) - 1
    t = (s - cum[i]) / (cum[i + 1] - cum[i])
    return (
        points[i, 0] + t * (points[i + 1, 0] - points[i, 0]),
        points[i, 1] + t * (points[i + 1, 1] - points[i, 1]),
    )


@njit(cache=True)
def project(points, cum, x, y, s_lo, s_hi):
    """Arc length of the point closest to ``(x, y)`` among the pipeline within ``[s_lo, s_hi]``.

    The window keeps the progress estimate continuous where the pipe comes back near itself.
    """
    best_s = max(0.0, min(s_lo, cum[-1]))
    best_d2 = np.inf
    for i in range(points.shape[0] - 1):
        a, b = cum[i], cum[i + 1]
        if b < s_lo or a > s_hi:
            continue
        x0, y0 = points[i, 0], points[i, 1]
        dx, dy = points[i + 1, 0] - x0, points[i + 1, 1] - y0
        seg2 = dx * dx + dy * dy
        t = ((x - x0) * dx + (y - y0) * dy) / seg2
        seg_len = b - a
        t_lo = max(0.0, (s_lo - a) / seg_len)
        t_hi = min(1.0, (s_hi - a) / seg_len)
        t = min(max(t, t_lo), t_hi)
        px, py = x0 + t * dx, y0 + t * dy
        d2 = (x - px) ** 2 + (y - py) ** 2
        if d2 < best_d2:
            best_d2 = d2
            best_s = a + t * seg_len
    return best_s
