"""``pipefollow robustness``: controllers against current speed and fixed scenario sets."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pipefollow.cli.common import (
    SEED,
    UserError,
    camera_record,
    camera_text,
    command_line,
    finite,
    guard,
    load_controller,
    pipe_count,
    writable_folder,
)
from pipefollow.cli.options import MAX_EPISODE_SECONDS, camera_options, pipes_option, suite_option
from pipefollow.files.paper_training import TEST_EPISODE_SECONDS

OUTPUTS = ("curve.csv", "scenarios.csv", "robustness.json", "robustness.png", "provenance.json")


def _numbers(text: str, option: str) -> list[float]:
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        raise UserError(f"{option} '{text}': expected numbers separated by commas") from None
    return values


def _controllers(specs, seed: int) -> dict[str, list]:
    """``LABEL=SPEC`` or ``SPEC`` (labelled by the built-in's name or the policy's folder) → agents."""
    out: dict[str, list] = {}
    for spec in specs or ("heuristic", "los"):
        label, sep, what = spec.partition("=")
        if not sep:
            label, what = spec, spec
            if what.endswith(".npz"):
                label = Path(what).parent.name or Path(what).stem
        if not label or not what:
            raise UserError(f"--controller '{spec}': expected LABEL=SPEC or SPEC")
        out.setdefault(label, []).append(load_controller(what, seed))
    return out


@click.command()
@click.option(
    "--controller",
    "controllers",
    multiple=True,
    metavar="[LABEL=]SPEC",
    help="'heuristic', 'los' or a policy file, optionally labelled; policies given the same label are "
    "seeds of one learner (repeatable) [default: heuristic and los].",
)
@suite_option()
@pipes_option()
@click.option(
    "--seconds",
    type=click.FloatRange(min=1.0, max=MAX_EPISODE_SECONDS),
    callback=finite,
    default=TEST_EPISODE_SECONDS,
    show_default=True,
    help="Episode length in seconds.",
)
@click.option(
    "--speeds",
    default="0,0.05,0.1,0.15,0.2,0.25,0.3",
    show_default=True,
    help="Current speeds (m/s) of the curve, separated by commas.",
)
@click.option(
    "--scenarios",
    "sets",
    default="calm,current,noise,misses,buried,sea",
    show_default=True,
    help="Fixed scenario sets to run, separated by commas ('' for none).",
)
@click.option("--seed", default=0, show_default=True, type=SEED, help="Seed of the bootstrap resampling.")
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False),
    default=None,
    help="Folder for curve.csv, scenarios.csv, robustness.json and the figure robustness.png.",
)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of tables.")
@camera_options
@guard
def robustness(controllers, suite_specs, pipes, seconds, speeds, sets, seed, out_dir, as_json, camera):
    """Success rate and mean return against current speed, and on fixed scenario sets.

    Every controller runs one deterministic episode per pipe of the suite at each current speed
    (pipe k's current always flows towards the same seeded direction) and on each scenario set
    (currents, camera noise, missed detections, buried stretches, all at once; seeded per pipe), beside
    the heuristic. Policies that share a label are pooled as training seeds.
    With --camera vision (or a --sensor sonar) every controller, the heuristic beside them too,
    observes through that camera or sensor and water; success and in view are the exact camera's.
    """
    from pipefollow.evaluation import robustness as rb
    from pipefollow.sim.pipe_names import resolve_suite

    speed_list = _numbers(speeds, "--speeds")
    set_list = [s for s in sets.split(",") if s]
    suite = resolve_suite(suite_specs or ["heldout"])  # what benchmark --suite takes
    n = pipe_count(suite, pipes)
    for v in speed_list:
        rb.curve_scenarios(v, suite, 1, seconds)  # a bad speed fails before any episode
    for name in set_list:
        rb.get_scenario_set(name)
    agents = _controllers(controllers, seed)
    if out_dir:
        for name in OUTPUTS:
            if (Path(out_dir) / name).is_dir():
                raise UserError(f"--out '{out_dir}': {name} is a folder")
    folder = writable_folder(out_dir, "--out") if out_dir else None
    common = dict(n_pipes=n, seconds=seconds, seed=seed, camera=camera)
    curve = rb.robustness_curve(agents, suite, speeds=speed_list, **common)
    table = rb.scenario_table(agents, suite, sets=set_list, **common)
    result = {"suite": suite.name, "pipes": n, "seconds": seconds, **camera_record(camera), "curve": curve,
              "scenarios": table}  # fmt: skip
    if folder is not None:
        from pipefollow.files.atomic import write_text_atomic
        from pipefollow.files.machine import write_provenance

        write_text_atomic(folder / "curve.csv", rb.to_csv(curve, "current_speed"))
        write_text_atomic(folder / "scenarios.csv", rb.to_csv(table, "scenarios"))
        write_text_atomic(folder / "robustness.json", json.dumps(result, indent=1) + "\n")
        write_provenance(folder, command_line())
        if curve:
            title = f"'{suite.name}', {n} pipes × {seconds:g} s{camera_text(camera, ', ')}"
            rb.plot_curve(curve, folder / "robustness.png", title)
        result["files"] = [str(folder / name) for name in OUTPUTS if curve or name != "robustness.png"]
    if as_json:
        click.echo(json.dumps(result))
        return
    cell = "mean return [95 % CI], success rate (pipe in view ≥ 95 % and followed forward)"
    if camera:
        click.echo(f"every controller observes through: {camera_text(camera, '')}\n")
    if curve:
        click.echo(f"current speed (m/s) — {cell}:\n" + rb.markdown(curve, "current_speed", "speed (m/s)"))
    if table:
        click.echo(f"\nscenario sets — {cell}:\n" + rb.markdown(table, "scenarios", "scenarios"))
    if folder is not None:
        click.echo(f"\nwrote {', '.join(result['files'])}")
