"""``pipefollow evaluate``: one controller, one pipeline, deterministic episodes."""

from __future__ import annotations

from pathlib import Path

import click

from pipefollow.cli.common import (
    apply_readings,
    camera_record,
    camera_text,
    check_plot_path,
    disturbance_text,
    echo_result,
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
from pipefollow.files.paper_training import EPISODE_SECONDS, TEST_EPISODE_SECONDS
from pipefollow.sim import disturbance as _disturbance


@click.command()
@controller_options
@pipeline_option(
    "Built-in name (paper-left, paper-right, paper-validation), a JSON file, a pipe of a suite "
    "(e.g. heldout-003, as 'suites export' names it) or random[:FAMILY] for a new pipe every episode."
)
@episodes_option(
    1, "Number of episodes; they differ only with start noise, random disturbances or a random pipeline."
)
@seconds_option(
    f"Episode length in seconds [default: {EPISODE_SECONDS:g} on a training pipe (paper-left, paper-right, "
    f"random[:FAMILY]), else {TEST_EPISODE_SECONDS:g}, as benchmark].",
    default=None,
)
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
    from pipefollow.evaluation import episodes as ev
    from pipefollow.sim.pipe_names import resolve_pipeline

    _check_figure_paths(plot_path, animate_path)
    seconds = ev.default_seconds(pipeline) if seconds is None else seconds
    pipe = resolve_pipeline(pipeline, seconds)  # a Pipeline, or a Suite for random[:FAMILY]
    agent = load_controller(controller, seed, lookahead)
    reading = apply_readings(readings, getattr(agent, "readings", "default"))
    warnings = inert_readings(readings)
    if episodes > 1 and ev.episodes_alike(pipe, start_noise, heading_noise, disturbance):
        warnings.append(
            f"the {episodes} episodes are the same: nothing random differs between them "
            "(see --start-noise, --heading-noise, random:FAMILY, --camera-noise, --miss-prob)"
        )
    for w in warnings:
        click.echo(f"pipefollow: warning: {w}", err=True)
    run = ev.evaluate(
        agent, pipeline, pipe, episodes=episodes, seconds=seconds, seed=seed, start_noise=start_noise,
        heading_noise=heading_noise, readings=reading, disturbance=disturbance, camera=camera,
        record=bool(animate_path),
    )  # fmt: skip
    result = {"controller": controller, "pipeline": pipeline, "seconds": run.seconds, "readings": reading.id,
              **run.summary(), **_settings(disturbance, camera, warnings)}  # fmt: skip
    if plot_path:
        run.write_plot(plot_path, "heuristic" if controller == "heuristic" else Path(controller).stem)
        result["plot"] = str(plot_path)
    if animate_path:
        run.write_animation(animate_path)
        result["animation"] = str(animate_path)
    echo_result(result, as_json, lambda: _text(result, episodes, disturbance, camera))


def _check_figure_paths(plot_path: str | None, animate_path: str | None) -> None:
    """Refuse a --plot or --animate file of an unknown format before any work."""
    check_plot_path(plot_path)
    if animate_path:
        from pipefollow.envs.animation import check_animation_path

        check_animation_path(animate_path, "--animate")


def _settings(disturbance, camera, warnings: list[str]) -> dict:
    """The result's entries for the disturbances, the vision camera and the warnings, where any."""
    out = {}
    if disturbance != _disturbance.NO_DISTURBANCE:
        out["disturbance"] = _disturbance.to_dict(disturbance)
    out.update(camera_record(camera))
    if warnings:
        out["warnings"] = warnings
    return out


def _text(result: dict, episodes: int, disturbance, camera=None) -> str:
    """The result as a table of the episodes with their mean, and the files written."""
    lines = [
        f"{result['controller']} on {result['pipeline']}, {episodes} episode(s) of {result['seconds']:g} s"
        f"{disturbance_text(disturbance)}{camera_text(camera)}",
        f"{'episode':>7} {'return':>9} {'in view':>8} {'progress':>9} {'of reach':>8} {'success':>7}  end",
    ]
    for i, row in enumerate(result["episodes"]):
        notes = "reached the end " if row["reached_end"] else ""
        notes += "turned back" if row["turned_back"] else ""
        lines.append(
            f"{i:>7} {row['return']:>9.3f} {row['pipe_in_view']:>8.1%} {row['progress_m']:>8.2f}m "
            f"{row['progress_share']:>8.0%} {'yes' if row['success'] else 'no':>7}  {notes}".rstrip()
        )
    lines.append(
        f"{'mean':>7} {result['mean_return']:>9.3f} {result['mean_pipe_in_view']:>8.1%} "
        f"{result['mean_progress_m']:>8.2f}m {result['mean_progress_share']:>8.0%} "
        f"{result['success_rate']:>7.0%}"
    )
    lines.append(
        "success: pipe in view ≥ 95 % of the decisions and followed forward (progress ≥ half the reachable, "
        f"or the end reached); turned back: {result['turned_back']} episode(s)"
    )
    lines += [f"{k}: {result[k]}" for k in ("plot", "animation") if k in result]
    return "\n".join(lines)
