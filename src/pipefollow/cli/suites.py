"""``pipefollow suites``, ``pipelines`` and ``benchmark``: pipes a controller has never seen."""

from __future__ import annotations

import json

import click

from pipefollow.cli.common import (
    SEED,
    UserError,
    apply_readings,
    camera_options,
    check_plot_path,
    complete_suite,
    controller_options,
    disturbance_options,
    disturbance_text,
    finite,
    guard,
    inert_readings,
    load_controller,
    reading_option,
    writable_folder,
)
from pipefollow.experiments.config import MAX_SECONDS
from pipefollow.sim import disturbance as _disturbance

pipes_option = click.option(
    "--pipes",
    type=click.IntRange(min=1, max=100_000),
    default=None,
    help="Number of pipes [default: all of a held-out suite, 100 of a training family].",
)


def _pipe_count(suite, pipes: int | None) -> int:
    """The pipes ``--pipes`` asks of ``suite`` (its default if None); a one-line error past its end."""
    n = pipes if pipes is not None else (suite.count or 100)
    if suite.count is not None and n > suite.count:
        raise UserError(f"--pipes {n}: suite '{suite.name}' has {suite.count} pipes")
    return n


@click.group(invoke_without_command=True)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of a table.")
@click.pass_context
def suites(ctx, as_json):
    """List the pipeline suites: training families and held-out test suites."""
    if ctx.invoked_subcommand is not None:
        return
    from pipefollow.sim.suites import SUITES

    rows = [s.summary() for s in SUITES.values()]
    if as_json:
        click.echo(json.dumps({"suites": rows}))
        return
    head = ("suite", "kind", "pipes", "turns", "straights", "arc radii")
    click.echo("{:<15} {:<8} {:>5} {:>9} {:>10} {:>10}  description".format(*head))
    for r in rows:
        count = "∞" if r["count"] is None else str(r["count"])
        turns = "{:g}–{:g}°".format(*r["turn_deg"])
        straights = "{:g}–{:g} m".format(*r["straight_m"])
        radii = "{:g}–{:g} m".format(*r["arc_radius_m"])
        cells = (r["name"], r["kind"], count, turns, straights, radii, r["description"])
        click.echo("{:<15} {:<8} {:>5} {:>9} {:>10} {:>10}  {}".format(*cells))


@suites.command("export")
@click.argument("name")
@click.option(
    "--out", "out_dir", type=click.Path(file_okay=False), required=True, help="Folder for the JSON files."
)
@pipes_option
@click.option(
    "--seconds",
    type=click.FloatRange(min=1.0, max=MAX_SECONDS),
    callback=finite,
    default=60.0,
    show_default=True,
    help="Episode length the pipes must be long enough for.",
)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object: the files written.")
@guard
def suites_export(name, out_dir, pipes, seconds, as_json):
    """Write the pipes of suite NAME as pipeline JSON files (NAME-000.json, ...)."""
    from pipefollow.sim.suites import export_suite, get_suite, min_length_for

    suite = get_suite(name)
    n = _pipe_count(suite, pipes)
    out = writable_folder(out_dir, "--out")
    paths = export_suite(suite, out, n, min_length_for(seconds))
    if as_json:
        click.echo(json.dumps({"suite": name, "files": [str(p) for p in paths]}))
        return
    click.echo(f"wrote {len(paths)} pipes of '{name}' to {out}")


@click.command()
@click.option("--json", "as_json", is_flag=True, help="Print one JSON list instead of a table.")
def pipelines(as_json):
    """List the named pipelines.

    The names --pipeline and experiment files accept, with segment count and length.
    """
    from pipefollow.cli.tables import pipeline_rows, table
    from pipefollow.cli.tables import pipelines as entries

    rows = pipeline_rows(entries())
    if as_json:
        click.echo(json.dumps(rows, ensure_ascii=False))
        return
    columns = [("name", "name"), ("group", "group"), ("segments", "segments"), ("length_m", "length (m)")]
    click.echo(table(rows, [*columns, ("description", "description")]))


@click.command()
@controller_options
@click.option(
    "--suite",
    "suite_specs",
    multiple=True,
    metavar="SUITE|PATH",
    shell_complete=complete_suite,
    help="A suite (see 'pipefollow suites'), or pipeline JSON files: folders, files, glob patterns "
    "(repeatable; what 'suites export' writes) [default: heldout].",
)
@click.option(
    "--seconds",
    type=click.FloatRange(min=1.0, max=MAX_SECONDS),
    callback=finite,
    default=60.0,
    show_default=True,
    help="Episode length in seconds.",
)
@pipes_option
@click.option(
    "--seed",
    default=0,
    show_default=True,
    type=SEED,
    help="Seed of the bootstrap resampling and of the random disturbances.",
)
@click.option(
    "--plot",
    "plot_path",
    type=click.Path(dir_okay=False),
    default=None,
    help="Save a plot of the per-pipe return differences to the heuristic and a few trajectories "
    "(.png, .svg, .pdf, ...).",
)
@reading_option("Reading of an open point, e.g. start_speed=cruise (repeatable) [default: the policy's].")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of a table.")
@disturbance_options
@camera_options
@guard
def benchmark(
    controller, lookahead, suite_specs, seconds, pipes, seed, plot_path, readings, as_json, disturbance,
    camera,
):  # fmt: skip
    """Run a controller deterministically on every pipe of a suite, beside the heuristic.

    Reports the mean return with a bootstrap 95 % confidence interval, the interquartile mean,
    the success rate (pipe in view at ≥ 95 % of the decisions) and, for a controller other than
    the heuristic, the paired per-pipe difference to the heuristic with its confidence interval.
    With --camera vision the controller sees through the pipe detector (the pipe in view is still
    the exact camera's) and is compared with the heuristic on the ideal camera.
    """
    from pipefollow.evaluation.benchmark import benchmark as run_benchmark
    from pipefollow.evaluation.benchmark import format_summary
    from pipefollow.readings import sim_params
    from pipefollow.sim.pipe_names import resolve_suite

    check_plot_path(plot_path)
    suite = resolve_suite(suite_specs or ["heldout"])
    _pipe_count(suite, pipes)
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
    if camera:  # compared with the heuristic on the ideal camera
        run.summary["camera"] = "vision"
        run.summary["water"] = camera["water"]._asdict()
    if disturbance != _disturbance.NO_DISTURBANCE:
        run.summary["disturbance"] = _disturbance.to_dict(disturbance)
    if warnings:
        run.summary["warnings"] = warnings
    if plot_path:
        from pipefollow.evaluation.plot import plot_benchmark

        plot_benchmark(run, plot_path)
        run.summary["plot"] = str(plot_path)
    if as_json:
        click.echo(json.dumps(run.summary))
        return
    click.echo(format_summary(run.summary, seconds) + disturbance_text(disturbance, "\n  disturbances   "))
    if plot_path:
        click.echo(f"plot: {plot_path}")
