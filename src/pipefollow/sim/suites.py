"""Pipeline suites: named, seeded families of random pipes, for training and for held-out tests.

A pipe of a suite is a polyline that alternates straight runs with bends. A bend turns the pipe
by an angle drawn from the difficulty's range, either at a sharp corner or along a circular arc
(discretized into pieces of at most :data:`ARC_STEP_DEG`). The side of each bend is random, but
a bend that would take the pipe's heading more than :data:`MAX_HEADING_DEG` away from its start
heading turns the other way, so no pipe doubles back over itself.

Difficulty levels (:data:`LEVELS`):

============  ===========  ===============  ==========  =================
level         turns (deg)  straights (m)    arc share   arc radius (m)
============  ===========  ===============  ==========  =================
``easy``      10 – 30      6 – 12           50 %        3 – 6
``medium``    30 – 60      4 – 8            50 %        2 – 4
``hard``      45 – 90      2 – 4            25 %        1 – 2
``sharp``     90 – 150     3 – 5            0 %         –
============  ===========  ===============  ==========  =================

``sharp`` (only the held-out suite ``heldout-sharp``) has corners only, hooks up to 150°; its
heading may go to ±:data:`SHARP_MAX_HEADING_DEG` (a hook from a straight north needs 150°), and a
bend whose next straight (at its longest) would pass within :data:`SHARP_CLEARANCE_M` of the pipe
before its last corner turns the other way, or is drawn anew from the same stream (at most
:data:`SHARP_ATTEMPTS` times), so the pipe never crosses itself; over the 100 held-out pipes no two
straights that do not meet come closer than 1.67 m (the legs either side of a 150° hook).

Every pipe is a pure function of its seed: pipe ``k`` of stream ``S`` and family ``F`` comes from
``SeedSequence([SUITE_ROOT, S, F, k])``. Two streams exist: :data:`TRAIN_STREAM` for the
infinite training families (``easy``, ``medium``, ``hard``, ``mixed``) and :data:`HELDOUT_STREAM`
for the fixed held-out suites. A training pipe and a held-out pipe never share a seed, since their
entropy differs in the stream word; that is what makes the held-out suites unseen by
construction. A pipe is generated until it is at least ``min_length`` long; a longer request
extends the same pipe (the shorter pipe's straights and bends are a prefix of the longer one's).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from pipefollow.sim.pipeline import Pipeline, PipelineError

SUITE_ROOT = 2010_0009  # first entropy word of every suite seed
TRAIN_STREAM, HELDOUT_STREAM = 0, 1
ARC_STEP_DEG = 10.0  # largest turn of one piece of a discretized arc
MAX_HEADING_DEG = 100.0  # bends keep the heading within ± this of the start heading
MIN_LENGTH_M = 46.0  # default pipe length: 60 s at 0.6 m/s (cruise is 0.48 m/s) plus 10 m
CRUISE_MARGIN = 0.6  # m/s used to size pipes for long episodes (above the 0.48 m/s cruise speed)
SHARP_MAX_HEADING_DEG = 165.0  # the sharp level's heading bound: both sides of a hook of ≤ 150° stay in it
SHARP_CLEARANCE_M = 3.0  # the sharp level: a new straight keeps this far from the pipe before its last corner


class SuiteError(PipelineError):
    """An unknown suite or family name; the message names it and lists the choices."""


@dataclass(frozen=True)
class Level:
    """A difficulty level: the ranges its bends and straights are drawn from."""

    name: str
    turn_deg: tuple[float, float]
    straight_m: tuple[float, float]
    arc_share: float
    radius_m: tuple[float, float]
    max_heading_deg: float = MAX_HEADING_DEG  # bends keep the heading within ± this of the start's
    clearance_m: float = 0.0  # > 0: a bend turns the other way if its straight would pass this near the pipe


LEVELS = {
    "easy": Level("easy", (10.0, 30.0), (6.0, 12.0), 0.5, (3.0, 6.0)),
    "medium": Level("medium", (30.0, 60.0), (4.0, 8.0), 0.5, (2.0, 4.0)),
    "hard": Level("hard", (45.0, 90.0), (2.0, 4.0), 0.25, (1.0, 2.0)),
    "sharp": Level(
        "sharp", (90.0, 150.0), (3.0, 5.0), 0.0, (0.0, 0.0), SHARP_MAX_HEADING_DEG, SHARP_CLEARANCE_M
    ),
}
FAMILY_IDS = {"easy": 1, "medium": 2, "hard": 3, "mixed": 4, "sharp": 5}  # entropy word of each family
_LEVEL_ORDER = ("easy", "medium", "hard")


@dataclass(frozen=True)
class Suite:
    """A named set of pipes.

    Attributes:
        name: the suite's name.
        family: ``easy``, ``medium``, ``hard`` or ``mixed`` (each pipe a level in turn / at random).
        stream: :data:`TRAIN_STREAM` (an infinite family) or :data:`HELDOUT_STREAM` (fixed pipes).
        count: number of pipes; ``None`` for an infinite training family.
        description: one line for ``pipefollow suites``.
    """

    name: str
    family: str
    stream: int
    count: int | None
    description: str

    @property
    def is_training(self) -> bool:
        """True for an infinite training family."""
        return self.stream == TRAIN_STREAM

    def levels(self) -> tuple[str, ...]:
        """The difficulty levels its pipes come from."""
        return _LEVEL_ORDER if self.family == "mixed" else (self.family,)

    def pipe(self, k: int, min_length: float = MIN_LENGTH_M) -> Pipeline:
        """Pipe ``k`` (``0 ≤ k < count`` for a held-out suite, any ``k ≥ 0`` for a training family)."""
        if k < 0 or (self.count is not None and k >= self.count):
            raise IndexError(f"suite '{self.name}' has pipes 0 to {(self.count or 0) - 1}, not {k}")
        return suite_pipe(self.family, self.stream, k, min_length, name=f"{self.name}-{k:03d}")

    def pipes(self, n: int | None = None, min_length: float = MIN_LENGTH_M) -> list[Pipeline]:
        """The first ``n`` pipes (all of a held-out suite by default)."""
        if n is None:
            if self.count is None:
                raise ValueError(f"suite '{self.name}' is an infinite training family: give n")
            n = self.count
        return [self.pipe(k, min_length) for k in range(n)]

    def draw(self, rng: np.random.Generator, min_length: float = MIN_LENGTH_M) -> Pipeline:
        """A training pipe chosen by ``rng``: pipe ``k`` of the family with ``k`` drawn from ``rng``."""
        return self.pipe(draw_index(rng), min_length)

    def summary(self) -> dict:
        """Name, count and ranges, for listings."""
        levels = [LEVELS[n] for n in self.levels()]
        return {
            "name": self.name,
            "kind": "train" if self.is_training else "heldout",
            "count": self.count,
            "difficulty": self.family,
            "turn_deg": [min(lv.turn_deg[0] for lv in levels), max(lv.turn_deg[1] for lv in levels)],
            "straight_m": [min(lv.straight_m[0] for lv in levels), max(lv.straight_m[1] for lv in levels)],
            "arc_radius_m": [min(lv.radius_m[0] for lv in levels), max(lv.radius_m[1] for lv in levels)],
            "description": self.description,
        }


HELDOUT_COUNT = 100

SUITES = {
    s.name: s
    for s in (
        Suite("easy", "easy", TRAIN_STREAM, None, "training family: gentle bends, long straights"),
        Suite("medium", "medium", TRAIN_STREAM, None, "training family: bends up to 60°"),
        Suite("hard", "hard", TRAIN_STREAM, None, "training family: bends up to 90°, short straights"),
        Suite("mixed", "mixed", TRAIN_STREAM, None, "training family: each pipe easy, medium or hard"),
        Suite(
            "heldout",
            "mixed",
            HELDOUT_STREAM,
            HELDOUT_COUNT,
            "held-out test: pipes easy, medium, hard in turn",
        ),
        Suite("heldout-easy", "easy", HELDOUT_STREAM, HELDOUT_COUNT, "held-out test, easy pipes"),
        Suite("heldout-medium", "medium", HELDOUT_STREAM, HELDOUT_COUNT, "held-out test, medium pipes"),
        Suite("heldout-hard", "hard", HELDOUT_STREAM, HELDOUT_COUNT, "held-out test, hard pipes"),
        Suite(
            "heldout-sharp",
            "sharp",
            HELDOUT_STREAM,
            HELDOUT_COUNT,
            "held-out test: corners of 90–150°, short straights",
        ),
    )
}


def get_suite(name: str) -> Suite:
    """The suite called ``name``; raises :class:`SuiteError` listing the suites otherwise."""
    try:
        return SUITES[name]
    except (KeyError, TypeError):
        raise SuiteError(f"suite '{name}': unknown (choose from {', '.join(SUITES)})") from None


def draw_index(rng: np.random.Generator) -> int:
    """A pipe index of a training family, drawn from ``rng`` (uniform on [0, 2**62))."""
    return int(rng.integers(0, 2**62))


def seed_sequence(family: str, stream: int, k: int) -> np.random.SeedSequence:
    """The seed of pipe ``k`` of ``family`` in ``stream``: ``SeedSequence([SUITE_ROOT, stream, id, k])``."""
    return np.random.SeedSequence([SUITE_ROOT, stream, FAMILY_IDS[family], k])


def min_length_for(seconds: float) -> float:
    """Pipe length that an episode of ``seconds`` cannot run off (the suite default at least)."""
    return max(MIN_LENGTH_M, CRUISE_MARGIN * seconds + 10.0)


def _draws(rng: np.random.Generator, n: int) -> Iterator[tuple[float, ...]]:
    """Uniform numbers for straights and bends, in batches of ``n`` (so any prefix is reproducible)."""
    while True:
        batch = rng.random((n, 6))
        yield from (tuple(row) for row in batch)


def suite_pipe(
    family: str, stream: int, k: int, min_length: float = MIN_LENGTH_M, name: str = ""
) -> Pipeline:
    """Pipe ``k`` of ``family`` in ``stream`` (see the module docstring), at least ``min_length`` long."""
    rng = np.random.default_rng(seed_sequence(family, stream, k))
    if family == "mixed":
        level_name = _LEVEL_ORDER[k % 3] if stream == HELDOUT_STREAM else _LEVEL_ORDER[int(rng.integers(3))]
    else:
        level_name = family
    lv = LEVELS[level_name]
    x = y = heading = 0.0
    pts = [(0.0, 0.0)]
    length = 0.0
    max_heading = math.radians(lv.max_heading_deg)
    step = math.radians(ARC_STEP_DEG)
    draws = _draws(rng, 16)
    for u_len, u_turn, u_side, u_arc, u_rad, _ in draws:
        straight = lv.straight_m[0] + u_len * (lv.straight_m[1] - lv.straight_m[0])
        x, y = x + straight * math.cos(heading), y + straight * math.sin(heading)
        pts.append((x, y))
        length += straight
        if length >= min_length:
            break
        turn = _turn(lv, heading, u_turn, u_side, max_heading)
        if lv.clearance_m > 0.0:
            turn = _clear_turn(lv, pts, heading, turn, draws, max_heading)
        if u_arc < lv.arc_share:
            radius = lv.radius_m[0] + u_rad * (lv.radius_m[1] - lv.radius_m[0])
            pieces = max(1, math.ceil(abs(turn) / step - 1e-9))
            d = turn / pieces
            chord = 2.0 * radius * math.sin(0.5 * abs(d))
            for _ in range(pieces):  # chords of the arc, each at the mean heading of its piece
                heading += 0.5 * d
                x, y = x + chord * math.cos(heading), y + chord * math.sin(heading)
                heading += 0.5 * d
                pts.append((x, y))
                length += chord
        else:
            heading += turn
    return Pipeline(np.array(pts), name or f"{family}-{stream}-{k}")


def _turn(lv: Level, heading: float, u_turn: float, u_side: float, max_heading: float) -> float:
    """A bend's turn (rad) from its two uniforms.

    Its size in the level's range, its side at random unless that breaks the heading bound.
    """
    turn = math.radians(lv.turn_deg[0] + u_turn * (lv.turn_deg[1] - lv.turn_deg[0]))
    turn = turn if u_side < 0.5 else -turn
    if abs(heading + turn) > max_heading:
        turn = -turn
    return turn


SHARP_ATTEMPTS = 32  # bends drawn at most for one corner of the sharp level before the clearest is kept


def _clear_turn(lv: Level, pts: list, heading: float, turn: float, draws, max_heading: float) -> float:
    """A bend whose next straight (at its longest) keeps ``lv.clearance_m`` from the pipe laid so far.

    ``turn`` is tried first, then its other side, then new bends from ``draws`` (the same stream,
    so a longer pipe still extends a shorter one); after :data:`SHARP_ATTEMPTS` the clearest bend
    tried is kept.
    """
    best_turn, best_gap = turn, -1.0
    for attempt in range(SHARP_ATTEMPTS):
        if attempt > 0:
            _, u_turn, u_side, *_ = next(draws)
            turn = _turn(lv, heading, u_turn, u_side, max_heading)
        for t in (turn, -turn):
            if abs(heading + t) > max_heading + 1e-12:
                continue
            gap = _gap_ahead(pts, heading + t, lv.straight_m[1])
            if gap >= lv.clearance_m:
                return t
            if gap > best_gap:
                best_turn, best_gap = t, gap
    return best_turn


def _gap_ahead(pts: list, heading: float, reach: float) -> float:
    """The distance from a straight of ``reach`` (from the last point at ``heading``) to the pipe.

    The pipe before the last straight: that one meets the new straight at the corner by construction.
    """
    x, y = pts[-1]
    end = (x + reach * math.cos(heading), y + reach * math.sin(heading))
    return min((_segment_gap(pts[i], pts[i + 1], (x, y), end) for i in range(len(pts) - 2)), default=math.inf)


def _segment_gap(a, b, c, d):
    """The shortest distance between segments a–b and c–d (0 if they cross)."""

    def point_to(p, q, r):  # distance from p to segment q–r
        qx, qy, rx, ry = q[0], q[1], r[0], r[1]
        ex, ey = rx - qx, ry - qy
        n2 = ex * ex + ey * ey
        t = 0.0 if n2 == 0.0 else min(max(((p[0] - qx) * ex + (p[1] - qy) * ey) / n2, 0.0), 1.0)
        return math.hypot(p[0] - qx - t * ex, p[1] - qy - t * ey)

    def side(p, q, r):
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    if side(a, b, c) * side(a, b, d) < 0.0 and side(c, d, a) * side(c, d, b) < 0.0:
        return 0.0
    return min(point_to(a, c, d), point_to(b, c, d), point_to(c, a, b), point_to(d, a, b))


def export_suite(suite: Suite, folder, n: int | None = None, min_length: float = MIN_LENGTH_M) -> list:
    """Write pipes of ``suite`` as pipeline JSON files ``NAME-KKK.json`` into ``folder`` (atomically each)."""
    from pathlib import Path

    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for pipe in suite.pipes(n, min_length):
        path = out / f"{pipe.name}.json"
        pipe.save(path)
        paths.append(path)
    return paths
