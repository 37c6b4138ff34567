"""Reproduce an experiment: its configuration with overrides, the run, the figures and a summary.

What ``pipefollow reproduce`` does once its options are read (:func:`reproduce`): load the
experiment (a shipped one or a TOML file) with the overrides of the command line, run it in its run
folder (:func:`~pipefollow.experiments.runner.run_experiment`), draw the figures and REPORT.md
(:func:`write_figures`) and summarise it (:func:`summary`, :func:`summary_text`).
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from pipefollow.experiments.config import ExperimentConfig
from pipefollow.experiments.runner import RunSummary

QUICK_REPEATS = 2  # repeats of a quick (smoke-test) reproduction
QUICK_EPISODES = 30  # episodes of every training phase of a quick reproduction


class ReportMissing(RuntimeError):
    """Figures were asked for, but :mod:`pipefollow.experiments.report` is not available."""


def note_on_stderr(text: str) -> None:
    """Print a note for the user on stderr (the default ``note`` of :func:`reproduce`)."""
    print(text, file=sys.stderr, flush=True)


def write_figures(
    run_dir: Path, required: bool, results=None, note: Callable[[str], None] = note_on_stderr
) -> list[Path]:
    """Figures and REPORT.md through ``pipefollow.experiments.report``, if that module exists.

    Args:
        run_dir: the run folder.
        required: raise :class:`ReportMissing` without the module (else ``note`` it and skip).
        results: the run's trial results in memory (``RunSummary.results``), or None to read them.
        note: receives the line saying that the figures were skipped.
    """
    try:
        from pipefollow.experiments import report
    except ModuleNotFoundError as e:
        if e.name != "pipefollow.experiments.report":
            raise
        if required:
            raise ReportMissing("figures need pipefollow.experiments.report, which is missing") from None
        note("note: figures skipped (pipefollow.experiments.report is not available)")
        return []
    return [Path(p) for p in report.write_outputs(run_dir, results)]


def preload_figures() -> None:
    """While the trials run: import what the figures need (``report.preload``), if that module exists."""
    try:
        from pipefollow.experiments import report
    except ModuleNotFoundError:
        return
    report.preload()


def configure(
    experiment: str = "paper",
    *,
    repeats: int | None = None,
    episodes: int | None = None,
    seed: int | None = None,
    trials: Sequence[str] = (),
    readings: Sequence[str] = (),
    quick: bool = False,
) -> tuple[str, ExperimentConfig]:
    """The name of ``experiment`` as shipped or loaded, and the experiment to run with the overrides.

    ``quick`` sets :data:`QUICK_REPEATS` and :data:`QUICK_EPISODES` where ``repeats`` and
    ``episodes`` are None; a study of the readings is expanded into its trials.
    """
    from pipefollow.experiments import sensitivity
    from pipefollow.experiments.config import load_experiment, with_overrides

    if quick:
        repeats = QUICK_REPEATS if repeats is None else repeats
        episodes = QUICK_EPISODES if episodes is None else episodes
    base = load_experiment(experiment)
    exp = with_overrides(
        base, repeats=repeats, episodes=episodes, seed=seed, trials=list(trials), readings=list(readings)
    )
    return base.name, sensitivity.expand(exp)


def default_run_dir(name: str, quick: bool = False) -> str:
    """``reproduction`` for the paper, ``reproduction-NAME`` for experiment NAME; ``-quick`` appended."""
    stem = "reproduction" if name == "paper" else f"reproduction-{name}"
    return f"{stem}-quick" if quick else stem


@dataclass(frozen=True)
class Reproduction:
    """A finished reproduction: the experiment run, what the run did, the files written."""

    exp: ExperimentConfig
    run: RunSummary
    outputs: tuple[Path, ...]


def reproduce(
    experiment: str = "paper",
    out_dir: str | Path | None = None,
    *,
    overrides: dict | None = None,
    quick: bool = False,
    figures: bool = True,
    note: Callable[[str], None] = note_on_stderr,
    **run_options,
) -> Reproduction:
    """Run ``experiment`` (overridden as :func:`configure` says) in its run folder, then draw its figures.

    Args:
        experiment: a shipped experiment's name or an experiment TOML file.
        out_dir: the run folder (default: :func:`default_run_dir`); the same options resume there.
        overrides: ``repeats``, ``episodes``, ``seed``, ``trials`` and ``readings`` of :func:`configure`.
        quick: a small smoke-test version (:data:`QUICK_REPEATS`, :data:`QUICK_EPISODES`).
        figures: draw the figures and REPORT.md (and import what they need while the trials run).
        note: receives the lines for the user that are not results (figures skipped, read-only).
        **run_options: ``backend``, ``workers``, ``ray_address``, ``show_progress`` and
            ``progress_bar`` of :func:`~pipefollow.experiments.runner.run_experiment`.

    Raises:
        RunInterrupted: on Ctrl-C; what was saved stays, and running the same call again resumes.
    """
    from pipefollow.experiments.runner import run_experiment

    name, exp = configure(experiment, quick=quick, **(overrides or {}))
    out = Path(out_dir or default_run_dir(name, quick))
    run = run_experiment(exp, out, while_waiting=preload_figures if figures else None, **run_options)
    outputs = list(run.tables)
    if run.read_only:
        note(f"note: '{run.run_dir}' is complete and read-only: summarised, nothing written")
    elif figures:
        outputs += write_figures(run.run_dir, required=False, results=run.results, note=note)
    return Reproduction(exp, run, tuple(outputs))


def summary(rep: Reproduction) -> dict:
    """The reproduction as one JSON object: the run, the files written and every trial's summary."""
    from pipefollow.experiments.tables import summary as trial_summary

    run = rep.run
    return {
        "run_dir": str(run.run_dir),
        "backend": run.backend,
        "workers": run.workers,
        "trials_total": run.trials_total,
        "trials_computed": run.trials_computed,
        "trials_reused": run.trials_reused,
        "wall_seconds": run.wall_seconds,
        "outputs": [str(p) for p in rep.outputs],
        "trials": trial_summary(run.run_dir, rep.exp, results=run.results or None),
    }


def summary_text(rep: Reproduction) -> str:
    """The reproduction in lines: the run, a table of the trials (or the claims' verdicts), the files."""
    run, exp = rep.run, rep.exp
    lines = [
        f"{exp.name}: {run.trials_total} trials ({run.trials_computed} computed, {run.trials_reused} "
        f"reused) in {run.wall_seconds:.1f} s, backend {run.backend} "
        f"({run.workers} worker{'s' if run.workers != 1 else ''})"
    ]
    lines += _verdicts(rep) if exp.compare_readings else _trial_table(rep)
    lines += [f"wrote {p}" for p in rep.outputs]
    return "\n".join(lines)


def _trial_table(rep: Reproduction) -> list[str]:
    """Every trial's mean return and pipe in view over the last 50 episodes, and its evaluations."""
    from pipefollow.experiments.tables import summary as trial_summary

    per_trial = trial_summary(rep.run.run_dir, rep.exp, results=rep.run.results or None)
    width = max(len(r["label"]) for r in per_trial.values()) if per_trial else 5
    lines = [f"{'trial':<{width}}  {'return, last 50 (mean ± sd over seeds)':>38}  {'in view':>7}"]
    for row in per_trial.values():
        ret = f"{row['mean_return_last50']:.2f} ± {row['std_return_last50']:.2f}"
        lines.append(f"{row['label']:<{width}}  {ret:>38}  {row['mean_pipe_in_view_last50']:>7.1%}")
    for name, row in per_trial.items():
        if rep.exp.trial(name).evaluate_on:
            evals = ", ".join(f"{c} {v:.2f}" for c, v in row["evaluation_mean_return"].items())
            lines.append(f"{row['label']} on {row['evaluation_pipeline']} (mean return): {evals}")
    return lines


def _verdicts(rep: Reproduction) -> list[str]:
    """The per-claim lines of a study of the readings."""
    from pipefollow.experiments import sensitivity

    table = rep.run.run_dir / sensitivity.READINGS_CSV
    # the table this run just wrote holds every verdict; without figures compute them
    s = sensitivity.read_csv(table) if table in rep.outputs else sensitivity.load(rep.run.run_dir)
    return [f"claim {claim}: {s.verdict_line(claim)}" for claim in s.claim_ids()]
