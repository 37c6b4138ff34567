"""The reproduction report: figures and ``REPORT.md`` computed from a run folder's stored results.

:func:`write_outputs` reads a run folder (``config.json``, ``results.csv``, ``evaluation.csv`` and,
for the trajectories and run time, ``trials/``), computes the findings
(:func:`pipefollow.experiments.findings.compute_findings`), renders them as markdown
(:func:`render_markdown`) and draws the paper's Figs. 5–7 and the validation trajectories. An
experiment that compares readings (``compare_readings``) gets the sensitivity report of
:mod:`pipefollow.experiments.sensitivity` instead.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from pipefollow.experiments import figures
from pipefollow.experiments.claims import Table1
from pipefollow.experiments.config import ExperimentConfig, TrialConfig, from_dict
from pipefollow.experiments.findings import Findings, compute_findings
from pipefollow.experiments.report_text import (
    FIGURES,
    REPORT_MD,
    TRAJECTORIES_PNG,
    render_markdown,
)
from pipefollow.experiments.summary import (
    Evaluation,
    PhaseSeries,
    Rows,
    Training,
    learning_curves,
    read_rows,
    read_training,
)
from pipefollow.sim.episode import STAT_IN_VIEW, STAT_PROGRESS, STAT_RETURN

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


def preload() -> None:
    """Import what drawing needs (Matplotlib's figure and Agg canvas, ≈ 0.5 s of CPU) ahead of drawing.

    ``pipefollow reproduce`` calls it while the trials run in worker processes, where the import
    shares the cores instead of adding to the wall time after the trials. Without Matplotlib it
    does nothing (drawing then reports the missing package).
    """
    try:
        import matplotlib.backends.backend_agg  # noqa: F401
        import matplotlib.figure  # noqa: F401
    except ImportError:
        pass


def training_of(config: ExperimentConfig, results: Mapping[tuple[str, int], object]) -> Training:
    """The learning curves that ``results.csv`` holds, from the trial results themselves.

    ``results`` maps (trial, seed) to a :class:`~pipefollow.experiments.trial.TrialResult`; the
    series equal :func:`~pipefollow.experiments.summary.read_training` of the table written from
    them (floats round-trip through the CSV exactly).
    """
    out: dict[str, dict[int, list[PhaseSeries]]] = {}
    for t in config.trials:
        for seed in config.seeds():
            r = results.get((t.name, seed))
            if r is None:
                continue
            phase = np.asarray(r.phase)
            out.setdefault(t.name, {})[seed] = [
                PhaseSeries(
                    t.phases[ph].pipeline,
                    np.array(r.stats[phase == ph, STAT_RETURN], dtype=np.float64),
                    np.array(r.stats[phase == ph, STAT_IN_VIEW], dtype=np.float64),
                    np.array(r.stats[phase == ph, STAT_PROGRESS], dtype=np.float64),
                )
                for ph in dict.fromkeys(phase.tolist())
            ]
    return out


def write_outputs(run_dir: str | Path, results: Mapping[tuple[str, int], object] | None = None) -> list[Path]:
    """Draw the figures and write REPORT.md into a run folder.

    Args:
        run_dir: the run folder (``config.json``, ``results.csv``, ``evaluation.csv``, ``trials/``).
        results: every stored trial by (trial, seed) (:func:`pipefollow.experiments.store.stored_results`,
            a run's :attr:`~pipefollow.experiments.runner.RunSummary.results`), to save reading
            ``results.csv`` and the trial files again; None reads them.

    Returns:
        Paths written: fig5/6/7.png for the figure groups with results, validation-trajectories.png
        if a table1 trial was evaluated and its trial file can be read, and REPORT.md (last).
    """
    from pipefollow.files.atomic import write_text_atomic

    run_dir = Path(run_dir)
    stored = json.loads((run_dir / "config.json").read_text())
    config = from_dict(stored)
    load = _load_trial
    if results is not None:
        known = results

        def load(run_dir: Path, trial: str, seed: int):
            return known[trial, seed] if (trial, seed) in known else _load_trial(run_dir, trial, seed)

    if config.compare_readings:
        from pipefollow.experiments import sensitivity

        return sensitivity.write_outputs(run_dir, _wall_seconds(run_dir, config, load))
    training = read_training(run_dir / "results.csv") if results is None else training_of(config, results)
    evaluation = read_rows(run_dir / "evaluation.csv")
    findings = compute_findings(config, training, evaluation, _wall_seconds(run_dir, config, load))
    findings = dataclasses.replace(findings, machine=stored.get("machine"))
    drawn = draw_learning_curves(run_dir, config, training, findings.evaluations)
    trajectories = None
    if findings.table1 is not None:
        try:
            trajectories = draw_trajectories(run_dir, findings.table1, load)
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
    return dataclasses.replace(findings, notes=(*findings.notes, note))
