"""``pipefollow rollouts``: a controller's episodes on a suite, as a Minari dataset."""

from __future__ import annotations

import re

import click

from pipefollow.cli.common import (
    UserError,
    camera_record,
    camera_text,
    echo_result,
    finite,
    guard,
    load_controller,
    pipe_count,
    writable_folder,
)
from pipefollow.cli.options import (
    camera_options,
    controller_options,
    disturbance_options,
    json_option,
    out_option,
    pipes_option,
    seconds_option,
    seed_option,
    suite_option,
)


@click.command()
@controller_options
@suite_option()
@pipes_option(
    "Number of pipes, one episode each [default: all of a held-out suite or folder, 100 of a family]."
)
@seconds_option()
@click.option(
    "--sigma",
    type=click.FloatRange(min=0.0, max=1.0),
    callback=finite,
    default=0.0,
    show_default=True,
    help="Exploration σ of a learned policy (0: deterministic episodes).",
)
@seed_option("Seed of episode k's environment: SEED + k.")
@out_option("Folder for the dataset.")
@click.option(
    "--name",
    "dataset_id",
    default=None,
    help="Minari dataset id, namespace/name-vN [default: pipefollow/SUITE-CONTROLLER-v0].",
)
@json_option("Print one JSON object: the dataset's id and folder.")
@disturbance_options
@camera_options
@guard
def rollouts(controller, lookahead, suite_specs, pipes, seconds, sigma, seed, out_dir, dataset_id, as_json,
             disturbance, camera):  # fmt: skip
    """Write a controller's episodes on a suite as a Minari dataset (offline RL, behaviour cloning).

    Observations, actions, rewards and the infos of every step, one episode per pipe; needs the
    optional extra 'rollouts'. Read it back with minari.load_dataset(ID) and MINARI_DATASETS_PATH=OUT.
    With --camera vision (or a --sensor sonar) the controller observes through that camera or
    sensor and water, and the dataset's environment is that one.
    """
    from pathlib import Path

    from pipefollow.evaluation.rollouts import RolloutsExtraMissing, record_rollouts
    from pipefollow.readings import parse, sim_params
    from pipefollow.sim.pipe_names import resolve_suite
    from pipefollow.sim.suites import min_length_for

    suite = resolve_suite(suite_specs or ["heldout"])
    n = pipe_count(suite, pipes)
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
            seconds=seconds, params=params, sigma=sigma, seed=seed, camera=camera,
        )  # fmt: skip
    except RolloutsExtraMissing as e:
        raise UserError(str(e)) from None
    echo_result(
        {"dataset_id": dataset_id, "folder": str(path), "episodes": n, **camera_record(camera)}, as_json,
        lambda: f"wrote {n} episodes of {controller} on '{suite.name}' as {dataset_id} to {path}"
        + camera_text(camera),
    )  # fmt: skip
