"""The reproduction report: figures and ``REPORT.md`` computed from a run folder's stored results.

:func:`write_outputs` reads a run folder (``config.json``, ``results.csv``, ``evaluation.csv`` and,
for the trajectories and run time, ``trials/``), computes the findings
(:func:`pipefollow.experiments.claims.compute_findings`), renders them as markdown
(:func:`render_markdown`) and draws the paper's Figs. 5–7 and the validation trajectories. An
experiment that compares readings (``compare_readings``) gets the sensitivity report of
:mod:`pipefollow.experiments.sensitivity` instead.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from pipefollow.experiments import figures
from pipefollow.experiments.claims import (
    NOT_CONFIRMED,
    NOT_TESTED,
    PAPER_EPISODES,
    PAPER_REPEATS,
    PAPER_TABLE1,
    Findings,
    Table1,
    compute_findings,
    paper_improvement_pct,
    pm,
)
from pipefollow.experiments.config import ExperimentConfig, TrialConfig, from_dict
from pipefollow.experiments.summary import (
    CONVERGE_EPISODES,
    CONVERGE_PIPELINE,
    EARLY_EPISODES,
    Evaluation,
    Rows,
    Training,
    learning_curves,
    read_rows,
    read_training,
)
from pipefollow.learners.registry import learner as learner_of_name

FIGURES = {
    "fig5": "Fig. 5: SARSA versus CACLA and supervised CACLA",
    "fig6": "Fig. 6: tabula rasa CACLA with varying skew",
    "fig7": "Fig. 7: supervised CACLA with varying skew",
}
TRAJECTORIES_PNG = "validation-trajectories.png"
REPORT_MD = "REPORT.md"


# ---------------------------------------------------------------------------------------------
# Markdown


def _turns_text() -> str:
    from pipefollow.sim.pipeline import builtin

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
        learner = ("supervised " if t.supervised else "") + learner_of_name(t.algorithm).title
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


def _readings_lines(f: Findings) -> list[str]:
    ids = {t.reading.id for t in f.config.trials}
    if ids == {"default"}:
        used = "every trial runs under the default readings"
    elif len(ids) == 1:
        used = f"every trial runs under the readings `{ids.pop()}` (the others at their defaults)"
    else:
        used = "the trials run under these readings: " + "; ".join(
            f"`{t.name}`: `{t.reading.id}`" for t in f.config.trials
        )
    return [
        "## Readings",
        "",
        f"Where the paper can be read in more than one way, the project names each way a *reading* "
        f"(docs/design.md); {used}. Among them, eq. 15 moves γ(s) itself by Δγ (`skew_step=gamma`) and "
        "the skew-normal sample keeps A(s) as its location (`skew_sample=location`). How each claim "
        "depends on the readings is the subject of the `readings` experiment "
        "(`pipefollow reproduce --experiment readings`).",
        "",
    ]


def _convergence_lines(f: Findings) -> list[str]:
    shortest = min((s.episodes for ss in f.summaries.values() for s in ss), default=0)
    rules = sorted({(t.reading.converge_in_view, t.reading.converge_progress_m) for t in f.config.trials})
    view, progress = rules[0] if len(rules) == 1 else (None, None)
    view_text = f"{view * 100:g} %" if view is not None else "a trial's `converge_in_view` reading"
    progress_text = f"{progress:g} m" if progress is not None else "its `converge_progress_m` reading"
    lines = [
        "## Convergence to a pipe-tracking policy",
        "",
        f"A repeat has *converged* when, over the last {CONVERGE_EPISODES} training episodes of a phase, the "
        f"pipe was in view at the end of at least {view_text} of the decisions on average and the mean "
        f"progress along the pipe was at least {progress_text}."
        + (
            f" On `{CONVERGE_PIPELINE}` (turns at {_turns_text()} of arc length) 4 m is past the first "
            "turn, with the second in the camera's 3 m view."
            if any(t.phases[0].pipeline == CONVERGE_PIPELINE for t in f.config.trials)
            else ""
        )
        + (" Claims 1–3 judge each trial's first phase." if _tests_claims(f) else ""),
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
                f"`{ev.pipeline}` | {pm(ev.of('learned'))} | {pm(ev.of('heuristic'))}"
                if ev is not None and last
                else "— | — | —"
            )
            lines.append(
                f"| {s.label} | {s.phase + 1}: `{s.pipeline}` | {s.n_converged}/{s.n} "
                f"| {pm(s.values('last_return'))} | {pm(s.values('first_return'))} "
                f"| {pm(s.values('last_in_view'), 1, 100.0)} | {pm(s.values('last_progress_m'))} "
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
        f"| learned (supervised CACLA, as executed) | {pm(t.learned)} | {PAPER_TABLE1['learned']:.4f} |",
    ]
    if t.actor.size:
        lines.append(f"| its pure actor | {pm(t.actor)} | — |")
    lines += [
        f"| heuristic | {pm(t.heuristic)} | {PAPER_TABLE1['heuristic']:.4f} |",
        f"| learned relative to heuristic | {t.improvement_pct:+.1f} % | {paper_improvement_pct():+.1f} % |",
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
    if not _tests_claims(f):  # a custom experiment is not a reproduction
        return []
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


def _tests_claims(f: Findings) -> bool:
    """Whether the run's trials test any of the paper's claims (a custom experiment may test none)."""
    return any(p.verdict != NOT_TESTED for c in f.claims for p in c.parts)


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
    claims = _tests_claims(findings)
    name = findings.config.name
    if claims:
        verdicts = ", ".join(f"claim {c.number} {c.verdict}" for c in findings.claims)
        head = [
            "# Reproduction report: AUV pipeline following with reinforcement learning",
            "",
            f"Fjerdingen, Kyrkjebø & Transeth (2010), experiment `{name}`. Generated by "
            "`pipefollow.experiments.report` from this run folder's `results.csv` and `evaluation.csv`; "
            "every number is computed from the stored results.",
            "",
            f"Summary: {verdicts}.",
            "",
        ]
    else:
        head = [
            f"# Experiment `{name}`: results",
            "",
            "Generated by `pipefollow.experiments.report` from this run folder's `results.csv` and "
            "`evaluation.csv`; every number is computed from the stored results. Its trials test none of "
            "the claims of Fjerdingen, Kyrkjebø & Transeth (2010), so no verdicts are given.",
            "",
        ]
    lines = head
    lines += _setup_lines(findings)
    lines += _readings_lines(findings)
    lines += _convergence_lines(findings)
    lines += _trial_table_lines(findings)
    if claims:
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
    run_dir: Path, config: ExperimentConfig, results: Rows | Training, evaluations: Mapping[str, Evaluation]
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
    from pipefollow.files.atomic import write_text_atomic

    run_dir = Path(run_dir)
    config = from_dict(json.loads((run_dir / "config.json").read_text()))
    if config.compare_readings:
        from pipefollow.experiments import sensitivity

        return sensitivity.write_outputs(run_dir, _wall_seconds(run_dir, config, _load_trial))
    results = read_training(run_dir / "results.csv")
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
