"""``pipefollow evaluate``: one controller, one pipeline, deterministic episodes."""

from __future__ import annotations

import json
from pathlib import Path

import click
import numpy as np

from pipefollow.cli.common import (
    apply_readings,
    check_plot_path,
    disturbance_text,
    guard,
    inert_readings,
    load_controller,
)
from pipefollow.cli.options import (
    camera_options,
    controller_options,
    disturbance_options,
    episodes_option,
    json_option,
    offset_option,
    pipeline_option,
    plot_option,
    reading_option,
    seconds_option,
    seed_option,
)
from pipefollow.sim import disturbance as _disturbance


def _default_seconds(pipeline: str, seconds: float | None) -> float:
    if seconds is not None:
        return seconds
    return 60.0 if pipeline == "paper-validation" else 20.0


def _summary(stats) -> dict:
    rows = [
        {
            "return": s.ret,
            "pipe_in_view": s.pipe_in_view,
            "progress_m": s.progress_m,
            "time_lost_s": s.time_lost_s,
        }
        for s in stats
    ]
    return {
        "mean_return": float(np.mean([r["return"] for r in rows])),
        "mean_pipe_in_view": float(np.mean([r["pipe_in_view"] for r in rows])),
        "mean_progress_m": float(np.mean([r["progress_m"] for r in rows])),
        "episodes": rows,
    }


@click.command()
@controller_options
@pipeline_option(
    "Built-in name (paper-left, paper-right, paper-validation), a JSON file, a pipe of a suite "
    "(e.g. heldout-003, as 'suites export' names it) or random[:FAMILY] for a new pipe every episode."
)
@episodes_option(
    1, "Number of episodes; they differ only with start noise, random disturbances or a random pipeline."
)
@seconds_option("Episode length in seconds [default: 60 on paper-validation, else 20].", default=None)
@seed_option("Seed of the start perturbation.")
@offset_option("--start-noise", "Uniform random lateral start offset up to this many metres.")
@offset_option("--heading-noise", "Uniform random start heading offset up to this many degrees.")
@plot_option("Save a trajectory plot of the first episode (.png, .svg, .pdf, .jpg, ...).")
@click.option(
    "--animate",
    "animate_path",
    type=click.Path(dir_okay=False),
    default=None,
    help="Save an animation of the first episode in the Fig. 2 view (.gif, or .mp4 with ffmpeg).",
)
@reading_option("Reading of an open point, e.g. start_speed=cruise (repeatable) [default: the policy's].")
@json_option()
@disturbance_options
@camera_options
@guard
def evaluate(
    controller,
    lookahead,
    pipeline,
    episodes,
    seconds,
    seed,
    start_noise,
    heading_noise,
    plot_path,
    animate_path,
    readings,
    as_json,
    disturbance,
    camera,
):
    """Evaluate a controller deterministically (σ = 0) on a pipeline.

    With --camera vision the controller sees through the pipe detector on the rendered camera
    image; "in view" is then the exact camera's.
    """
    from pipefollow.envs.env import PipelineFollowingEnv
    from pipefollow.readings import sim_params
    from pipefollow.sim.pipe_names import resolve_pipeline
    from pipefollow.sim.suites import Suite
    from pipefollow.training.compiled import run_episode

    check_plot_path(plot_path)
    if animate_path:
        from pipefollow.envs.animation import check_animation_path

        check_animation_path(animate_path, "--animate")
    seconds = _default_seconds(pipeline, seconds)
    pipe = resolve_pipeline(pipeline, seconds)  # a Pipeline, or a Suite for random[:FAMILY]
    agent = load_controller(controller, seed, lookahead)
    reading = apply_readings(readings, getattr(agent, "readings", "default"))
    warnings = inert_readings(readings)
    if episodes > 1 and not (start_noise or heading_noise or isinstance(pipe, Suite)):
        from pipefollow.sim.disturbance import noise_count

        if not noise_count(disturbance):
            warnings.append(
                f"the {episodes} episodes are the same: nothing random differs between them "
                "(see --start-noise, --heading-noise, random:FAMILY, --camera-noise, --miss-prob)"
            )
    for w in warnings:
        click.echo(f"pipefollow: warning: {w}", err=True)
    env = PipelineFollowingEnv(
        pipeline if isinstance(pipe, Suite) else pipe,  # a family: the env draws a pipe every episode
        seconds,
        start_noise,
        heading_noise,
        params=sim_params(reading)._replace(disturbance=disturbance),
        **(camera or {}),
    )
    stats, frames = [], []
    for e in range(episodes):
        if e == 0 and animate_path:
            from pipefollow.envs.animation import Recorder

            recorder = Recorder(env)  # the same episode, with its states kept for the animation
            stats.append(run_episode(recorder, agent, seed=seed))
            frames = recorder.frames
        else:
            stats.append(run_episode(env, agent, seed=seed if e == 0 else None))
        if e == 0:
            pipe = env.pipeline  # the first episode's pipe, for the plot and the animation
    result = {
        "controller": controller,
        "pipeline": pipeline,
        "seconds": env.episode_seconds,
        "readings": reading.id,
        **_summary(stats),
    }
    if disturbance != _disturbance.NO_DISTURBANCE:
        result["disturbance"] = _disturbance.to_dict(disturbance)
    if camera:
        result["camera"] = "vision"
        result["water"] = camera["water"]._asdict()
    if warnings:
        result["warnings"] = warnings
    if plot_path:
        from pipefollow.envs.render import plot_trajectories

        name = "heuristic" if controller == "heuristic" else Path(controller).stem
        plot_trajectories(
            pipe, {name: stats[0].poses}, plot_path, title=f"{name} on {pipe.name}: return {stats[0].ret:.2f}"
        )
        result["plot"] = str(plot_path)
    if animate_path:
        from pipefollow.envs.animation import write_animation

        write_animation(pipe, frames, animate_path, env.params)
        result["animation"] = str(animate_path)
    if as_json:
        click.echo(json.dumps(result))
        return
    click.echo(
        f"{controller} on {pipeline}, {episodes} episode(s) of {env.episode_seconds:g} s"
        f"{disturbance_text(disturbance)}"
    )
    click.echo(f"{'episode':>7} {'return':>9} {'in view':>8} {'progress':>9}")
    for i, row in enumerate(result["episodes"]):
        click.echo(f"{i:>7} {row['return']:>9.3f} {row['pipe_in_view']:>8.1%} {row['progress_m']:>8.2f}m")
    click.echo(
        f"{'mean':>7} {result['mean_return']:>9.3f} {result['mean_pipe_in_view']:>8.1%} "
        f"{result['mean_progress_m']:>8.2f}m"
    )
    if plot_path:
        click.echo(f"plot: {plot_path}")
    if animate_path:
        click.echo(f"animation: {animate_path}")
