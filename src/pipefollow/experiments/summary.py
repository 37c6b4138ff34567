"""Per-repeat statistics of a run folder's tables and the convergence rule.

Statistics use plain NumPy: spreads are sample standard deviations over repeats (ddof = 1) and
differences between two set-ups carry Welch's standard error ``sqrt(s_a²/n_a + s_b²/n_b)``.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipefollow.experiments.schema import TrialConfig
from pipefollow.readings import DEFAULT

# "Converged to a pipe-tracking policy" (docs/design.md, claims 1-3), measured on a repeat's phase.
# The thresholds are readings (converge_in_view, converge_progress_m); these are the defaults.
CONVERGE_EPISODES = 50  # judged over the last 50 training episodes of the phase
CONVERGE_MIN_IN_VIEW = DEFAULT.converge_in_view  # mean fraction of decisions ending with the pipe in view
CONVERGE_MIN_PROGRESS_M = DEFAULT.converge_progress_m  # mean arc length reached (m): past the first turn
CONVERGE_PIPELINE = "paper-left"  # the pipeline whose turns the text cites
EARLY_EPISODES = 100  # "early, high-exploration episodes" (claim 2): the first 100 of a phase

Rows = list[dict[str, str]]

# ---------------------------------------------------------------------------------------------
# Statistics


def mean_sd(values: Sequence[float]) -> tuple[float, float]:
    """Mean and sample standard deviation (ddof = 1; NaN for fewer than two values)."""
    v = np.asarray(values, dtype=np.float64)
    if v.size == 0:
        return math.nan, math.nan
    return float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else math.nan


def welch(a: Sequence[float], b: Sequence[float]) -> tuple[float, float]:
    """Difference of means ``mean(a) - mean(b)`` and its Welch standard error (NaN below two each)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    diff = float(a.mean() - b.mean()) if a.size and b.size else math.nan
    if a.size < 2 or b.size < 2:
        return diff, math.nan
    return diff, float(math.sqrt(a.var(ddof=1) / a.size + b.var(ddof=1) / b.size))


# ---------------------------------------------------------------------------------------------
# Per-repeat statistics and the convergence rule


@dataclass(frozen=True)
class RepeatStats:
    """One repeat (seed) of one training phase.

    Attributes:
        seed: the repeat's seed.
        episodes: episodes of the phase.
        last_return: mean return over the last ``CONVERGE_EPISODES`` episodes.
        first_return: mean return over the first ``EARLY_EPISODES`` episodes.
        last_in_view: mean pipe-in-view fraction over the last ``CONVERGE_EPISODES`` episodes.
        last_progress_m: mean progress (m) over the last ``CONVERGE_EPISODES`` episodes.
        min_in_view: the convergence rule's threshold on ``last_in_view``.
        min_progress_m: its threshold on ``last_progress_m`` (m).
    """

    seed: int
    episodes: int
    last_return: float
    first_return: float
    last_in_view: float
    last_progress_m: float
    min_in_view: float = CONVERGE_MIN_IN_VIEW
    min_progress_m: float = CONVERGE_MIN_PROGRESS_M

    @property
    def converged(self) -> bool:
        """The convergence rule: enough of the pipe in view and far enough along it."""
        return is_converged(self.last_in_view, self.last_progress_m, self.min_in_view, self.min_progress_m)


def is_converged(
    last_in_view: float,
    last_progress_m: float,
    min_in_view: float = CONVERGE_MIN_IN_VIEW,
    min_progress_m: float = CONVERGE_MIN_PROGRESS_M,
) -> bool:
    """Whether last-window means of pipe-in-view fraction and progress meet the thresholds."""
    return bool(last_in_view >= min_in_view and last_progress_m >= min_progress_m)


def repeat_stats(
    seed: int,
    returns,
    in_view,
    progress_m,
    min_in_view: float = CONVERGE_MIN_IN_VIEW,
    min_progress_m: float = CONVERGE_MIN_PROGRESS_M,
) -> RepeatStats:
    """Statistics of one repeat's phase from its per-episode series (in episode order).

    Windows longer than the phase use all of its episodes; the thresholds are the convergence
    rule's (readings ``converge_in_view`` and ``converge_progress_m``).
    """
    returns, in_view, progress_m = (np.asarray(v, dtype=np.float64) for v in (returns, in_view, progress_m))
    last = slice(-CONVERGE_EPISODES, None)
    return RepeatStats(
        seed=seed,
        episodes=len(returns),
        last_return=float(returns[last].mean()),
        first_return=float(returns[:EARLY_EPISODES].mean()),
        last_in_view=float(in_view[last].mean()),
        last_progress_m=float(progress_m[last].mean()),
        min_in_view=min_in_view,
        min_progress_m=min_progress_m,
    )


@dataclass(frozen=True)
class PhaseSummary:
    """All repeats of one training phase of one trial.

    Attributes:
        trial: the trial's name.
        label: its label.
        phase: position of the phase in the trial (0 = first).
        pipeline: the phase's training pipeline.
        repeats: per-repeat statistics, in seed order.
    """

    trial: str
    label: str
    phase: int
    pipeline: str
    repeats: tuple[RepeatStats, ...]

    @property
    def n(self) -> int:
        """Number of repeats."""
        return len(self.repeats)

    @property
    def n_converged(self) -> int:
        """Number of converged repeats."""
        return sum(r.converged for r in self.repeats)

    @property
    def episodes(self) -> int:
        """Episodes of the phase (the shortest repeat's)."""
        return min((r.episodes for r in self.repeats), default=0)

    def values(self, name: str) -> np.ndarray:
        """One statistic (a :class:`RepeatStats` attribute) of every repeat."""
        return np.array([getattr(r, name) for r in self.repeats], dtype=np.float64)


# ---------------------------------------------------------------------------------------------
# Reading the tables


def read_rows(path: str | Path) -> Rows:
    """The rows of a CSV file as dictionaries of strings; an absent file gives no rows."""
    path = Path(path)
    if not path.exists():
        return []
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


@dataclass(frozen=True)
class PhaseSeries:
    """One repeat's episodes of one training phase, in episode order."""

    pipeline: str
    returns: np.ndarray
    in_view: np.ndarray
    progress_m: np.ndarray


# trial → seed (in repeat order) → the repeat's phases in order
Training = Mapping[str, Mapping[int, list[PhaseSeries]]]


def training_series(rows: Iterable[Mapping[str, str]]) -> dict[str, dict[int, list[PhaseSeries]]]:
    """``results.csv`` rows grouped by trial, seed and phase, as arrays in episode order.

    One pass over the rows, keeping only the columns the report uses: a run of a thousand
    trials reads in a fraction of the memory its rows would take as dictionaries.
    """
    acc: dict[str, dict[int, tuple[int, list]]] = {}
    for r in rows:
        by_seed = acc.setdefault(r["trial"], {})
        seed = int(r["seed"])
        if seed not in by_seed:
            by_seed[seed] = (int(r["repeat"]), [])
        by_seed[seed][1].append(
            (
                int(r["episode"]),
                r["phase"],
                r["pipeline"],
                float(r["return"]),
                float(r["pipe_in_view"]),
                float(r["progress_m"]),
            )
        )
    out: dict[str, dict[int, list[PhaseSeries]]] = {}
    for trial, by_seed in acc.items():
        out[trial] = {}
        for seed in sorted(by_seed, key=lambda sd: (by_seed[sd][0], sd)):
            episodes = sorted(by_seed[seed][1], key=lambda e: e[0])
            phases: dict[str, list] = {}
            for e in episodes:
                phases.setdefault(e[1], []).append(e)
            out[trial][seed] = [
                PhaseSeries(
                    g[0][2],
                    np.array([e[3] for e in g], dtype=np.float64),
                    np.array([e[4] for e in g], dtype=np.float64),
                    np.array([e[5] for e in g], dtype=np.float64),
                )
                for g in phases.values()
            ]
    return out


def read_training(path: str | Path) -> dict[str, dict[int, list[PhaseSeries]]]:
    """:func:`training_series` of a ``results.csv`` file, streamed; an absent file gives none."""
    path = Path(path)
    if not path.exists():
        return {}
    with path.open(newline="") as f:
        return training_series(csv.DictReader(f))


def as_training(results: Rows | Training) -> Training:
    """``results`` grouped by :func:`training_series` unless it already is."""
    return results if isinstance(results, Mapping) else training_series(results)


def summarize_trial(results: Rows | Training, trial: TrialConfig) -> list[PhaseSummary]:
    """Per-phase summaries of one trial from ``results.csv`` rows or their series (none if no rows)."""
    per_phase: dict[int, list[RepeatStats]] = {}
    pipelines: dict[int, str] = {}
    r = trial.reading
    for seed, phases in as_training(results).get(trial.name, {}).items():
        for k, ph in enumerate(phases):
            series = (ph.returns, ph.in_view, ph.progress_m)
            stats = repeat_stats(seed, *series, r.converge_in_view, r.converge_progress_m)
            per_phase.setdefault(k, []).append(stats)
            pipelines[k] = ph.pipeline
    title = trial.title
    return [PhaseSummary(trial.name, title, k, pipelines[k], tuple(per_phase[k])) for k in sorted(per_phase)]


def learning_curves(results: Rows | Training, trial: str) -> np.ndarray:
    """(repeats, episodes) return per training episode of a trial (cut to the shortest repeat)."""
    series = [np.concatenate([p.returns for p in ph]) for ph in as_training(results).get(trial, {}).values()]
    if not series:
        return np.zeros((0, 0))
    n = min(len(s) for s in series)
    return np.array([s[:n] for s in series])


@dataclass(frozen=True)
class Evaluation:
    """The deterministic evaluation episodes of one trial.

    Attributes:
        trial: the trial's name.
        pipeline: the evaluation pipeline.
        returns: controller (learned, actor, heuristic) → seed → accumulated reward.
    """

    trial: str
    pipeline: str
    returns: Mapping[str, Mapping[int, float]]

    def of(self, controller: str) -> np.ndarray:
        """Returns of one controller in seed order (empty if not evaluated)."""
        by_seed = self.returns.get(controller, {})
        return np.array([by_seed[s] for s in sorted(by_seed)], dtype=np.float64)


def read_evaluations(rows: Rows) -> dict[str, Evaluation]:
    """Trial name → :class:`Evaluation` from ``evaluation.csv`` rows."""
    returns: dict[str, dict[str, dict[int, float]]] = {}
    pipelines: dict[str, str] = {}
    for r in rows:
        by_seed = returns.setdefault(r["trial"], {}).setdefault(r["controller"], {})
        by_seed[int(r["seed"])] = float(r["return"])
        pipelines[r["trial"]] = r["pipeline"]
    return {t: Evaluation(t, pipelines[t], returns[t]) for t in returns}
