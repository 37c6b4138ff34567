"""The reproduction report: figures and ``REPORT.md`` computed from a run folder's stored results.

:func:`write_outputs` reads a run folder (``config.json``, ``results.csv``, ``evaluation.csv`` and,
for the trajectories and run time, ``trials/``), computes a :class:`Findings` record with pure
functions (:func:`compute_findings`), renders it as markdown (:func:`render_markdown`) and draws
the paper's Figs. 5–7 and the validation trajectories. Every number in the report comes from the
stored results; the only numbers written here are the paper's own (for comparison) and the
thresholds of the convergence rule, stated in the report from the constants below.

Statistics use plain NumPy: spreads are sample standard deviations over repeats (ddof = 1) and
differences between two set-ups carry Welch's standard error ``sqrt(s_a²/n_a + s_b²/n_b)``.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pipefollow.experiments import figures
from pipefollow.experiments.config import ExperimentConfig, TrialConfig, from_dict

# "Converged to a pipe-tracking policy" (DESIGN.md, claims 1-3), measured on a repeat's phase:
CONVERGE_EPISODES = 50  # judged over the last 50 training episodes of the phase
CONVERGE_MIN_IN_VIEW = 0.95  # mean fraction of decisions ending with the pipe in view
CONVERGE_MIN_PROGRESS_M = 4.0  # mean arc length reached (m): past paper-left's first turn (2 m)
CONVERGE_PIPELINE = "paper-left"  # the pipeline whose turns the text cites
EARLY_EPISODES = 100  # "early, high-exploration episodes" (claim 2): the first 100 of a phase
SE_FACTOR = 2.0  # a difference is "clear" when it exceeds 2 standard errors

# The paper's set-up and numbers, for comparison only (never substituted for ours).
PAPER_REPEATS = 5  # §4.1
PAPER_EPISODES = 500  # §4.1
PAPER_TABLE1 = {"learned": -23.2349, "heuristic": -27.8590}  # Table 1, accumulated reward

CONFIRMED = "confirmed"
NOT_CONFIRMED = "not confirmed"
NOT_TESTED = "not tested"

FIGURES = {
    "fig5": "Fig. 5: SARSA versus CACLA and supervised CACLA",
    "fig6": "Fig. 6: tabula rasa CACLA with varying skew",
    "fig7": "Fig. 7: supervised CACLA with varying skew",
}
TRAJECTORIES_PNG = "validation-trajectories.png"
REPORT_MD = "REPORT.md"

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
    """

    seed: int
    episodes: int
    last_return: float
    first_return: float
    last_in_view: float
    last_progress_m: float

    @property
    def converged(self) -> bool:
        """The convergence rule: enough of the pipe in view and far enough along it."""
        return is_converged(self.last_in_view, self.last_progress_m)


def is_converged(last_in_view: float, last_progress_m: float) -> bool:
    """Whether last-window means of pipe-in-view fraction and progress meet the thresholds."""
    return bool(last_in_view >= CONVERGE_MIN_IN_VIEW and last_progress_m >= CONVERGE_MIN_PROGRESS_M)


def repeat_stats(seed: int, returns, in_view, progress_m) -> RepeatStats:
    """Statistics of one repeat's phase from its per-episode series (in episode order).

    Windows longer than the phase use all of its episodes.
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


def _episodes_by_seed(rows: Rows, trial: str) -> dict[int, Rows]:
    """A trial's training rows grouped by seed (in repeat order), each sorted by episode."""
    out: dict[int, Rows] = {}
    for r in rows:
        if r["trial"] == trial:
            out.setdefault(int(r["seed"]), []).append(r)
    order = sorted(out, key=lambda s: (int(out[s][0]["repeat"]), s))
    return {s: sorted(out[s], key=lambda r: int(r["episode"])) for s in order}


def _phases(episodes: Rows) -> list[tuple[str, Rows]]:
    """A repeat's episodes split by phase, in order of appearance: (pipeline, rows)."""
    groups: dict[str, Rows] = {}
    for r in episodes:
        groups.setdefault(r["phase"], []).append(r)
    return [(g[0]["pipeline"], g) for g in groups.values()]


def _col(rows: Rows, name: str) -> np.ndarray:
    return np.array([float(r[name]) for r in rows], dtype=np.float64)


def summarize_trial(rows: Rows, trial: TrialConfig) -> list[PhaseSummary]:
    """Per-phase summaries of one trial from ``results.csv`` rows (none if it has no rows)."""
    per_phase: dict[int, list[RepeatStats]] = {}
    pipelines: dict[int, str] = {}
    for seed, episodes in _episodes_by_seed(rows, trial.name).items():
        for k, (pipeline, ph) in enumerate(_phases(episodes)):
            stats = repeat_stats(seed, _col(ph, "return"), _col(ph, "pipe_in_view"), _col(ph, "progress_m"))
            per_phase.setdefault(k, []).append(stats)
            pipelines[k] = pipeline
    title = trial.title
    return [PhaseSummary(trial.name, title, k, pipelines[k], tuple(per_phase[k])) for k in sorted(per_phase)]


def learning_curves(rows: Rows, trial: str) -> np.ndarray:
    """(repeats, episodes) return per training episode of a trial (cut to the shortest repeat)."""
    series = [_col(ep, "return") for ep in _episodes_by_seed(rows, trial).values()]
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


# ---------------------------------------------------------------------------------------------
# Claims


@dataclass(frozen=True)
class Part:
    """One checkable part of a claim.

    Attributes:
        statement: what the paper says (this part).
        ours: our numbers.
        verdict: ``confirmed``, ``not confirmed`` or ``not tested``.
    """

    statement: str
    ours: str
    verdict: str


@dataclass(frozen=True)
class Claim:
    """One of the paper's claims (DESIGN.md), checked part by part.

    Attributes:
        number: 1-4.
        source: where the paper makes it (``Fig. 5`` ...).
        paper: the paper's statement.
        parts: the parts with their verdicts.
    """

    number: int
    source: str
    paper: str
    parts: tuple[Part, ...]

    @property
    def verdict(self) -> str:
        """``confirmed`` if every part is, ``not tested`` if no part was tested, else ``not confirmed``."""
        verdicts = {p.verdict for p in self.parts}
        if verdicts == {CONFIRMED}:
            return CONFIRMED
        if verdicts == {NOT_TESTED}:
            return NOT_TESTED
        return NOT_CONFIRMED


def _pm(values, digits: int = 2, scale: float = 1.0) -> str:
    """``mean ± sd`` over repeats (just the mean for a single repeat)."""
    m, s = mean_sd(np.asarray(values, dtype=np.float64) * scale)
    if math.isnan(m):
        return "—"
    return f"{m:.{digits}f}" if math.isnan(s) else f"{m:.{digits}f} ± {s:.{digits}f}"


def _se_text(diff: float, se: float) -> str:
    if math.isnan(se):
        return f"difference {diff:+.2f} (standard error undefined with fewer than two repeats)"
    ratio = "" if se == 0 else f", {diff / se:+.1f} SE"
    return f"difference {diff:+.2f} ± {se:.2f} (Welch SE{ratio})"


def _verdict(ok: bool) -> str:
    return CONFIRMED if ok else NOT_CONFIRMED


def _convergence_part(summaries: Sequence[PhaseSummary], statement: str, expect_all: bool = True) -> Part:
    """All listed set-ups converge in every repeat (``expect_all``) or in none."""
    if not summaries:
        return Part(statement, "no such trial in this run", NOT_TESTED)
    ours = "; ".join(f"{s.label}: {s.n_converged}/{s.n} repeats converged" for s in summaries)
    ok = all((s.n_converged == s.n if expect_all else s.n_converged == 0) and s.n > 0 for s in summaries)
    return Part(statement, ours, _verdict(ok))


def _group(trials: Iterable[TrialConfig], key: str, summaries: Mapping[str, list[PhaseSummary]]):
    """Trials of a figure group that have results."""
    return [t for t in trials if key in t.figures and summaries.get(t.name)]


def claim_fig5(trials: Sequence[TrialConfig], summaries: Mapping[str, list[PhaseSummary]]) -> Claim:
    """Claim 1: CACLA and supervised CACLA converge in every repeat; SARSA in none."""
    group = _group(trials, "fig5", summaries)
    parts = []
    for t in group:
        first = summaries[t.name][0]
        if t.algorithm == "sarsa":
            parts.append(_convergence_part([first], f"{t.title} does not converge in any repeat", False))
        else:
            parts.append(_convergence_part([first], f"{t.title} converges in every repeat"))
    if not parts:
        statement = "CACLA and supervised CACLA converge; SARSA does not"
        parts.append(Part(statement, "no fig5 trials in this run", NOT_TESTED))
    paper = (
        '"The Sarsa algorithm did not converge to a result able to track the pipeline within the '
        "allotted number of episodes in any instance. Both versions of CACLA converged to a successful "
        'policy in all instances." (§5.1)'
    )
    return Claim(1, "Fig. 5", paper, tuple(parts))


def _baseline_and_variants(group: Sequence[TrialConfig], supervised: bool):
    base = [t for t in group if t.algorithm == "cacla" and t.supervised == supervised and t.skew_deg == 0]
    variants = [t for t in group if t.algorithm == "cacla" and t.supervised == supervised and t.skew_deg > 0]
    return (base[0] if base else None), variants


def _comparisons(base: TrialConfig, variants, summaries, stat: str) -> list[tuple[TrialConfig, float, float]]:
    """(variant, mean difference variant − baseline, Welch SE) of a per-repeat statistic, first phase."""
    b = summaries[base.name][0].values(stat)
    return [(v, *welch(summaries[v.name][0].values(stat), b)) for v in variants]


def claim_fig6(trials: Sequence[TrialConfig], summaries: Mapping[str, list[PhaseSummary]]) -> Claim:
    """Claim 2: CACLA with skew converges; skew helps in the early, high-exploration episodes."""
    group = _group(trials, "fig6", summaries)
    base, variants = _baseline_and_variants(group, supervised=False)
    first = [summaries[t.name][0] for t in group]
    converge = _convergence_part(first, "every set-up (plain and skewed CACLA) converges in every repeat")
    statement = (
        f"skew helps early: each skew variant's mean return over the first {EARLY_EPISODES} "
        f"episodes is above plain CACLA's by more than {SE_FACTOR:g} standard errors"
    )
    if base is None or not variants:
        helps = Part(statement, "needs plain CACLA and at least one skew variant in fig6", NOT_TESTED)
    else:
        comps = _comparisons(base, variants, summaries, "first_return")
        better = [not math.isnan(se) and d > SE_FACTOR * se for _, d, se in comps]
        lines = [f"{base.title}: {_pm(summaries[base.name][0].values('first_return'))}"]
        lines += [
            f"{v.title}: {_pm(summaries[v.name][0].values('first_return'))}, {_se_text(d, se)}"
            for v, d, se in comps
        ]
        if all(better):
            tally = f"all {len(comps)} variants better by more than {SE_FACTOR:g} SE"
        elif any(better):
            tally = f"mixed: {sum(better)} of {len(comps)} variants better by more than {SE_FACTOR:g} SE"
        else:
            tally = f"none of the {len(comps)} variants better by more than {SE_FACTOR:g} SE"
        head = f"first {EARLY_EPISODES} episodes, mean return over repeats: "
        ours = head + "; ".join(lines) + f" — {tally}"
        helps = Part(statement, ours, _verdict(all(better)))
    paper = (
        '"All cases converged to a successful policy in all instances." (§5.1) "Adding skew '
        "exploration also seems to have a positive effect on early stages of the tabula rasa CACLA "
        'algorithm – the stages with more heavy exploration." (§6)'
    )
    return Claim(2, "Fig. 6", paper, (converge, helps))


def claim_fig7(trials: Sequence[TrialConfig], summaries: Mapping[str, list[PhaseSummary]]) -> Claim:
    """Claim 3: supervised CACLA with and without skew both converge; no advantage from skew."""
    group = _group(trials, "fig7", summaries)
    base, variants = _baseline_and_variants(group, supervised=True)
    first = [summaries[t.name][0] for t in group]
    converge = _convergence_part(first, "supervised CACLA with and without skew converges in every repeat")
    statement = (
        f"no advantage from skew: the last-{CONVERGE_EPISODES}-episode mean returns with and "
        f"without skew differ by less than {SE_FACTOR:g} standard errors"
    )
    if base is None or not variants:
        same = Part(statement, "needs supervised CACLA with and without skew in fig7", NOT_TESTED)
    else:
        comps = _comparisons(base, variants, summaries, "last_return")
        alike = [not math.isnan(se) and abs(d) < SE_FACTOR * se for _, d, se in comps]
        lines = [f"{base.title}: {_pm(summaries[base.name][0].values('last_return'))}"]
        lines += [
            f"{v.title}: {_pm(summaries[v.name][0].values('last_return'))}, {_se_text(d, se)}"
            for v, d, se in comps
        ]
        ours = f"last {CONVERGE_EPISODES} episodes, mean return over repeats: " + "; ".join(lines)
        same = Part(statement, ours, _verdict(all(alike)))
    paper = (
        '"Both cases converged to a successful policy in all instances." (§5.1) "Comparing the '
        "supervised CACLA algorithm with and without skew, we see no advantage of using the skew "
        'exploration parameter." (§6)'
    )
    return Claim(3, "Fig. 7", paper, (converge, same))


@dataclass(frozen=True)
class Table1:
    """Deterministic evaluation of the validation trial (paper Table 1).

    Attributes:
        trial: the trial's name.
        label: its label.
        pipeline: the evaluation pipeline.
        seconds: length of the evaluation episode (s).
        seeds: seeds of the repeats.
        learned: learned controller's return per repeat (as executed, with k(s) for supervised agents).
        heuristic: heuristic's return per repeat (deterministic, so normally all equal).
        actor: pure actor's return per repeat (empty if not evaluated).
    """

    trial: str
    label: str
    pipeline: str
    seconds: float
    seeds: tuple[int, ...]
    learned: np.ndarray
    heuristic: np.ndarray
    actor: np.ndarray

    @property
    def improvement_pct(self) -> float:
        """Relative improvement of the mean learned return over the mean heuristic return (%)."""
        h = float(self.heuristic.mean())
        return (float(self.learned.mean()) - h) / abs(h) * 100.0

    @property
    def n_beat(self) -> int:
        """Repeats whose learned return is above that repeat's heuristic return."""
        return int(np.sum(self.learned > self.heuristic))

    @property
    def median_seed(self) -> int:
        """Seed of the repeat with the median learned return (the lower one for an even count)."""
        order = np.argsort(self.learned, kind="stable")
        return self.seeds[int(order[(len(order) - 1) // 2])]


def table1_from(trial: TrialConfig, evaluation: Evaluation) -> Table1 | None:
    """Table 1 data of a trial, if its learned and heuristic controllers were both evaluated."""
    learned, heuristic = evaluation.returns.get("learned", {}), evaluation.returns.get("heuristic", {})
    seeds = tuple(sorted(set(learned) & set(heuristic)))
    if not seeds:
        return None
    actor = evaluation.returns.get("actor", {})
    seconds = trial.evaluate_seconds if trial.evaluate_on else trial.episode_seconds
    return Table1(
        trial=trial.name,
        label=trial.title,
        pipeline=evaluation.pipeline,
        seconds=seconds,
        seeds=seeds,
        learned=np.array([learned[s] for s in seeds]),
        heuristic=np.array([heuristic[s] for s in seeds]),
        actor=np.array([actor[s] for s in seeds if s in actor]),
    )


def _paper_improvement_pct() -> float:
    return (PAPER_TABLE1["learned"] - PAPER_TABLE1["heuristic"]) / abs(PAPER_TABLE1["heuristic"]) * 100.0


def claim_table1(table: Table1 | None, later_phases: Sequence[PhaseSummary]) -> Claim:
    """Claim 4: the learned policy beats the heuristic on the validation pipe (and learned right turns)."""
    statement = "the learned policy's accumulated reward on the unseen validation pipe beats the heuristic's"
    if table is None:
        beats = Part(statement, "no table1 trial with a learned and a heuristic evaluation", NOT_TESTED)
    else:
        lm, hm = float(table.learned.mean()), float(table.heuristic.mean())
        ours = (
            f"on `{table.pipeline}` for {table.seconds:g} s (σ = 0): learned {_pm(table.learned)} "
            f"(mean ± sd over {len(table.seeds)} repeats) vs heuristic {hm:.2f}: "
            f"{table.improvement_pct:+.1f} % relative to the heuristic (paper: "
            f"{_paper_improvement_pct():+.1f} %); the learned policy beats the heuristic in "
            f"{table.n_beat}/{len(table.seeds)} repeats"
        )
        beats = Part(statement, ours, _verdict(lm > hm))
    parts = [beats]
    for s in later_phases:
        part = f"training on `{s.pipeline}` (phase {s.phase + 1}) also converges in every repeat"
        parts.append(_convergence_part([s], part))
    paper = (
        '"Training of the supervised CACLA algorithm resulted in a successful policy also for right '
        f'turns." (§5.2) Table 1: CACLA {PAPER_TABLE1["learned"]:.4f}, heuristic '
        f"{PAPER_TABLE1['heuristic']:.4f} accumulated reward ({_paper_improvement_pct():.1f} % better)."
    )
    return Claim(4, "Table 1", paper, tuple(parts))


# ---------------------------------------------------------------------------------------------
# Findings


@dataclass(frozen=True)
class Findings:
    """Everything the report states, computed from the stored tables.

    Attributes:
        config: the experiment.
        summaries: trial name → its phases' summaries (trials with results only).
        evaluations: trial name → its deterministic evaluation.
        claims: the four claims with verdicts.
        table1: the validation trial's evaluation, if any.
        wall_seconds: summed wall time of the trials (s), if known.
        notes: extra lines for the end of the report (what could not be drawn, and why).
    """

    config: ExperimentConfig
    summaries: Mapping[str, list[PhaseSummary]]
    evaluations: Mapping[str, Evaluation]
    claims: tuple[Claim, ...]
    table1: Table1 | None = None
    wall_seconds: float | None = None
    notes: tuple[str, ...] = field(default=())


def compute_findings(
    config: ExperimentConfig, results: Rows, evaluation: Rows, wall_seconds: float | None = None
) -> Findings:
    """The findings of a run from its configuration and the rows of ``results.csv``/``evaluation.csv``."""
    summaries = {t.name: s for t in config.trials if (s := summarize_trial(results, t))}
    evaluations = read_evaluations(evaluation)
    table_trial = next((t for t in config.trials if any("table1" in f for f in t.figures)), None)
    table = None
    later: list[PhaseSummary] = []
    if table_trial is not None:
        if table_trial.name in evaluations:
            table = table1_from(table_trial, evaluations[table_trial.name])
        later = summaries.get(table_trial.name, [])[1:]
    claims = (
        claim_fig5(config.trials, summaries),
        claim_fig6(config.trials, summaries),
        claim_fig7(config.trials, summaries),
        claim_table1(table, later),
    )
    return Findings(config, summaries, evaluations, claims, table, wall_seconds)


# ---------------------------------------------------------------------------------------------
# Markdown


def _turns_text() -> str:
    from pipefollow.pipeline import builtin

    turns = builtin(CONVERGE_PIPELINE).cumulative[1:-1]
    return " and ".join(f"{s:g} m" for s in turns)


def _setup_lines(f: Findings) -> list[str]:
    cfg = f.config
    seeds = cfg.seeds()
    seed_text = f"seed {seeds[0]}" if len(seeds) == 1 else f"seeds {seeds[0]}–{seeds[-1]}"
    lines = [
        "## What was run",
        "",
        f"Experiment `{cfg.name}`: {len(cfg.trials)} trials, each repeated {cfg.repeats} times "
        f"({seed_text}).",
        "",
        "| trial | label | learner | training phases (pipeline × episodes) | episode length (s) |",
        "|---|---|---|---|---|",
    ]
    for t in cfg.trials:
        learner = "SARSA" if t.algorithm == "sarsa" else ("supervised " if t.supervised else "") + "CACLA"
        if t.skew_deg:
            learner += f", Δγ = {t.skew_deg:g}°"
        phases = ", then ".join(f"`{p.pipeline}` × {p.episodes}" for p in t.phases)
        lines.append(f"| `{t.name}` | {t.title} | {learner} | {phases} | {t.episode_seconds:g} |")
    lines.append("")
    evaluated = {e.pipeline for e in f.evaluations.values()}
    if evaluated:
        lines.append(
            "After training, every trial was evaluated deterministically (σ = 0) for one episode "
            "(learned controller, the heuristic and, for supervised agents, the pure actor) on "
            + ", ".join(f"`{p}`" for p in sorted(evaluated))
            + "."
        )
    if f.wall_seconds is not None:
        took = f"{f.wall_seconds:.1f} s" if f.wall_seconds < 3600 else f"{f.wall_seconds / 3600:.2f} h"
        lines.append(
            f"The trials took {took} of compute in total (summed over trials that may have run in parallel)."
        )
    missing = [t.name for t in cfg.trials if t.name not in f.summaries]
    if missing:
        lines.append("No training results for: " + ", ".join(f"`{m}`" for m in missing) + ".")
    lines.append("")
    return lines


def _convergence_lines(f: Findings) -> list[str]:
    shortest = min((s.episodes for ss in f.summaries.values() for s in ss), default=0)
    lines = [
        "## Convergence to a pipe-tracking policy",
        "",
        f"A repeat has *converged* when, over the last {CONVERGE_EPISODES} training episodes of a phase, the "
        f"pipe was in view at the end of at least {CONVERGE_MIN_IN_VIEW * 100:g} % of the decisions on "
        f"average and the mean progress along the pipe was at least {CONVERGE_MIN_PROGRESS_M:g} m. On "
        f"`{CONVERGE_PIPELINE}` (turns at {_turns_text()} of arc length) that is past the first turn, with "
        "the second in the camera's 3 m view. Claims 1–3 judge each trial's first phase.",
        "",
    ]
    if shortest and shortest < CONVERGE_EPISODES + EARLY_EPISODES:
        lines += [
            f"Note: this run's shortest phase has {shortest} episodes, fewer than "
            f"{CONVERGE_EPISODES + EARLY_EPISODES}; the first-{EARLY_EPISODES} and "
            f"last-{CONVERGE_EPISODES} windows overlap or are cut to what exists.",
            "",
        ]
    return lines


def _trial_table_lines(f: Findings) -> list[str]:
    lines = [
        "## Results per trial",
        "",
        "Mean ± sample standard deviation over repeats. Training columns are per phase; the evaluation "
        "columns give the one deterministic episode after training (σ = 0) of the learned controller and of "
        "the heuristic on the same pipeline.",
        "",
        f"| trial | phase | converged | return, last {CONVERGE_EPISODES} | return, first {EARLY_EPISODES} "
        f"| pipe in view, last {CONVERGE_EPISODES} (%) | progress, last {CONVERGE_EPISODES} (m) "
        "| evaluation pipeline | eval. return, learned | eval. return, heuristic |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for t in f.config.trials:
        phases = f.summaries.get(t.name, [])
        ev = f.evaluations.get(t.name)
        for s in phases:
            last = s is phases[-1]
            evals = (
                f"`{ev.pipeline}` | {_pm(ev.of('learned'))} | {_pm(ev.of('heuristic'))}"
                if ev is not None and last
                else "— | — | —"
            )
            lines.append(
                f"| {s.label} | {s.phase + 1}: `{s.pipeline}` | {s.n_converged}/{s.n} "
                f"| {_pm(s.values('last_return'))} | {_pm(s.values('first_return'))} "
                f"| {_pm(s.values('last_in_view'), 1, 100.0)} | {_pm(s.values('last_progress_m'))} "
                f"| {evals} |"
            )
    lines.append("")
    return lines


def _claim_lines(f: Findings) -> list[str]:
    lines = ["## The paper's claims", ""]
    for c in f.claims:
        lines += [f"### Claim {c.number} ({c.source}): {c.verdict}", "", f"Paper: {c.paper}", ""]
        for i, p in enumerate(c.parts):
            tag = f"({chr(ord('a') + i)}) " if len(c.parts) > 1 else ""
            lines += [f"- {tag}*{p.statement}.* Ours: {p.ours}. **Verdict: {p.verdict}.**"]
        lines.append("")
    return lines


def _table1_lines(f: Findings, trajectories: str | None) -> list[str]:
    t = f.table1
    if t is None:
        return []
    lines = [
        "## Table 1: validation on an unseen pipe",
        "",
        f"Trial `{t.trial}` ({t.label}), evaluated on `{t.pipeline}` for {t.seconds:g} s, σ = 0; mean ± sd "
        f"over {len(t.seeds)} repeats. The paper's absolute numbers come from its own simulator and "
        "pipeline, so compare the direction and size of the difference, not the values.",
        "",
        "| controller | ours: accumulated reward | paper |",
        "|---|---|---|",
        f"| learned (supervised CACLA, as executed) | {_pm(t.learned)} | {PAPER_TABLE1['learned']:.4f} |",
    ]
    if t.actor.size:
        lines.append(f"| its pure actor | {_pm(t.actor)} | — |")
    lines += [
        f"| heuristic | {_pm(t.heuristic)} | {PAPER_TABLE1['heuristic']:.4f} |",
        f"| learned relative to heuristic | {t.improvement_pct:+.1f} % | {_paper_improvement_pct():+.1f} % |",
        f"| repeats where learned beats heuristic | {t.n_beat}/{len(t.seeds)} | — |",
        "",
    ]
    if trajectories:
        lines += [
            f"Trajectories of the repeat with the median learned return (seed {t.median_seed}):",
            "",
            f"![validation trajectories]({trajectories})",
            "",
        ]
    return lines


def _figure_lines(drawn: Mapping[str, str]) -> list[str]:
    if not drawn:
        return []
    lines = ["## Learning curves", ""]
    for key, name in drawn.items():
        lines += [f"![{FIGURES[key]}]({name})", ""]
    return lines


def _differences_lines(f: Findings) -> list[str]:
    lines = ["## Where we differ from the paper", ""]
    differ = [(c, p) for c in f.claims for p in c.parts if p.verdict == NOT_CONFIRMED]
    untested = [(c, p) for c in f.claims for p in c.parts if p.verdict == NOT_TESTED]
    for c, p in differ:
        lines.append(f"- Not confirmed — claim {c.number} ({c.source}): {p.statement}.")
    for c, p in untested:
        lines.append(f"- Not tested in this run — claim {c.number} ({c.source}): {p.statement}.")
    cfg = f.config
    episodes = sorted({p.episodes for t in cfg.trials for p in t.phases})
    if cfg.repeats != PAPER_REPEATS or episodes != [PAPER_EPISODES]:
        counts = ", ".join(map(str, episodes))
        lines.append(
            f"- Set-up: {cfg.repeats} repeats of {counts} episodes per phase; the paper used "
            f"{PAPER_REPEATS} repeats of {PAPER_EPISODES}."
        )
    if len(lines) == 2:
        lines.append("- Every claim was confirmed.")
    lines.append("")
    return lines


def render_markdown(
    findings: Findings, figures_drawn: Mapping[str, str] | None = None, trajectories: str | None = None
) -> str:
    """REPORT.md text from findings.

    Args:
        findings: what was computed.
        figures_drawn: figure key (fig5 ...) → relative path of the PNG, for those drawn.
        trajectories: relative path of the validation-trajectories PNG, if drawn.

    Returns:
        The markdown text.
    """
    verdicts = ", ".join(f"claim {c.number} {c.verdict}" for c in findings.claims)
    lines = [
        "# Reproduction report: AUV pipeline following with reinforcement learning",
        "",
        f"Fjerdingen, Kyrkjebø & Transeth (2010), experiment `{findings.config.name}`. Generated by "
        "`pipefollow.experiments.report` from this run folder's `results.csv` and `evaluation.csv`; every "
        "number is computed from the stored results.",
        "",
        f"Summary: {verdicts}.",
        "",
    ]
    lines += _setup_lines(findings)
    lines += _convergence_lines(findings)
    lines += _trial_table_lines(findings)
    lines += _claim_lines(findings)
    lines += _table1_lines(findings, trajectories)
    lines += _figure_lines(figures_drawn or {})
    lines += _differences_lines(findings)
    lines += list(findings.notes)
    return "\n".join(lines).rstrip() + "\n"


# ---------------------------------------------------------------------------------------------
# The run folder


def _load_trial(run_dir: Path, trial: str, seed: int):
    """The store's :class:`~pipefollow.experiments.trial.TrialResult` (imported lazily)."""
    from pipefollow.experiments.store import load_trial

    return load_trial(run_dir, trial, seed)


_LOAD_ERRORS = (ImportError, OSError, KeyError, ValueError)


def _wall_seconds(run_dir: Path, config: ExperimentConfig, load: Callable) -> float | None:
    """Summed wall time of all trial files, or None if any cannot be read."""
    try:
        runs = [(t.name, s) for t in config.trials for s in config.seeds()]
        return float(sum(load(run_dir, name, seed).wall_seconds for name, seed in runs))
    except _LOAD_ERRORS:
        return None


def draw_learning_curves(
    run_dir: Path, config: ExperimentConfig, results: Rows, evaluations: Mapping[str, Evaluation]
) -> dict[str, str]:
    """Draw fig5/6/7.png for the groups with results; returns key → file name of those drawn."""
    drawn = {}
    for key, title in FIGURES.items():
        group = [t for t in config.trials if key in t.figures]
        curves = {t.title: c for t in group if (c := learning_curves(results, t.name)).size}
        if not curves:
            continue
        figures.learning_curve_figure(curves, run_dir / f"{key}.png", title, _reference(group, evaluations))
        drawn[key] = f"{key}.png"
    return drawn


def _reference(group: Sequence[TrialConfig], evaluations: Mapping[str, Evaluation]) -> float | None:
    """Mean heuristic return on the group's training pipeline, if all its evaluations ran there."""
    evs = [evaluations[t.name] for t in group if t.name in evaluations]
    training = {t.phases[-1].pipeline for t in group}
    if not evs or len(training) != 1 or {e.pipeline for e in evs} != training:
        return None
    h = np.concatenate([e.of("heuristic") for e in evs])
    return float(h.mean()) if h.size else None


def draw_trajectories(run_dir: Path, table: Table1, load: Callable = _load_trial) -> str:
    """Draw the validation trajectories of the median repeat; returns the PNG's file name.

    Raises:
        ImportError, OSError, KeyError, ValueError: the trial file cannot be read.
    """
    result = load(run_dir, table.trial, table.median_seed)
    names = {"learned": f"learned ({table.label})", "actor": "pure actor", "heuristic": "heuristic"}
    i = table.seeds.index(table.median_seed)
    returns = {"learned": table.learned[i], "heuristic": table.heuristic[i]}
    if table.actor.size == len(table.seeds):
        returns["actor"] = table.actor[i]
    order = sorted(result.poses, key=lambda c: list(names).index(c) if c in names else len(names))
    trajectories = {
        f"{names.get(c, c)}: {returns[c]:.2f}" if c in returns else names.get(c, c): result.poses[c]
        for c in order
    }
    title = f"{table.pipeline}, {table.seconds:g} s, σ = 0, seed {table.median_seed} (median learned return)"
    figures.trajectories_figure(table.pipeline, trajectories, run_dir / TRAJECTORIES_PNG, title)
    return TRAJECTORIES_PNG


def write_outputs(run_dir: str | Path) -> list[Path]:
    """Draw the figures and write REPORT.md into a run folder.

    Args:
        run_dir: the run folder (``config.json``, ``results.csv``, ``evaluation.csv``, ``trials/``).

    Returns:
        Paths written: fig5/6/7.png for the figure groups with results, validation-trajectories.png
        if a table1 trial was evaluated and its trial file can be read, and REPORT.md (last).
    """
    from pipefollow.atomic import write_text_atomic

    run_dir = Path(run_dir)
    config = from_dict(json.loads((run_dir / "config.json").read_text()))
    results = read_rows(run_dir / "results.csv")
    evaluation = read_rows(run_dir / "evaluation.csv")
    findings = compute_findings(config, results, evaluation, _wall_seconds(run_dir, config, _load_trial))
    drawn = draw_learning_curves(run_dir, config, results, findings.evaluations)
    trajectories = None
    if findings.table1 is not None:
        try:
            trajectories = draw_trajectories(run_dir, findings.table1, _load_trial)
        except _LOAD_ERRORS as e:
            findings = _with_note(findings, f"The validation trajectories were not drawn: {e}.")
    written = [run_dir / name for name in drawn.values()]
    if trajectories:
        written.append(run_dir / trajectories)
    report = run_dir / REPORT_MD
    write_text_atomic(report, render_markdown(findings, drawn, trajectories))
    written.append(report)
    return written


def _with_note(findings: Findings, note: str) -> Findings:
    import dataclasses

    return dataclasses.replace(findings, notes=(*findings.notes, note))
