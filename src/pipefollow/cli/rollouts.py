"""``pipefollow rollouts``: a controller's episodes on a suite, as a Minari dataset."""

from __future__ import annotations

import json
import re

import click

from pipefollow.cli.common import (
    SEED,
    UserError,
    complete_suite,
    controller_options,
    disturbance_options,
    finite,
    guard,
    load_controller,
    writable_folder,
)


@click.command()
@controller_options
@click.option(
    "--suite",
    "suite_specs",
    multiple=True,
    metavar="SUITE|PATH",
    shell_complete=complete_suite,
    help="A suite (see 'pipefollow suites'), or pipeline JSON files: folders, files, glob patterns "
    "(repeatable) [default: heldout].",
)
@click.option(
    "--pipes",
    type=click.IntRange(min=1, max=100_000),
    default=None,
    help="Number of pipes, one episode each [default: all of a held-out suite or folder, 100 of a family].",
)
@click.option(
    "--seconds",
    type=click.FloatRange(min=1.0, max=86_400.0),
    callback=finite,
    default=60.0,
    show_default=True,
    help="Episode length in seconds.",
)
@click.option(
    "--sigma",
    type=click.FloatRange(min=0.0, max=1.0),
    callback=finite,
    default=0.0,
    show_default=True,
    help="Exploration σ of a learned policy (0: deterministic episodes).",
)
@click.option(
    "--seed", default=0, show_default=True, type=SEED, help="Seed of episode k's environment: SEED + k."
)
@click.option(
    "--out", "out_dir", type=click.Path(file_okay=False), required=True, help="Folder for the dataset."
)
@click.option(
    "--name",
    "dataset_id",
    default=None,
    help="Minari dataset id, namespace/name-vN [default: pipefollow/SUITE-CONTROLLER-v0].",
)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object: the dataset's id and folder.")
@disturbance_options
@guard
def rollouts(controller, lookahead, suite_specs, pipes, seconds, sigma, seed, out_dir, dataset_id, as_json,
             disturbance):  # fmt: skip
    """Write a controller's episodes on a suite as a Minari dataset (offline RL, behaviour cloning).

    Observations, actions, rewards and the infos of every step, one episode per pipe; needs the
    optional extra 'rollouts'. Read it back with minari.load_dataset(ID) and MINARI_DATASETS_PATH=OUT.
    """
    from pathlib import Path

    from pipefollow.evaluation.rollouts import RolloutsExtraMissing, record_rollouts
    from pipefollow.readings import parse, sim_params
    from pipefollow.sim.pipe_names import resolve_suite
    from pipefollow.sim.suites import min_length_for

    suite = resolve_suite(suite_specs or ["heldout"])
    n = pipes if pipes is not None else (suite.count or 100)
    if suite.count is not None and n > suite.count:
        raise UserError(f"--pipes {n}: suite '{suite.name}' has {suite.count} pipes")
    agent = load_controller(controller, seed, lookahead)
    name = re.sub(r"[^a-z0-9-]+", "-", Path(controller).stem.lower()).strip("-") or "controller"
    dataset_id = dataset_id or f"pipefollow/{suite.name}-{name}-v0"
    if not re.fullmatch(r"([\w-]+/)?[\w.-]+-v\d+", dataset_id):
        raise UserError(f"--name '{dataset_id}': a Minari id is namespace/name-vN, e.g. pipefollow/mine-v0")
    folder = writable_folder(out_dir, "--out")
    if (folder / dataset_id).exists():
        raise UserError(f"--out '{out_dir}' already holds the dataset {dataset_id}; give another --name")
    params = sim_params(parse(getattr(agent, "readings", "default")))._replace(disturbance=disturbance)
    try:
        path = record_rollouts(
            agent, suite.pipes(n, min_length_for(seconds)), folder, dataset_id,
            seconds=seconds, params=params, sigma=sigma, seed=seed,
        )  # fmt: skip
    except RolloutsExtraMissing as e:
        raise UserError(str(e)) from None
    if as_json:
        click.echo(json.dumps({"dataset_id": dataset_id, "folder": str(path), "episodes": n}))
        return
    click.echo(f"wrote {n} episodes of {controller} on '{suite.name}' as {dataset_id} to {path}")
