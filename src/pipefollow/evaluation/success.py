"""When an episode is a success as a pipeline inspector counts it: the pipe kept in view, followed forward.

The functions take statistics rows (columns :data:`pipefollow.sim.episode.STAT_NAMES`, one row an
episode, or one row alone) and the lengths of the episodes' pipes (m). The AUV starts on the pipe's
first point, so its progress (the farthest arc length reached) is the length of pipe it inspected.

* **reached the end**: the progress within :data:`~pipefollow.sim.episode.END_MARGIN_M` (0.5 m)
  of the pipe's length (:func:`pipefollow.sim.episode.reached_end`, where the episode ends);
* **reachable**: the distance the AUV covered over ground (``swum_m``, the straight lines between
  its poses at decision ends), capped by the pipe's length: the progress it would have made had
  every metre gone along the pipe;
* **progress share**: progress / reachable (1 with the end reached, or nothing covered);
* **turned back**: the progress lost in decisions that ended with the pipe in view (``back_m``)
  ≥ :data:`TURNED_BACK_M`: the AUV followed the pipe backwards for as far as its camera's
  footprint is long. Such an episode can keep the pipe in view all along;
* **followed forward**: the end reached or a progress share ≥ :data:`SUCCESS_PROGRESS`, and not
  turned back;
* **success**: the pipe in view at ≥ :data:`SUCCESS_IN_VIEW` of the decisions and followed forward.

Why half: every metre an AUV follows the pipe backwards, or circles over it, counts in the reachable
distance and not in the progress, so such an episode scores low (one that goes back as far as it came
scores ½ at best: hence the turned-back test beside it). A controller that follows the
pipe forward loses some of its travel in bends (it swings wide of a corner and comes back): on the
held-out suites (60 s) the heuristic's share is ≥ 0.66 on every pipe, line-of-sight guidance's ≥ 0.55
(docs/decisions.md). A threshold of 0.9 would judge how tightly a controller takes its bends, which
the return measures already, and fail the heuristic on two thirds of the medium pipes.
"""

from __future__ import annotations

import numpy as np

from pipefollow.sim import episode as ep
from pipefollow.sim.camera import PAPER_CAMERA

SUCCESS_IN_VIEW = 0.95  # share of decisions that must end with the pipe in view
SUCCESS_PROGRESS = 0.5  # share of the reachable distance that must be progress along the pipe
TURNED_BACK_M = PAPER_CAMERA.depth  # progress lost in view (m) that makes a turned-back episode: 3 m


def _rows(stats) -> np.ndarray:
    return np.atleast_2d(np.asarray(stats, dtype=np.float64))


def _lengths(lengths, n: int) -> np.ndarray:
    return np.broadcast_to(np.asarray(lengths, dtype=np.float64), (n,))


def reached_end(stats, lengths) -> np.ndarray:
    """Per episode: whether the AUV reached its pipe's far end."""
    rows = _rows(stats)
    # the episodes' own rule, applied to arrays (its Python form: the same comparison)
    return ep.reached_end.py_func(rows[:, ep.STAT_PROGRESS], _lengths(lengths, len(rows)))


def reachable_m(stats, lengths) -> np.ndarray:
    """Per episode: the distance covered over ground, capped by the pipe's length (m)."""
    rows = _rows(stats)
    return np.minimum(rows[:, ep.STAT_SWUM], _lengths(lengths, len(rows)))


def progress_share(stats, lengths) -> np.ndarray:
    """Per episode: progress / reachable distance; 1 with the end reached or nothing covered."""
    rows = _rows(stats)
    reach = reachable_m(rows, lengths)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(reach > 0.0, rows[:, ep.STAT_PROGRESS] / np.where(reach > 0.0, reach, 1.0), 1.0)
    return np.where(reached_end(rows, lengths), 1.0, share)


def followed_forward(stats, lengths) -> np.ndarray:
    """Per episode: the end reached or a progress share ≥ :data:`SUCCESS_PROGRESS`, and not turned back."""
    return (progress_share(stats, lengths) >= SUCCESS_PROGRESS) & ~turned_back(stats)


def turned_back(stats) -> np.ndarray:
    """Per episode: the pipe followed backwards for at least :data:`TURNED_BACK_M` (in view)."""
    return _rows(stats)[:, ep.STAT_BACK] >= TURNED_BACK_M


def in_view(stats) -> np.ndarray:
    """Per episode: the pipe in view at ≥ :data:`SUCCESS_IN_VIEW` of the decisions (success, until now)."""
    return _rows(stats)[:, ep.STAT_IN_VIEW] >= SUCCESS_IN_VIEW


def success(stats, lengths) -> np.ndarray:
    """Per episode: the pipe in view at ≥ 95 % of the decisions and followed forward."""
    return in_view(stats) & followed_forward(stats, lengths)


def summary(stats, lengths) -> dict:
    """The rates over episodes: ``success_rate``, ``in_view_rate``, ``mean_progress_share``, ``turned_back``.

    ``in_view_rate`` is the share of episodes with the pipe in view at ≥ 95 % of the decisions
    (what success meant before it asked for the pipe followed forward); ``turned_back`` a count.
    """
    rows = _rows(stats)
    return {
        "success_rate": float(np.mean(success(rows, lengths))),
        "in_view_rate": float(np.mean(in_view(rows))),
        "mean_progress_share": float(np.mean(progress_share(rows, lengths))),
        "reached_end": int(np.sum(reached_end(rows, lengths))),
        "turned_back": int(np.sum(turned_back(rows))),
    }


def episode_fields(row, length: float) -> dict:
    """One episode's judgement: ``progress_share``, ``reached_end``, ``turned_back``, ``success``."""
    return {
        "progress_share": float(progress_share(row, length)[0]),
        "reached_end": bool(reached_end(row, length)[0]),
        "turned_back": bool(turned_back(row)[0]),
        "success": bool(success(row, length)[0]),
    }


def summary_of_runs(runs, lengths) -> dict:
    """:func:`summary` over several runs (statistics arrays, one row per pipe each) on the same pipes."""
    rows = np.concatenate([_rows(r) for r in runs])
    return summary(rows, np.tile(np.asarray(lengths, dtype=np.float64), len(runs)))
