"""The paper's claims, checked part by part against a run's per-repeat statistics.

Each of the four claims (:class:`Claim`: :func:`claim_fig5`, :func:`claim_fig6`,
:func:`claim_fig7`, :func:`claim_table1`) is judged part by part from the trials' summaries and
the validation trial's :class:`Table1`; :func:`pipefollow.experiments.findings.compute_findings`
gathers them from a run's stored tables, so every number comes from the stored results. The only
numbers written here are the paper's own (for comparison) and the rules' constants.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from pipefollow.experiments.schema import TrialConfig
from pipefollow.experiments.summary import (
    CONVERGE_EPISODES,
    EARLY_EPISODES,
    Evaluation,
    PhaseSummary,
    mean_sd,
    welch,
)
from pipefollow.files.paper_training import TRAINING_EPISODES

SE_FACTOR = 2.0  # a difference is "clear" when it exceeds 2 standard errors

# The paper's set-up and numbers, for comparison only (never substituted for ours).
PAPER_REPEATS = 5  # §4.1
PAPER_EPISODES = TRAINING_EPISODES  # §4.1
PAPER_TABLE1 = {"learned": -23.2349, "heuristic": -27.8590}  # Table 1, accumulated reward

CONFIRMED = "confirmed"
NOT_CONFIRMED = "not confirmed"
NOT_TESTED = "not tested"


# ---------------------------------------------------------------------------------------------
# Claims


@dataclass(frozen=True)
class Part:
    """One checkable part of a claim.

    Attributes:
        statement: what the paper says (this part).
        ours: our numbers.
        verdict: ``confirmed``, ``not confirmed`` or ``not tested``.
        passed: cases in which the statement held: repeats (summed over set-ups) for convergence
            and Table 1, (variant, repeat) pairs of the same seed for a skew comparison.
        total: cases counted.
        margin: how far the deciding number lies from the rule's threshold, with its unit
            (positive on the side of the verdict given, negative where the rule failed).
    """

    statement: str
    ours: str
    verdict: str
    passed: int = 0
    total: int = 0
    margin: str = ""


@dataclass(frozen=True)
class Claim:
    """One of the paper's claims (docs/design.md), checked part by part.

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


def pm(values, digits: int = 2, scale: float = 1.0) -> str:
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


def _slack(r) -> float:
    """How far a repeat is past the convergence rule, as the smaller of its two relative margins.

    Positive when it converged, negative when it did not: ``min(in view / threshold,
    progress / threshold) − 1`` (a threshold of 0 counts as met by any value).
    """
    pairs = ((r.last_in_view, r.min_in_view), (r.last_progress_m, r.min_progress_m))
    ratios = [v / t for v, t in pairs if t > 0]
    return min(ratios, default=math.inf) - 1.0


def convergence_margin(summaries: Sequence[PhaseSummary], expect_all: bool = True) -> str:
    """The repeat nearest the rule's other side: the worst for "every repeat", the best for "none".

    Its pipe-in-view and progress against their thresholds, e.g. ``CACLA seed 2013: in view
    100.0 % (rule ≥ 95 %), progress 3.96 m (rule ≥ 4 m)``.
    """
    repeats = [(s, r) for s in summaries for r in s.repeats]
    if not repeats:
        return ""
    pick = min if expect_all else max
    s, r = pick(repeats, key=lambda sr: _slack(sr[1]))
    # the repeat that decides the part: one on the rule's other side is named for what it did
    if expect_all:
        label = "closest to failing" if _slack(r) >= 0.0 else "failed furthest"
    else:
        label = "closest to converging" if _slack(r) < 0.0 else "converged furthest"
    return (
        f"{label}: {s.label} seed {r.seed}, "
        f"in view {r.last_in_view * 100:.1f} % (rule ≥ {r.min_in_view * 100:g} %), "
        f"progress {r.last_progress_m:.2f} m (rule ≥ {r.min_progress_m:g} m)"
    )


def _convergence_part(summaries: Sequence[PhaseSummary], statement: str, expect_all: bool = True) -> Part:
    """All listed set-ups converge in every repeat (``expect_all``) or in none."""
    if not summaries:
        return Part(statement, "no such trial in this run", NOT_TESTED)
    ours = "; ".join(f"{s.label}: {s.n_converged}/{s.n} repeats converged" for s in summaries)
    ok = all((s.n_converged == s.n if expect_all else s.n_converged == 0) and s.n > 0 for s in summaries)
    total = sum(s.n for s in summaries)
    converged = sum(s.n_converged for s in summaries)
    passed = converged if expect_all else total - converged
    return Part(statement, ours, _verdict(ok), passed, total, convergence_margin(summaries, expect_all))


def _se_margin(comps, rule) -> str:
    """The comparison nearest the other side of a standard-error rule, in standard errors."""
    defined = [(v, d / se) for v, d, se in comps if not math.isnan(se) and se > 0]
    if not defined:
        return ""
    v, z, m = min(((v, z, rule(z)) for v, z in defined), key=lambda x: x[2])
    return f"nearest the rule: {v.title}, {z:+.1f} SE ({m:+.1f} SE from the {SE_FACTOR:g}-SE threshold)"


def _paired(base: PhaseSummary, variant: PhaseSummary, stat: str, variant_better: bool) -> tuple[int, int]:
    """(repeats of the same seed in which the variant is better — or not better —, repeats paired)."""
    b = {r.seed: getattr(r, stat) for r in base.repeats}
    pairs = [(getattr(r, stat), b[r.seed]) for r in variant.repeats if r.seed in b]
    return sum((v > w) == variant_better for v, w in pairs), len(pairs)


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


def _skew_figure(trials, summaries, key: str, supervised: bool, converge_statement: str):
    """A skew figure's CACLA trials with results: the baseline (or None), the skew variants, convergence.

    The last is the part that every set-up of the figure converges in every repeat.
    """
    group = _group(trials, key, summaries)
    cacla = [t for t in group if t.algorithm == "cacla" and t.supervised == supervised]
    base = [t for t in cacla if t.skew_deg == 0]
    converge = _convergence_part([summaries[t.name][0] for t in group], converge_statement)
    return (base[0] if base else None), [t for t in cacla if t.skew_deg > 0], converge


def _against_baseline(base: TrialConfig, variants, summaries, stat: str, variant_better: bool):
    """Each variant against the baseline on a per-repeat statistic of the first phase.

    Returns the comparisons ``(variant, mean difference variant − baseline, Welch SE)``, the lines
    of the report (the baseline's mean ± sd, then each variant's with its difference) and the
    paired counts of :func:`_paired`, summed over the variants.
    """
    b0 = summaries[base.name][0]
    comps = [(v, *welch(summaries[v.name][0].values(stat), b0.values(stat))) for v in variants]
    lines = [f"{base.title}: {pm(b0.values(stat))}"]
    lines += [f"{v.title}: {pm(summaries[v.name][0].values(stat))}, {_se_text(d, se)}" for v, d, se in comps]
    counts = [_paired(b0, summaries[v.name][0], stat, variant_better) for v in variants]
    return comps, lines, tuple(map(sum, zip(*counts, strict=True)))


def claim_fig6(trials: Sequence[TrialConfig], summaries: Mapping[str, list[PhaseSummary]]) -> Claim:
    """Claim 2: CACLA with skew converges; skew helps in the early, high-exploration episodes."""
    base, variants, converge = _skew_figure(
        trials, summaries, "fig6", False, "every set-up (plain and skewed CACLA) converges in every repeat"
    )
    statement = (
        f"skew helps early: each skew variant's mean return over the first {EARLY_EPISODES} "
        f"episodes is above plain CACLA's by more than {SE_FACTOR:g} standard errors"
    )
    if base is None or not variants:
        helps = Part(statement, "needs plain CACLA and at least one skew variant in fig6", NOT_TESTED)
    else:
        comps, lines, counts = _against_baseline(base, variants, summaries, "first_return", True)
        better = [not math.isnan(se) and d > SE_FACTOR * se for _, d, se in comps]
        if all(better):
            tally = f"all {len(comps)} variants better by more than {SE_FACTOR:g} SE"
        elif any(better):
            tally = f"mixed: {sum(better)} of {len(comps)} variants better by more than {SE_FACTOR:g} SE"
        else:
            tally = f"none of the {len(comps)} variants better by more than {SE_FACTOR:g} SE"
        head = f"first {EARLY_EPISODES} episodes, mean return over repeats: "
        ours = head + "; ".join(lines) + f" — {tally}"
        margin = _se_margin(comps, lambda z: z - SE_FACTOR)
        helps = Part(statement, ours, _verdict(all(better)), *counts, margin)
    paper = (
        '"All cases converged to a successful policy in all instances." (§5.1) "Adding skew '
        "exploration also seems to have a positive effect on early stages of the tabula rasa CACLA "
        'algorithm – the stages with more heavy exploration." (§6)'
    )
    return Claim(2, "Fig. 6", paper, (converge, helps))


def claim_fig7(trials: Sequence[TrialConfig], summaries: Mapping[str, list[PhaseSummary]]) -> Claim:
    """Claim 3: supervised CACLA with and without skew both converge; no advantage from skew."""
    base, variants, converge = _skew_figure(
        trials, summaries, "fig7", True, "supervised CACLA with and without skew converges in every repeat"
    )
    statement = (
        f"no advantage from skew: the last-{CONVERGE_EPISODES}-episode mean returns with and "
        f"without skew differ by less than {SE_FACTOR:g} standard errors"
    )
    if base is None or not variants:
        same = Part(statement, "needs supervised CACLA with and without skew in fig7", NOT_TESTED)
    else:
        comps, lines, counts = _against_baseline(base, variants, summaries, "last_return", False)
        alike = [not math.isnan(se) and abs(d) < SE_FACTOR * se for _, d, se in comps]
        ours = f"last {CONVERGE_EPISODES} episodes, mean return over repeats: " + "; ".join(lines)
        margin = _se_margin(comps, lambda z: SE_FACTOR - abs(z))
        same = Part(statement, ours, _verdict(all(alike)), *counts, margin)
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


def paper_improvement_pct() -> float:
    """The paper's Table 1: learned relative to heuristic (%)."""
    return (PAPER_TABLE1["learned"] - PAPER_TABLE1["heuristic"]) / abs(PAPER_TABLE1["heuristic"]) * 100.0


def claim_table1(table: Table1 | None, later_phases: Sequence[PhaseSummary]) -> Claim:
    """Claim 4: the learned policy beats the heuristic on the validation pipe (and learned right turns)."""
    statement = "the learned policy's accumulated reward on the unseen validation pipe beats the heuristic's"
    if table is None:
        beats = Part(statement, "no table1 trial with a learned and a heuristic evaluation", NOT_TESTED)
    else:
        lm, hm = float(table.learned.mean()), float(table.heuristic.mean())
        ours = (
            f"on `{table.pipeline}` for {table.seconds:g} s (σ = 0): learned {pm(table.learned)} "
            f"(mean ± sd over {len(table.seeds)} repeats) vs heuristic {hm:.2f}: "
            f"{table.improvement_pct:+.1f} % relative to the heuristic (paper: "
            f"{paper_improvement_pct():+.1f} %); the learned policy beats the heuristic in "
            f"{table.n_beat}/{len(table.seeds)} repeats"
        )
        margin = f"learned − heuristic = {lm - hm:+.2f} (mean over repeats)"
        beats = Part(statement, ours, _verdict(lm > hm), table.n_beat, len(table.seeds), margin)
    parts = [beats]
    for s in later_phases:
        part = f"training on `{s.pipeline}` (phase {s.phase + 1}) also converges in every repeat"
        parts.append(_convergence_part([s], part))
    paper = (
        '"Training of the supervised CACLA algorithm resulted in a successful policy also for right '
        f'turns." (§5.2) Table 1: CACLA {PAPER_TABLE1["learned"]:.4f}, heuristic '
        f"{PAPER_TABLE1['heuristic']:.4f} accumulated reward ({paper_improvement_pct():.1f} % better)."
    )
    return Claim(4, "Table 1", paper, tuple(parts))
