"""``pipefollow compare``: several learners over their training seeds and a suite of pipes."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pipefollow.cli.common import (
    UserError,
    camera_record,
    camera_text,
    check_plot_path,
    echo_result,
    guard,
    load_controller,
    pipe_count,
)
from pipefollow.cli.options import (
    camera_options,
    disturbance_options,
    json_option,
    pipes_option,
    plot_option,
    seconds_option,
    seed_option,
    suite_option,
)


@click.command()
@click.argument("policies", nargs=-1, required=True, metavar="POLICY...")
@click.option(
    "--label",
    "labels",
    multiple=True,
    help="Learner of each POLICY, in order (repeat once per POLICY); policies with the same label "
    "are runs of one learner [default: the learner and options the policy was trained with].",
)
@suite_option()
@seconds_option()
@pipes_option("Number of pipes [default: all of a held-out suite or folder, 100 of a training family].")
@click.option(
    "--reps",
    type=click.IntRange(min=100, max=1_000_000),
    default=50_000,
    show_default=True,
    help="Bootstrap replicates of the IQM and mean intervals (rliable's default).",
)
@seed_option("Seed of the bootstrap and of the random disturbances.")
@plot_option("Save the intervals and performance profiles as a figure (.png, .svg, .pdf, ...).")
@click.option(
    "--scores",
    "scores_path",
    default=None,
    metavar="FILE.json",
    help="Write the score matrices in rliable's layout: learner → runs × pipes returns, and the pipes.",
)
@json_option()
@disturbance_options
@camera_options
@guard
def compare(policies, labels, suite_specs, seconds, pipes, reps, seed, plot_path, scores_path, as_json,
            disturbance, camera):  # fmt: skip
    """Compare learners over training seeds × pipes: IQM, mean, probability of improvement.

    Every POLICY (a policy file, or heuristic / los) runs one deterministic episode per pipe
    under the readings it was trained with. Policies of one learner (same training options, or
    same --label) are its runs; the intervals are rliable's stratified bootstrap over runs, kept
    per pipe, so they need several training seeds per learner. With --camera vision (or --sensor
    sonar, fused, fls, fused-fls) every policy observes through that camera or sensor and water.
    """
    import numpy as np

    from pipefollow.evaluation.benchmark import run_episodes
    from pipefollow.evaluation.compare import compare as run_compare
    from pipefollow.evaluation.compare import format_summary
    from pipefollow.evaluation.success import summary_of_runs
    from pipefollow.readings import parse, sim_params
    from pipefollow.sim.episode import STAT_RETURN
    from pipefollow.sim.pipe_names import resolve_suite
    from pipefollow.sim.suites import min_length_for

    check_plot_path(plot_path)
    if scores_path is not None and not str(scores_path).lower().endswith(".json"):
        raise UserError(f"--scores '{scores_path}': expected a .json file")
    if labels and len(labels) != len(policies):
        raise UserError(f"--label given {len(labels)} times for {len(policies)} policies (one per policy)")
    suite = resolve_suite(suite_specs or ["heldout"])
    n = pipe_count(suite, pipes)
    agents = [load_controller(p, seed) for p in policies]  # every file checked before any episode
    pipe_list = suite.pipes(n, min_length_for(seconds))
    if not labels:  # the learner and options each policy was trained with
        labels = tuple(getattr(agent, "name", spec) for spec, agent in zip(policies, agents, strict=True))
    rows: dict[str, list] = {}
    stats: dict[str, list] = {}  # every episode's statistics, for the success and the turned-back count
    for spec, agent, label in zip(policies, agents, labels, strict=True):
        reading = parse(getattr(agent, "readings", "default"), source=f"policy '{spec}' readings")
        params = sim_params(reading)._replace(disturbance=disturbance)
        res, _ = run_episodes(agent, pipe_list, seconds, params, noise_seed=seed, camera=camera)
        rows.setdefault(label, []).append(res[:, STAT_RETURN])
        stats.setdefault(label, []).append(res)
    result = run_compare({k: np.stack(v) for k, v in rows.items()}, reps=reps, seed=seed)
    summary = {"suite": suite.name, "seconds": seconds, **camera_record(camera), **result.summary}
    lengths = [p.length for p in pipe_list]
    for label, runs in stats.items():
        summary["learners"][label].update(summary_of_runs(runs, lengths))
    pairs = list(zip(policies, labels, strict=True))
    summary["policies"] = {label: [p for p, q in pairs if q == label] for label in rows}
    # rliable's layout: {learner: (runs, tasks) array}, here the runs × pipes returns compare judged
    summary["tasks"] = [p.name for p in pipe_list]
    summary["scores"] = {label: np.stack(v).tolist() for label, v in rows.items()}
    if scores_path is not None:
        from pipefollow.files.atomic import write_text_atomic

        scores = {"tasks": summary["tasks"], "scores": summary["scores"]}
        write_text_atomic(Path(scores_path), json.dumps(scores) + "\n")
        summary["scores_file"] = str(scores_path)
    if plot_path:
        from pipefollow.evaluation.plot import plot_comparison

        plot_comparison(summary, plot_path)
        summary["plot"] = str(plot_path)
    echo_result(summary, as_json, lambda: format_summary(summary, camera_text(camera)))
