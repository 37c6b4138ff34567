"""``pipefollow suites``, ``pipelines`` and ``benchmark``: pipes a controller has never seen."""

from __future__ import annotations

import click

from pipefollow.cli.common import (
    apply_readings,
    camera_text,
    check_plot_path,
    disturbance_text,
    echo_result,
    guard,
    inert_readings,
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
    plot_option,
    reading_option,
    seconds_option,
    seed_option,
    suite_option,
)
from pipefollow.sim import disturbance as _disturbance


@click.group(invoke_without_command=True)
@json_option()
@click.pass_context
def suites(ctx, as_json):
    """List the pipeline suites: training families and held-out test suites."""
    if ctx.invoked_subcommand is not None:
        return
    from pipefollow.sim.suites import SUITES

    rows = [s.summary() for s in SUITES.values()]
    echo_result({"suites": rows}, as_json, lambda: _suite_table(rows))


def _suite_table(rows: list[dict]) -> str:
    """The rows of ``pipefollow suites``, one suite a line under a header."""
    head = ("suite", "kind", "pipes", "turns", "straights", "arc radii")
    lines = ["{:<15} {:<8} {:>5} {:>9} {:>10} {:>10}  description".format(*head)]
    for r in rows:
        count = "∞" if r["count"] is None else str(r["count"])
        turns = "{:g}–{:g}°".format(*r["turn_deg"])
        straights = "{:g}–{:g} m".format(*r["straight_m"])
        radii = "{:g}–{:g} m".format(*r["arc_radius_m"]) if max(r["arc_radius_m"]) > 0 else "corners"
        cells = (r["name"], r["kind"], count, turns, straights, radii, r["description"])
        lines.append("{:<15} {:<8} {:>5} {:>9} {:>10} {:>10}  {}".format(*cells))
    return "\n".join(lines)


@suites.command("export")
@click.argument("name")
@out_option("Folder for the JSON files.")
@pipes_option()
@seconds_option("Episode length the pipes must be long enough for.")
@json_option("Print one JSON object: the files written.")
@guard
def suites_export(name, out_dir, pipes, seconds, as_json):
    """Write the pipes of suite NAME as pipeline JSON files (NAME-000.json, ...)."""
    from pipefollow.sim.suites import export_suite, get_suite, min_length_for

    suite = get_suite(name)
    n = pipe_count(suite, pipes)
    out = writable_folder(out_dir, "--out")
    paths = export_suite(suite, out, n, min_length_for(seconds))
    echo_result(
        {"suite": name, "files": [str(p) for p in paths]}, as_json,
        lambda: f"wrote {len(paths)} pipes of '{name}' to {out}",
    )  # fmt: skip


@click.command()
@json_option("Print one JSON list instead of a table.")
def pipelines(as_json):
    """List the named pipelines.

    The names --pipeline and experiment files accept, with segment count and length.
    """
    from pipefollow.cli.tables import pipeline_rows, table
    from pipefollow.cli.tables import pipelines as entries

    rows = pipeline_rows(entries())
    columns = [("name", "name"), ("group", "group"), ("segments", "segments"), ("length_m", "length (m)")]
    columns.append(("description", "description"))
    echo_result(rows, as_json, lambda: table(rows, columns), ensure_ascii=False)


@click.command()
@controller_options
@suite_option(
    "A suite (see 'pipefollow suites'), or pipeline JSON files: folders, files, glob patterns "
    "(repeatable; what 'suites export' writes) [default: heldout]."
)
@seconds_option()
@pipes_option()
@seed_option("Seed of the bootstrap resampling and of the random disturbances.")
@plot_option(
    "Save a plot of the per-pipe return differences to the heuristic and a few trajectories "
    "(.png, .svg, .pdf, ...)."
)
@reading_option("Reading of an open point, e.g. start_speed=cruise (repeatable) [default: the policy's].")
@json_option()
@disturbance_options
@camera_options
@guard
def benchmark(
    controller, lookahead, suite_specs, seconds, pipes, seed, plot_path, readings, as_json, disturbance,
    camera,
):  # fmt: skip
    """Run a controller deterministically on every pipe of a suite, beside the heuristic.

    Reports the mean return with a bootstrap 95 % confidence interval, the interquartile mean,
    the success rate (pipe in view at ≥ 95 % of the decisions and followed forward), the episodes
    that turned back and, for a controller other than the heuristic, the paired per-pipe difference
    to the heuristic with its confidence interval.
    With --camera vision (or a --sensor sonar) the controller sees through the pipe detector
    (the pipe in view is still the exact camera's) and is compared with the heuristic through the
    same camera, sensor and water, and with the heuristic on the ideal camera as a second reference.
    """
    from pipefollow.evaluation.benchmark import benchmark as run_benchmark
    from pipefollow.evaluation.benchmark import format_summary
    from pipefollow.readings import sim_params
    from pipefollow.sim.pipe_names import resolve_suite

    check_plot_path(plot_path)
    suite = resolve_suite(suite_specs or ["heldout"])
    pipe_count(suite, pipes)
    agent = load_controller(controller, seed, lookahead)
    reading = apply_readings(readings, getattr(agent, "readings", "default"))
    warnings = inert_readings(readings)
    for w in warnings:
        click.echo(f"pipefollow: warning: {w}", err=True)
    run = run_benchmark(
        agent,
        suite,
        controller=controller,
        seconds=seconds,
        params=sim_params(reading)._replace(disturbance=disturbance),
        n_pipes=pipes,
        seed=seed,
        noise_seed=seed,
        camera=camera,
    )
    run.summary["readings"] = reading.id
    if disturbance != _disturbance.NO_DISTURBANCE:
        run.summary["disturbance"] = _disturbance.to_dict(disturbance)
    if warnings:
        run.summary["warnings"] = warnings
    if plot_path:
        from pipefollow.evaluation.plot import plot_benchmark

        plot_benchmark(run, plot_path)
        run.summary["plot"] = str(plot_path)
    echo_result(
        run.summary, as_json,
        lambda: _with_camera(format_summary(run.summary, seconds), camera)
        + disturbance_text(disturbance, "\n  disturbances   ")
        + (f"\nplot: {plot_path}" if plot_path else ""),
    )  # fmt: skip


def _with_camera(summary: str, camera) -> str:
    """The benchmark's text with the camera and water line under its head line."""
    head, _, rest = summary.partition("\n")
    return head + camera_text(camera, "\n  ") + ("\n" + rest if rest else "")
