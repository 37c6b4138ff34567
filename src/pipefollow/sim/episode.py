"""The episode protocol: what happens at each decision's end (docs/design.md, "updates while lost").

Every episode loop runs its decisions through these small compiled helpers: the Gymnasium
environment and its vector version, the learners' compiled loops, the environment path of
training and the benchmark's compiled episodes. So the lost-pipe bookkeeping, the per-episode
statistics and the episode's end cannot drift apart.

* The **book** of an episode is one float array with the named slots of :data:`BOOK_SLOTS`: the
  running totals (decisions, return, decisions ending in view, their Σ e_dist²) and the pending
  transition of the semi-Markov update;
* :func:`start_episode` draws what the environment's reset draws and places the AUV on its pipe;
  :func:`start` clears the book;
* :func:`decide` runs one decision and keeps its totals (:func:`tally`); the environments'
  :func:`decide_packed` counts it without its reward, which may come from the vision camera;
  :func:`end_of` says whether and why the episode ends: its decisions run out (a time limit,
  ``truncated``) or the AUV has reached the pipe's far end (:func:`reached_end`, a terminal state,
  ``terminated``; not under the paper's reading ``pipe_end=continue``);
* :func:`carry` keeps the pending transition: a decision taken with the pipe in view starts one
  (its reward, bootstrap factor γ_d); while the pipe is lost the rewards add up discounted;
  :func:`due` says when the one semi-Markov update is made (pipe back in view, or the last decision),
  :func:`bootstrap` with which factor (none from the pipe's end, which is terminal);
* :func:`close_episode` writes a row of the statistics, whose columns are :data:`STAT_NAMES`.

The compiled loops take grouped arguments: :class:`Tracks` (the pipes) and :class:`Run` (how the
episodes run), each a ``NamedTuple`` that numba passes as one argument.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.sim import decision as sim

# The per-episode statistics: one row an episode, its columns these, in this order. Training runs
# return (and write) the leading columns up to the time lost, :data:`TRAINING_STAT_NAMES`.
STAT_NAMES = (
    "return", "pipe_in_view", "progress_m", "time_lost_s", "sum_e_dist2", "n_in_view", "swum_m", "back_m",
)  # fmt: skip
STAT_COLUMN = {name: i for i, name in enumerate(STAT_NAMES)}
STAT_RETURN = STAT_COLUMN["return"]  # accumulated reward
STAT_IN_VIEW = STAT_COLUMN["pipe_in_view"]  # share of decisions that ended with the pipe in view
STAT_PROGRESS = STAT_COLUMN["progress_m"]  # arc length reached along the pipe (m)
STAT_TIME_LOST = STAT_COLUMN["time_lost_s"]  # time with the pipe out of view at decision ends (s)
STAT_SUM_E2 = STAT_COLUMN["sum_e_dist2"]  # Σ e_dist² over the decisions that ended in view (m²)
STAT_N_SEEN = STAT_COLUMN["n_in_view"]  # the number of those decisions
STAT_SWUM = STAT_COLUMN["swum_m"]  # distance covered over ground, decision end to decision end (m)
STAT_BACK = STAT_COLUMN["back_m"]  # progress lost in decisions that ended in view: following backwards (m)
TRAINING_STAT_NAMES = STAT_NAMES[: STAT_TIME_LOST + 1]

# The slots of an episode's book: its running totals, then the pending transition of :func:`carry`.
BOOK_SLOTS = ("decisions", "return", "seen", "sum_e2", "pending", "acc", "disc", "swum", "back")
BOOK_SLOT = {name: i for i, name in enumerate(BOOK_SLOTS)}
DECISIONS = BOOK_SLOT["decisions"]  # decisions made
TOTAL = BOOK_SLOT["return"]  # Σ r
SEEN = BOOK_SLOT["seen"]  # decisions that ended with the pipe in view
E2 = BOOK_SLOT["sum_e2"]  # Σ e_dist² over those
PENDING = BOOK_SLOT["pending"]  # 1 while a transition waits for its update
ACC = BOOK_SLOT["acc"]  # its discounted reward Σ γ^j r_j
DISC = BOOK_SLOT["disc"]  # its bootstrap factor γ^n
SWUM = BOOK_SLOT["swum"]  # Σ of the straight distances between the poses at decision ends (m)
BACK = BOOK_SLOT["back"]  # Σ of the progress lost in decisions that ended with the pipe in view (m)
BOOK_SIZE = len(BOOK_SLOTS)

# How an episode ends (:func:`end_of`): it goes on, its decisions ran out (a time limit: Gymnasium's
# ``truncated``), or the AUV reached the pipe's far end (a terminal state: ``terminated``).
GOES_ON, TIME_LIMIT, PIPE_END = 0, 1, 2
# The far end is reached when the progress along the pipe is within this distance of the pipe's
# length (m): a decision's travel at cruise speed (0.476 m/s), so that the decision that reaches it
# ends with the pipe's end still ahead in the camera's footprint (which starts at the AUV's centre),
# not with the pipe lost behind the AUV (−10).
END_MARGIN_M = 0.5


class Tracks(NamedTuple):
    """The pipes of a run, concatenated: pipe ``i`` is ``points[offsets[i]:offsets[i + 1]]``.

    Episode ``e`` runs on pipe ``e % n_pipes``: one pipe for all, or one pipe per episode.
    """

    points: np.ndarray  # (n, 2) polyline points of all pipes (m)
    cum: np.ndarray  # (n,) arc length at each point (m)
    offsets: np.ndarray  # (pipes + 1,) int64
    starts: np.ndarray  # (pipes, 3) start pose (x, y, ψ) of each pipe


class Run(NamedTuple):
    """How the episodes of one compiled call run."""

    sim: np.ndarray  # packed SimParams (pipefollow.sim.decision.pack_params)
    sigmas: np.ndarray  # (episodes,) exploration σ per episode
    n_decisions: int  # decisions per episode
    learn: bool  # update the learner (training) or not (evaluation)


def tracks_of(pipes) -> Tracks:
    """The pipes (:class:`~pipefollow.sim.pipeline.Pipeline`) of a run as one :class:`Tracks`."""
    offsets = np.zeros(len(pipes) + 1, dtype=np.int64)
    offsets[1:] = np.cumsum([len(p.points) for p in pipes])
    points = np.ascontiguousarray(np.concatenate([p.points for p in pipes]))
    cum = np.ascontiguousarray(np.concatenate([p.cumulative for p in pipes]))
    starts = np.array([[p.points[0, 0], p.points[0, 1], p.start_heading] for p in pipes])
    # Read-only like a Pipeline's own arrays, which the environment hands to the simulator: numba
    # types the two alike, so the simulator's functions are compiled once, not once for each.
    points.setflags(write=False)
    cum.setflags(write=False)
    return Tracks(points, cum, offsets, starts)


def no_poses() -> np.ndarray:
    """The ``poses`` argument of a loop that records none."""
    return np.zeros((0, 1, 3))


def new_book(n: int | None = None) -> np.ndarray:
    """A cleared book (:data:`BOOK_SLOTS`), or ``n`` of them as rows of one array."""
    return np.zeros(BOOK_SIZE if n is None else (n, BOOK_SIZE))


@njit(cache=True)
def pipe_of(tracks, e):
    """Points and arc lengths of episode ``e``'s pipe, and its start pose."""
    k = e % tracks.starts.shape[0]
    a, b = tracks.offsets[k], tracks.offsets[k + 1]
    return tracks.points[a:b], tracks.cum[a:b], tracks.starts[k]


@njit(cache=True)
def start(book, poses, e, s):
    """A new episode's book, and its start pose into ``poses[e, 0]`` (if poses are recorded)."""
    book[:] = 0.0
    record_pose(poses, e, 0, s)


@njit(cache=True)
def start_episode(s, points, cum, start_pose, ps, env_rng, dz, book, poses, e):
    """Reset: the first camera reading's normals from ``env_rng``, the AUV on its start pose."""
    sim.draw_normals(env_rng, dz)
    sim.init_state(s, points, cum, start_pose[0], start_pose[1], start_pose[2], ps, dz)
    start(book, poses, e, s)


@njit(cache=True)
def record_pose(poses, e, t, s):
    """Pose (x, y, ψ) after decision ``t`` into ``poses[e, t]``, if poses are recorded."""
    if poses.shape[0] > 0:
        poses[e, t, 0], poses[e, t, 1], poses[e, t, 2] = s[sim.X], s[sim.Y], s[sim.PSI]


@njit(cache=True)
def hold_poses(poses, e, book):
    """The last pose of episode ``e`` in the rows of ``poses[e]`` after its last decision, if any are left.

    An episode that ended at the pipe's end made fewer decisions than the rows hold: the AUV stays
    where its inspection ended, so a recorded track keeps its shape and no row holds zeros.
    """
    if poses.shape[0] > 0:
        last = int(book[DECISIONS])
        for t in range(last + 1, poses.shape[1]):
            poses[e, t, :] = poses[e, last, :]


@njit(cache=True)
def count(book, in_view, e_dist):
    """Count a decision, and whether it ended with the pipe ``in_view`` (with its ``e_dist``²)."""
    book[DECISIONS] += 1.0
    if in_view:
        book[SEEN] += 1.0
        book[E2] += e_dist * e_dist


@njit(cache=True)
def travel(book, s, x0, y0, progress0):
    """Add a decision's move from ``(x0, y0)`` at ``progress0`` to the state ``s`` after it to the book.

    ``swum``: the straight distance between the two poses; ``back``: the progress (the state's
    ``PROGRESS``, the arc length of the AUV's place on the pipe) lost, if the decision ended with
    the pipe in view: a vehicle that follows the pipe backwards.
    """
    book[SWUM] += math.hypot(s[sim.X] - x0, s[sim.Y] - y0)
    if s[sim.IN_VIEW] != 0.0 and s[sim.PROGRESS] < progress0:
        book[BACK] += progress0 - s[sim.PROGRESS]


@njit(cache=True)
def tally(book, r, in_view, e_dist):
    """Add a decision's reward ``r`` to the book, and :func:`count` it."""
    book[TOTAL] += r
    count(book, in_view, e_dist)


@njit(cache=True)
def decide(s, a, points, cum, ps, z, book, poses, e):
    """One decision with action ``a`` and the disturbances' normals ``z``, tallied. Returns r."""
    x0, y0, progress0 = s[sim.X], s[sim.Y], s[sim.PROGRESS]
    r = sim.decide(s, a, points, cum, ps, z)
    tally(book, r, s[sim.IN_VIEW] != 0.0, s[sim.E_DIST])
    travel(book, s, x0, y0, progress0)
    record_pose(poses, e, int(book[DECISIONS]), s)
    return r


@njit(cache=True)
def draw_and_decide(s, a, points, cum, ps, env_rng, dz, book, poses, e):
    """:func:`decide`, its normals first drawn from ``env_rng`` into ``dz`` as the environment draws them."""
    sim.draw_normals(env_rng, dz)
    return decide(s, a, points, cum, ps, dz, book, poses, e)


@njit(cache=True)
def decide_packed(s, a, points, cum, packed, z, book, n_decisions):
    """The environments' decision (packed parameters), counted; returns its reward and :func:`end_of`.

    The reward is not added to the book: an environment sums the rewards it returns itself (the
    vision camera's when it has one), in Python, where a float costs less than an array's entry.
    What the book counts in view is the simulation's exact camera, before any detection.
    """
    ps = sim.unpack_params(packed)
    x0, y0, progress0 = s[sim.X], s[sim.Y], s[sim.PROGRESS]
    r = sim.decide(s, a, points, cum, ps, z)
    count(book, s[sim.IN_VIEW] != 0.0, s[sim.E_DIST])
    travel(book, s, x0, y0, progress0)
    return r, end_of(book, s, cum, ps, n_decisions)


@njit(cache=True)
def reached_end(progress_m, length_m):
    """Whether an AUV at ``progress_m`` along a pipe ``length_m`` long has reached its far end.

    Reached: the progress (the farthest arc length reached) is within :data:`END_MARGIN_M` of the
    length. The AUV starts on the pipe's first point, so a pipe shorter than the margin ends at
    its first decision.
    """
    return progress_m >= length_m - END_MARGIN_M


@njit(cache=True)
def end_of(book, s, cum, ps, n_decisions):
    """How the episode stands after a decision: :data:`GOES_ON`, :data:`TIME_LIMIT` or :data:`PIPE_END`.

    :data:`PIPE_END` when the AUV has reached the pipe's far end (:func:`reached_end`) and ``ps``
    ends episodes there (``end_at_pipe_end``, the reading ``pipe_end=end``); this comes first when
    the same decision also makes the ``n_decisions``-th, the time limit.
    """
    if ps.end_at_pipe_end and reached_end(s[sim.PROGRESS_MAX], cum[cum.shape[0] - 1]):
        return PIPE_END
    if book[DECISIONS] >= n_decisions:
        return TIME_LIMIT
    return GOES_ON


@njit(cache=True)
def carry(book, visible, r, discount):
    """The lost-pipe bookkeeping after a decision taken from a state with (``visible``) or without the pipe.

    In view, the decision starts a pending transition with reward ``r`` and bootstrap factor
    γ_d; while lost, ``r`` adds to the pending one with the next power of γ_d.
    """
    if visible:
        book[PENDING], book[ACC], book[DISC] = 1.0, r, discount
    elif book[PENDING] != 0.0:
        book[ACC] += book[DISC] * r
        book[DISC] *= discount


@njit(cache=True)
def due(book, now_visible, last):
    """Whether the pending transition's update is made now: the pipe is back, or the episode ends."""
    return book[PENDING] != 0.0 and (now_visible or last)


@njit(cache=True)
def bootstrap(book, end):
    """The pending transition's bootstrap factor after a decision that left the episode at ``end``.

    γ^n (the book's) while the episode goes on or at its time limit, which is no state of the task;
    0 at the pipe's end, a terminal state: nothing follows it.
    """
    return 0.0 if end == PIPE_END else book[DISC]


@njit(cache=True)
def close_episode(stats, e, book, progress_m, decision_s):
    """Row ``e`` of the statistics (:data:`STAT_NAMES`, or their leading columns) from the book.

    ``progress_m`` is the arc length the episode reached (the state's ``PROGRESS_MAX``). The rates
    are over the decisions made: fewer than the episode's if it ended at the pipe's end.
    """
    n = book[DECISIONS]
    stats[e, STAT_RETURN] = book[TOTAL]
    stats[e, STAT_IN_VIEW] = book[SEEN] / n
    stats[e, STAT_PROGRESS] = progress_m
    stats[e, STAT_TIME_LOST] = (n - book[SEEN]) * decision_s
    if stats.shape[1] > STAT_SUM_E2:
        stats[e, STAT_SUM_E2] = book[E2]
        stats[e, STAT_N_SEEN] = book[SEEN]
    if stats.shape[1] > STAT_SWUM:
        stats[e, STAT_SWUM] = book[SWUM]
        stats[e, STAT_BACK] = book[BACK]


def statistics_row(book: np.ndarray, progress_m: float, decision_s: float) -> np.ndarray:
    """:func:`close_episode` from Python: the statistics of one episode (:data:`STAT_NAMES`)."""
    row = np.empty((1, len(STAT_NAMES)))
    close_episode(row, 0, book, float(progress_m), float(decision_s))
    return row[0]
