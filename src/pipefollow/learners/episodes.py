"""The episode protocol shared by every compiled episode loop (docs/design.md, "updates while lost").

Every learner's compiled loop (:mod:`~pipefollow.learners.cacla`, :mod:`~pipefollow.learners.sarsa`,
:mod:`~pipefollow.learners.actor_critic`) runs its episodes through these small compiled helpers, so
the lost-pipe bookkeeping and the per-episode statistics are written once:

* :func:`start_episode` draws what the environment's reset draws and places the AUV on its pipe;
* :func:`carry` keeps the pending transition: a decision taken with the pipe in view starts one
  (its reward, bootstrap factor γ_d); while the pipe is lost the rewards add up discounted;
  :func:`due` says when the one semi-Markov update is made (pipe back in view, or the last decision);
* :func:`tally` and :func:`close_episode` keep the statistics of :data:`STAT_NAMES`.

The loops take grouped arguments: :class:`Tracks` (the pipes), :class:`Run` (how the episodes run)
and :class:`Features` (the packed RBF grid of the state), each a ``NamedTuple`` that numba passes
as one argument.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.sim import decision as sim

# Columns of the per-episode statistics: training reports the first four.
STAT_NAMES = ("return", "pipe_in_view", "progress_m", "time_lost_s", "sum_e_dist2", "n_in_view")
RETURN, IN_VIEW, PROGRESS, TIME_LOST, SUM_E2, N_SEEN = range(len(STAT_NAMES))
TRAINING_STATS = 4  # the columns a training run returns

# Slots of the pending-transition record of :func:`carry`.
PENDING, ACC, DISC = 0, 1, 2
BOOK_SIZE = 3
# Slots of the running totals of :func:`tally`.
TOTAL, SEEN, E2 = 0, 1, 2
TALLY_SIZE = 3


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


class Features(NamedTuple):
    """A packed RBF grid (:attr:`~pipefollow.learners.rbf.RBFGrid.packed`) and its form."""

    centres: np.ndarray
    offsets: np.ndarray
    widths: np.ndarray
    normalized: bool


def features_of(grid) -> Features:
    """The grouped argument of an :class:`~pipefollow.learners.rbf.RBFGrid`."""
    centres, offsets, widths = grid.packed
    return Features(centres, offsets, widths, grid.form == "normalized")


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


@njit(cache=True)
def pipe_of(tracks, e):
    """Points and arc lengths of episode ``e``'s pipe, and its start pose."""
    k = e % tracks.starts.shape[0]
    a, b = tracks.offsets[k], tracks.offsets[k + 1]
    return tracks.points[a:b], tracks.cum[a:b], tracks.starts[k]


@njit(cache=True)
def start_episode(s, points, cum, start, ps, env_rng, dz, book, totals, poses, e):
    """Reset: the first camera reading's normals from ``env_rng``, the AUV on its start pose."""
    sim.draw_normals(env_rng, dz)
    sim.init_state(s, points, cum, start[0], start[1], start[2], ps, dz)
    book[:] = 0.0
    totals[:] = 0.0
    record_pose(poses, e, 0, s)


@njit(cache=True)
def record_pose(poses, e, t, s):
    """Pose (x, y, ψ) after decision ``t`` into ``poses[e, t]``, if poses are recorded."""
    if poses.shape[0] > 0:
        poses[e, t, 0], poses[e, t, 1], poses[e, t, 2] = s[sim.X], s[sim.Y], s[sim.PSI]


@njit(cache=True)
def decide(s, a, points, cum, ps, env_rng, dz, totals, poses, e, t):
    """One decision with action ``a``: its disturbance normals, the step, the tallies. Returns r."""
    sim.draw_normals(env_rng, dz)
    r = sim.decide(s, a, points, cum, ps, dz)
    tally(totals, s, r)
    record_pose(poses, e, t + 1, s)
    return r


@njit(cache=True)
def tally(totals, s, r):
    """Add a decision's reward, and whether it ended with the pipe in view (its e_dist²), to the totals."""
    totals[TOTAL] += r
    if s[sim.IN_VIEW] != 0.0:
        totals[SEEN] += 1.0
        totals[E2] += s[sim.E_DIST] * s[sim.E_DIST]


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
def close_episode(stats, e, s, totals, n_decisions, decision_s):
    """Row ``e`` of the statistics (:data:`STAT_NAMES`) from the episode's totals and final state."""
    stats[e, RETURN] = totals[TOTAL]
    stats[e, IN_VIEW] = totals[SEEN] / n_decisions
    stats[e, PROGRESS] = s[sim.PROGRESS_MAX]
    stats[e, TIME_LOST] = (n_decisions - totals[SEEN]) * decision_s
    if stats.shape[1] > SUM_E2:
        stats[e, SUM_E2] = totals[E2]
        stats[e, N_SEEN] = totals[SEEN]
