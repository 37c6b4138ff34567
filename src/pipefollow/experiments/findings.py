"""A run's findings: the paper's claims judged on its stored tables, on all repeats and on the paper's count.

:func:`compute_findings` turns a run's configuration and the rows of ``results.csv`` and
``evaluation.csv`` into a :class:`Findings` record: the trials' summaries, the validation trial's
Table 1 and the four claims (:mod:`pipefollow.experiments.claims`), which the report
(:mod:`pipefollow.experiments.report`) and the sensitivity analysis
(:mod:`pipefollow.experiments.sensitivity`) state.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

from pipefollow.experiments.claims import (
    PAPER_REPEATS,
    Claim,
    Table1,
    claim_fig5,
    claim_fig6,
    claim_fig7,
    claim_table1,
    table1_from,
)
from pipefollow.experiments.schema import ExperimentConfig
from pipefollow.experiments.summary import (
    Evaluation,
    PhaseSummary,
    Rows,
    Training,
    as_training,
    read_evaluations,
    summarize_trial,
)


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
        machine: where the run was started (``config.json``'s ``machine``), if recorded.
        first_repeats: the claims judged on the paper's count of repeats only (the run's first
            :data:`PAPER_REPEATS` seeds), for a run with more repeats; None otherwise.
    """

    config: ExperimentConfig
    summaries: Mapping[str, list[PhaseSummary]]
    evaluations: Mapping[str, Evaluation]
    claims: tuple[Claim, ...]
    table1: Table1 | None = None
    wall_seconds: float | None = None
    notes: tuple[str, ...] = field(default=())
    machine: Mapping | None = None
    first_repeats: tuple[Claim, ...] | None = None


def compute_findings(
    config: ExperimentConfig, results: Rows | Training, evaluation: Rows, wall_seconds: float | None = None
) -> Findings:
    """The findings of a run from its configuration, ``results.csv`` (rows or series), ``evaluation.csv``.

    A run of more than the paper's :data:`PAPER_REPEATS` repeats is judged twice: on all its
    repeats and on its first :data:`PAPER_REPEATS` seeds (``first_repeats``), so that the report
    shows which verdicts of a 5-repeat run hold over more repeats.
    """
    training = as_training(results)
    found = _judge(config, training, evaluation, wall_seconds)
    if config.repeats <= PAPER_REPEATS:
        return found
    seeds = set(config.seeds()[:PAPER_REPEATS])
    first_training = {t: {s: v for s, v in by_seed.items() if s in seeds} for t, by_seed in training.items()}
    first_evaluation = [r for r in evaluation if int(r["seed"]) in seeds]
    first = _judge(config, first_training, first_evaluation, None)
    return dataclasses.replace(found, first_repeats=first.claims)


def _judge(config: ExperimentConfig, training: Training, evaluation: Rows, wall_seconds: float | None):
    summaries = {t.name: s for t in config.trials if (s := summarize_trial(training, t))}
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
