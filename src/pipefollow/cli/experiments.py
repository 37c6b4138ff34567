"""``pipefollow reproduce``, ``plot`` and ``trials``: experiments and their run folders."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from pipefollow.cli.common import (
    SEED,
    guard,
)
from pipefollow.cli.options import (
    reading_option,
)


def _write_figures(run_dir: Path, required: bool, results=None) -> list[Path]:
    """Figures and REPORT.md through ``pipefollow.experiments.report``, if that module exists.

    ``results``: the run's trial results in memory (``RunSummary.results``), or None to read them.
    """
    try:
        from pipefollow.experiments import report
    except ModuleNotFoundError as e:
        if e.name != "pipefollow.experiments.report":
            raise
        if required:
            raise click.ClickException(
                "figures need pipefollow.experiments.report, which is missing"
            ) from None
        click.echo("note: figures skipped (pipefollow.experiments.report is not available)", err=True)
        return []
    return [Path(p) for p in report.write_outputs(run_dir, results)]


def _preload_figures() -> None:
    """While the trials run: import what the figures need (``report.preload``), if that module exists."""
    try:
        from pipefollow.experiments import report
    except ModuleNotFoundError:
        return
    report.preload()


@click.command()
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False),
    default=None,
    help="Run folder; running again with the same options resumes. [default: ./reproduction for the "
    "paper, ./reproduction-NAME for experiment NAME; with --quick, -quick appended]",
)
@click.option(
    "--backend",
    default="process",
    show_default=True,
    metavar="serial|process|ray",
    help="Where trials run: in this process, in a local process pool, or on Ray.",
)
@click.option(
    "--workers",
    type=click.IntRange(min=1),
    default=None,
    help="Trials at the same time [default: all cores].",
)
@click.option(
    "--ray-address", default=None, help="Address of a running Ray cluster [default: a local instance]."
)
@click.option(
    "--repeats",
    type=click.IntRange(min=1),
    default=None,
    help="Repeats (seeds) of every trial [default: the experiment's, 5 for the paper].",
)
@click.option(
    "--episodes",
    type=click.IntRange(min=1),
    default=None,
    help="Episodes of every training phase [default: the experiment's, 500 for the paper].",
)
@click.option(
    "--seed", type=SEED, default=None, help="Seed of the first repeat [default: 2010 for the paper]."
)
@click.option(
    "--experiment",
    default="paper",
    show_default=True,
    help="A shipped experiment ('paper'; 'readings': the claims under each reading of the paper's open "
    "points; 'reference-learners': CACLA beside the actor-critic of eq. 9) or an experiment TOML file.",
)
@click.option(
    "--trial",
    "trials",
    multiple=True,
    metavar="NAME",
    help="Run only this trial (repeatable) [default: all].",
)
@click.option(
    "--quick",
    is_flag=True,
    help="Small smoke-test version: 2 repeats, 30 episodes per phase, --out ./reproduction-quick.",
)
@reading_option("Reading of an open point applied to every trial, e.g. start_speed=cruise (repeatable).")
@click.option("--no-figures", is_flag=True, help="Do not draw figures and REPORT.md.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object at the end.")
@guard
def reproduce(
    out_dir,
    backend,
    workers,
    ray_address,
    repeats,
    episodes,
    seed,
    experiment,
    trials,
    quick,
    readings,
    no_figures,
    as_json,
):
    """Reproduce the paper's experiments: train every trial × seed, store results, draw the figures.

    The run folder holds config.json, one file per finished trial (trials/), the learned policies
    (policies/), results.csv and evaluation.csv (tidy tables for pandas), and the figures and
    REPORT.md. An interrupted run resumes where it stopped when started again with the same options.
    """
    from pipefollow.experiments import sensitivity
    from pipefollow.experiments.config import load_experiment, with_overrides
    from pipefollow.experiments.runner import RunInterrupted, run_experiment
    from pipefollow.experiments.store import summary

    if quick:
        repeats = 2 if repeats is None else repeats
        episodes = 30 if episodes is None else episodes
    base = load_experiment(experiment)
    exp = with_overrides(
        base, repeats=repeats, episodes=episodes, seed=seed, trials=list(trials), readings=list(readings)
    )
    exp = sensitivity.expand(exp)
    if not out_dir:
        stem = "reproduction" if base.name == "paper" else f"reproduction-{base.name}"
        out_dir = f"{stem}-quick" if quick else stem
    out = Path(out_dir)
    try:
        run = run_experiment(
            exp,
            out,
            backend=backend,
            workers=workers,
            ray_address=ray_address,
            show_progress=not as_json,
            while_waiting=None if no_figures else _preload_figures,
        )
    except RunInterrupted as e:
        click.echo(f"pipefollow: {e.message}", err=True)
        sys.exit(130)
    outputs = list(run.tables)
    if run.read_only:
        click.echo(f"note: '{run.run_dir}' is complete and read-only: summarised, nothing written", err=True)
    elif not no_figures:
        outputs += _write_figures(run.run_dir, required=False, results=run.results)
    if as_json:
        click.echo(
            json.dumps(
                {
                    "run_dir": str(run.run_dir),
                    "backend": run.backend,
                    "workers": run.workers,
                    "trials_total": run.trials_total,
                    "trials_computed": run.trials_computed,
                    "trials_reused": run.trials_reused,
                    "wall_seconds": run.wall_seconds,
                    "outputs": [str(p) for p in outputs],
                    "trials": summary(run.run_dir, exp, results=run.results or None),
                }
            )
        )
        return
    click.echo(
        f"{exp.name}: {run.trials_total} trials ({run.trials_computed} computed, {run.trials_reused} reused) "
        f"in {run.wall_seconds:.1f} s, backend {run.backend} "
        f"({run.workers} worker{'s' if run.workers != 1 else ''})"
    )
    if exp.compare_readings:
        _echo_sensitivity(run.run_dir, outputs)
        return
    per_trial = summary(run.run_dir, exp, results=run.results or None)
    width = max(len(r["label"]) for r in per_trial.values()) if per_trial else 5
    click.echo(f"{'trial':<{width}}  {'return, last 50 (mean ± sd over seeds)':>38}  {'in view':>7}")
    for row in per_trial.values():
        ret = f"{row['mean_return_last50']:.2f} ± {row['std_return_last50']:.2f}"
        click.echo(f"{row['label']:<{width}}  {ret:>38}  {row['mean_pipe_in_view_last50']:>7.1%}")
    for name, row in per_trial.items():
        if exp.trial(name).evaluate_on:
            evals = ", ".join(f"{c} {v:.2f}" for c, v in row["evaluation_mean_return"].items())
            click.echo(f"{row['label']} on {row['evaluation_pipeline']} (mean return): {evals}")
    for p in outputs:
        click.echo(f"wrote {p}")


def _echo_sensitivity(run_dir: Path, outputs: list[Path]) -> None:
    """The per-claim lines of a sensitivity study."""
    from pipefollow.experiments import sensitivity

    table = run_dir / sensitivity.READINGS_CSV
    # the table this run just wrote holds every verdict; without it (--no-figures) compute them
    s = sensitivity.read_csv(table) if table in outputs else sensitivity.load(run_dir)
    for claim in s.claim_ids():
        click.echo(f"claim {claim}: {s.verdict_line(claim)}")
    for p in outputs:
        click.echo(f"wrote {p}")


@click.command()
@click.argument("run_dir", type=click.Path(file_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object: the files written.")
@guard
def plot(run_dir, as_json):
    """Redraw all figures and REPORT.md of a run folder from its stored results."""
    from pipefollow.experiments.store import read_config

    read_config(run_dir)  # a one-line error if RUN_DIR is not a run folder
    outputs = _write_figures(Path(run_dir), required=True)
    if as_json:
        click.echo(json.dumps({"run_dir": str(run_dir), "outputs": [str(p) for p in outputs]}))
        return
    for p in outputs:
        click.echo(f"wrote {p}")


@click.command()
@click.option(
    "--experiment",
    default="paper",
    show_default=True,
    help="A shipped experiment ('paper', 'readings', 'reference-learners') or an experiment TOML file.",
)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON list instead of a table.")
@guard
def trials(experiment, as_json):
    """List the trials of an experiment.

    Their names (for --trial), labels, learners, options and episodes.
    """
    from pipefollow.cli.tables import table
    from pipefollow.cli.tables import trials as rows_of
    from pipefollow.experiments.config import load_experiment

    exp = load_experiment(experiment)
    rows = rows_of(exp)
    if as_json:
        click.echo(json.dumps(rows, ensure_ascii=False))
        return
    click.echo(f"{exp.name}: {len(rows)} trials, {exp.repeats} repeats each (seeds from {exp.seed})")
    columns = [("name", "name"), ("label", "label"), ("algorithm", "algorithm"), ("options", "options")]
    click.echo(table(rows, [*columns, ("episodes", "episodes"), ("phases", "phases")]))
