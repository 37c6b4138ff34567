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
from pipefollow.files.paper_training import TRAINING_EPISODES


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
    help=f"Episodes of every training phase [default: the experiment's, {TRAINING_EPISODES} for the paper].",
)
@click.option(
    "--seed", type=SEED, default=None, help="Seed of the first repeat [default: 2010 for the paper]."
)
@click.option(
    "--experiment",
    default="paper",
    show_default=True,
    help="A shipped experiment ('paper'; 'repeats': the paper's trials over 30 repeats beside the first 5; "
    "'readings': the claims under each reading of the paper's open points; 'reference-learners': CACLA "
    "beside the actor-critic of eq. 9) or an experiment TOML file.",
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
    from pipefollow.experiments import reproduction
    from pipefollow.experiments.runner import RunInterrupted

    try:
        rep = reproduction.reproduce(
            experiment, out_dir,
            overrides=dict(repeats=repeats, episodes=episodes, seed=seed, trials=trials, readings=readings),
            quick=quick, figures=not no_figures, note=_note, backend=backend, workers=workers,
            ray_address=ray_address, show_progress=not as_json, progress_bar=click.progressbar,
        )  # fmt: skip
    except RunInterrupted as e:
        click.echo(f"pipefollow: {e.message}", err=True)
        sys.exit(130)
    if as_json:
        click.echo(json.dumps(reproduction.summary(rep)))
    else:
        click.echo(reproduction.summary_text(rep))


def _note(text: str) -> None:
    click.echo(text, err=True)


@click.command()
@click.argument("run_dir", type=click.Path(file_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object: the files written.")
@guard
def plot(run_dir, as_json):
    """Redraw all figures and REPORT.md of a run folder from its stored results."""
    from pipefollow.experiments.reproduction import ReportMissing, write_figures
    from pipefollow.experiments.store import read_config

    read_config(run_dir)  # a one-line error if RUN_DIR is not a run folder
    try:
        outputs = write_figures(Path(run_dir), required=True)
    except ReportMissing as e:
        raise click.ClickException(str(e)) from None
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
    help="A shipped experiment ('paper', 'repeats', 'readings', 'reference-learners') or an experiment "
    "TOML file.",
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
