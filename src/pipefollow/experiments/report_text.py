"""The reproduction report's text: the findings of a run rendered as ``REPORT.md`` markdown.

:func:`render_markdown` turns the :class:`~pipefollow.experiments.findings.Findings` of a run (and
the figures drawn for it) into the report; :mod:`pipefollow.experiments.report` reads the run
folder, draws the figures and writes the file.
"""

from __future__ import annotations

from collections.abc import Mapping

from pipefollow.experiments.claims import (
    NOT_CONFIRMED,
    NOT_TESTED,
    PAPER_EPISODES,
    PAPER_REPEATS,
    PAPER_TABLE1,
    Part,
    paper_improvement_pct,
    pm,
)
from pipefollow.experiments.config import load_experiment
from pipefollow.experiments.findings import Findings
from pipefollow.experiments.summary import (
    CONVERGE_EPISODES,
    CONVERGE_PIPELINE,
    EARLY_EPISODES,
)
from pipefollow.files.machine import describe as describe_machine
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
    if f.machine:
        lines.append(f"Started on {describe_machine(f.machine)}.")
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
            margin = f" Margin: {p.margin}." if p.margin else ""
            lines += [f"- {tag}*{p.statement}.* Ours: {p.ours}.{margin} **Verdict: {p.verdict}.**"]
        lines.append("")
    return lines


def _part_cell(p: Part) -> str:
    count = f" ({p.passed}/{p.total})" if p.total else ""
    return f"{p.verdict}{count}" + (f"; {p.margin}" if p.margin else "")


def _firmness_lines(f: Findings) -> list[str]:
    """Each part's verdict over the paper's 5 repeats beside its verdict over all of this run's."""
    if f.first_repeats is None:
        return [
            "## How firm the verdicts are",
            "",
            f"Each verdict above rests on this run's {f.config.repeats} repeats, and its margin says how "
            "near the rule's threshold it lies. `pipefollow reproduce --experiment repeats` judges the same "
            f"claims over {load_experiment('repeats').repeats} repeats, with the first "
            f"{PAPER_REPEATS} repeats' verdicts beside them.",
            "",
        ]
    seeds = f.config.seeds()
    lines = [
        "## How firm the verdicts are",
        "",
        f"Each part judged on the paper's {PAPER_REPEATS} repeats (this run's first seeds, "
        f"{seeds[0]}–{seeds[PAPER_REPEATS - 1]}, which `pipefollow reproduce` runs) and on all "
        f"{len(seeds)} repeats (seeds {seeds[0]}–{seeds[-1]}). In brackets, the cases in which the "
        "statement held (repeats, or paired repeats for a skew comparison); then the margin of the "
        "deciding number from the rule's threshold.",
        "",
        f"| claim | part | {PAPER_REPEATS} repeats: verdict; margin | {len(seeds)} repeats: verdict; margin "
        "| firm |",
        "|---|---|---|---|---|",
    ]
    few_parts = {(c.number, i): p for c in f.first_repeats for i, p in enumerate(c.parts)}
    for c_all in f.claims:
        for i, full in enumerate(c_all.parts):
            # a part the first repeats cannot judge (no results of theirs for a phase) is not tested there
            few = few_parts.get((c_all.number, i), Part(full.statement, "", NOT_TESTED))
            firm = "yes" if few.verdict == full.verdict else "**no**"
            if full.verdict == NOT_TESTED:
                firm = "—"
            lines.append(
                f"| {c_all.number}{chr(ord('a') + i)} ({c_all.source}) | {full.statement} "
                f"| {_part_cell(few)} | {_part_cell(full)} | {firm} |"
            )
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
        lines += _firmness_lines(findings)
    lines += _table1_lines(findings, trajectories)
    lines += _figure_lines(figures_drawn or {})
    lines += _differences_lines(findings)
    lines += list(findings.notes)
    return "\n".join(lines).rstrip() + "\n"
