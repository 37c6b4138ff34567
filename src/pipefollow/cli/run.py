"""``pipefollow train``: a learner on a pipeline or a family of random pipes."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from pipefollow.cli.common import (
    UserError,
    apply_readings,
    camera_record,
    echo_result,
    guard,
    policy_file,
    writable_folder,
)
from pipefollow.cli.options import (
    camera_options,
    disturbance_options,
    episodes_option,
    json_option,
    learner_options,
    out_option,
    pipeline_option,
    reading_option,
    seconds_option,
    seed_option,
)
from pipefollow.files.paper_training import EPISODE_SECONDS, TRAINING_EPISODES
from pipefollow.files.progress import progress as progress_report
from pipefollow.learners.registry import NAMES as LEARNER_NAMES
from pipefollow.sim import disturbance as _disturbance

DEEP = ("ppo", "sac")  # the learners of Stable-Baselines3 (pipefollow.training.deep)


@click.command()
@click.option(
    "--algorithm",
    type=click.Choice([*LEARNER_NAMES, *DEEP]),
    required=True,
    help="The paper's learners (sarsa, cacla; ac: the general actor-critic of eq. 9), or PPO / SAC "
    "from Stable-Baselines3 (extra 'deep').",
)
@learner_options
@pipeline_option(
    "Built-in name or JSON file to train on, or random[:FAMILY] for a new pipe every episode "
    "(families: see 'pipefollow suites'; random = random:mixed)."
)
@episodes_option(
    TRAINING_EPISODES,
    "Training episodes (σ falls linearly from --sigma-start to --sigma-end over them); the paper's learners.",
)
@seconds_option(default=EPISODE_SECONDS)
@click.option(
    "--steps",
    type=click.IntRange(min=1, max=100_000_000),
    default=None,
    help="PPO and SAC: budget in environment steps (decisions) [default: 100,000].",
)
@seed_option("Seed of the learner's exploration, its initial weights and any random pipes and disturbances.")
@out_option("Folder for policy.npz and learning_curve.csv.")
@click.option(
    "--init",
    "init_policy",
    type=click.Path(),
    default=None,
    help="Continue training from this policy file, or the folder holding it (e.g. left turns, then "
    "right turns); its learner options are kept unless given.",
)
@click.option("--force", is_flag=True, help="Replace the policy and learning curve already in --out.")
@click.option(
    "--tensorboard",
    "tensorboard_dir",
    type=click.Path(file_okay=False),
    default=None,
    help="Also log return, pipe in view, progress and σ per episode for TensorBoard in this folder "
    "(SARSA and CACLA; optional extra 'tensorboard').",
)
@reading_option(
    "Reading of an open point, e.g. skew_step=weights or skew_sample=centred (repeatable; "
    "see docs/design.md) [default: the project's readings, or those of --init]."
)
@json_option("Print one JSON object at the end.")
@click.option(
    "--randomization",
    metavar="PRESET|FILE.toml",
    default=None,
    help="Domain randomization: each episode draws its disturbances from a preset (mild, moderate, "
    "vision, harsh) or a TOML table (see pipefollow.sim.randomization); not with the fixed disturbance "
    "options.",
)
@disturbance_options
@camera_options
@guard
def train(
    algorithm,
    learner_options,
    pipeline,
    episodes,
    seconds,
    steps,
    seed,
    out_dir,
    init_policy,
    force,
    tensorboard_dir,
    readings,
    as_json,
    randomization,
    disturbance,
    camera,
):
    """Train a learner; writes the policy and its learning curve.

    Every learner option of experiment files is an option here too (--critic-lambda, --alpha-v,
    --sigma-start, --state, ...): the same values give the same policy. An --out folder that already
    holds them is refused unless --force is given. Ctrl-C stops without writing anything (exit status 130).
    With --camera vision (or a --sensor sonar) and its water every learner trains through that
    camera or sensor: the paper's learners then run in the environment, frame by frame, instead of
    their compiled loop of the ideal camera.
    """
    _refuse_existing(out_dir, force)
    randomization = _randomization(randomization, disturbance)
    if tensorboard_dir:
        _check_tensorboard(algorithm)
    if algorithm in DEEP:
        _refuse_learner_options(algorithm, learner_options)
        return _train_deep(
            algorithm, pipeline, seconds, steps, seed, out_dir, as_json, disturbance, randomization, camera
        )
    if steps is not None:
        raise UserError("--steps applies to --algorithm ppo and sac only (use --episodes)")
    from pipefollow.files.output_paths import first_missing
    from pipefollow.training.runs import train_into

    agent, reading, options = _learner(algorithm, pipeline, seed, init_policy, readings, learner_options)
    made = first_missing(out_dir)
    out = writable_folder(out_dir, "--out")  # before training, after the checks of --init
    try:
        with progress_report(
            episodes, f"training {agent.name}", hidden=as_json, unit="episodes", bar=click.progressbar
        ) as bar:
            run = train_into(
                out, agent, pipeline, episodes, seed=seed, readings=reading, disturbance=disturbance,
                randomization=randomization, seconds=seconds, progress=_counter(bar),
                tensorboard=tensorboard_dir, made=made, sigma_start=options["sigma_start"],
                sigma_end=options["sigma_end"], options=options, camera=camera,
            )  # fmt: skip
    except KeyboardInterrupt:
        click.echo(f"pipefollow: interrupted; nothing written to '{out_dir}'", err=True)
        sys.exit(130)
    _echo_trained({**run.summary(), **camera_record(camera)}, disturbance, randomization, as_json, run.text)


def _counter(bar, every: int = 0, total: int | None = None):
    """A ``progress(n)`` callback (n: the work done so far) moving ``bar`` by at least ``every``.

    With ``total``, the bar stops there and the last step is always shown.
    """
    done = [0]

    def progress(n):
        if n - done[0] >= every or (total is not None and n >= total):
            n = n if total is None else min(n, total)
            bar.update(n - done[0])
            done[0] = n

    return progress


def _refuse_existing(out_dir: str, force: bool) -> None:
    """An --out folder holding a policy or learning curve is refused without --force."""
    from pipefollow.training.outputs import TRAINING_OUTPUTS

    existing = [name for name in TRAINING_OUTPUTS if (Path(out_dir) / name).exists()]
    if existing and not force:
        raise UserError(f"--out '{out_dir}' already holds {existing[0]}; use --force to replace it")


def _randomization(spec: str | None, disturbance):
    """``--randomization``, read; refused beside the fixed disturbance options."""
    if spec is None:
        return None
    from pipefollow.cli.parsing import parse_randomization
    from pipefollow.sim.randomization import both_given

    randomization = parse_randomization(spec)
    if both_given(disturbance, randomization):
        raise UserError("--randomization replaces --current, --camera-noise and --miss-prob: give one")
    return randomization


def _check_tensorboard(algorithm: str) -> None:
    """``--tensorboard``: SARSA and CACLA only, and the extra installed."""
    from pipefollow.files.tensorboard import TensorBoardMissing, check_available

    if algorithm in DEEP:
        raise UserError(f"--tensorboard applies to --algorithm sarsa and cacla, not {algorithm}")
    try:
        check_available()
    except TensorBoardMissing as e:
        raise UserError(str(e)) from None


def _flag(option: str) -> str:
    from pipefollow.learners.options import OPTION

    return OPTION[option].option


def _refuse_learner_options(algorithm: str, given: dict) -> None:
    """PPO and SAC take none of the learners' options."""
    if given:
        flags = ", ".join(_flag(k) for k in given)
        raise UserError(f"{flags} not available with --algorithm {algorithm}")


def _learner(algorithm, pipeline, seed, init_policy, readings, given: dict):
    """The agent to train, its readings and its options (the σ schedule too).

    A new agent from the given options (the others at their defaults), or the policy of --init with
    its options, which the given ones must not contradict.
    """
    from pipefollow.learners.options import DEFAULTS, check_schedule
    from pipefollow.learners.registry import learner, takes, taking
    from pipefollow.sim.pipe_names import resolve_training
    from pipefollow.training.runs import new_agent

    kind = learner(algorithm)
    for option in given:
        if not takes(kind, option):
            raise UserError(f"{_flag(option)} applies to --algorithm {' and '.join(taking(option))} only")
    resolve_training(pipeline)  # a bad pipeline fails before a policy is read
    schedule = {k: given.get(k, DEFAULTS[k]) for k in ("sigma_start", "sigma_end")}
    if not init_policy:
        _check_schedule(check_schedule, schedule)
        reading = apply_readings(readings)
        agent_given = {k: v for k, v in given.items() if k not in schedule}
        agent = new_agent(algorithm, seed, reading, **agent_given)
        return agent, reading, {**given, **schedule}
    from pipefollow.training.phases import agent_rng
    from pipefollow.training.policy_files import load_policy

    init_policy = policy_file(init_policy, "--init")
    agent = load_policy(init_policy)
    reading = apply_readings(readings, agent.readings)
    if agent.algorithm != algorithm:
        raise UserError(f"--init {init_policy}: holds a {agent.name} policy, not {algorithm}")
    saved = getattr(agent, "learner_options", {})
    schedule = {k: given.get(k, saved.get(k, DEFAULTS[k])) for k in schedule}
    _check_schedule(check_schedule, schedule)
    _check_init_options(agent, reading, init_policy, {k: v for k, v in given.items() if k not in schedule})
    agent.readings = reading.id
    agent.rng = agent_rng(seed)
    from pipefollow.training.runs import saved_options

    return agent, reading, {**saved, **saved_options(agent), **schedule}


def _check_schedule(check, schedule: dict) -> None:
    try:
        check(schedule["sigma_start"], schedule["sigma_end"])
    except ValueError as e:
        raise UserError(f"--sigma-start: {e}") from None


def _check_init_options(agent, reading, init_policy, given: dict) -> None:
    """``train --init``: the saved policy's options unless given; differences named."""
    from pipefollow.training.runs import option_differences

    differ = option_differences(agent, reading, **given)
    if differ:
        raise UserError(
            f"--init {init_policy}: holds a {agent.name} policy (readings '{agent.readings}') whose options "
            f"differ from this run's: {'; '.join(differ)}; give its options or none"
        )


def _given(*names: str) -> list[str]:
    """The options (``--steps``) of the parameters ``names`` given on the command line, in that order."""
    from click.core import ParameterSource

    ctx = click.get_current_context()
    option = {p.name: p.opts[0] for p in ctx.command.params}  # a parameter's name → its option
    return [option[n] for n in names if ctx.get_parameter_source(n) == ParameterSource.COMMANDLINE]


def _train_deep(
    algorithm, pipeline, seconds, steps, seed, out_dir, as_json, disturbance, randomization=None, camera=None
):
    """``train --algorithm ppo|sac``: :func:`pipefollow.training.deep.train_to_folder`."""
    given = _given("episodes", "init_policy", "readings")
    if given:
        budget = "; its budget is --steps" if "--episodes" in given else ""
        raise UserError(f"{', '.join(given)} not available with --algorithm {algorithm}{budget}")
    try:
        from pipefollow.training import deep
    except ImportError as e:  # pipefollow.training.deep.DeepExtraMissing: torch or Stable-Baselines3 missing
        if type(e).__name__ != "DeepExtraMissing":
            raise
        raise UserError(str(e).split(" (")[0]) from None
    from pipefollow.sim.pipe_names import resolve_training

    resolve_training(pipeline)  # a bad pipeline fails before any work
    out = writable_folder(out_dir, "--out")
    steps = deep.STEPS if steps is None else steps
    with progress_report(
        steps, f"training {algorithm.upper()}", hidden=as_json, unit="steps", bar=click.progressbar
    ) as bar:
        extra = {} if disturbance == _disturbance.NO_DISTURBANCE else {"disturbance": disturbance}
        if randomization is not None:
            extra["randomization"] = randomization
        result = deep.train_to_folder(
            algorithm, pipeline, out, steps=steps, seconds=seconds, seed=seed,
            progress=_counter(bar, every=256, total=steps), camera=camera, **extra,
        )  # fmt: skip
    result.update(camera_record(camera))
    _echo_trained(result, disturbance, randomization, as_json, lambda: deep.result_text(result))


def _echo_trained(result: dict, disturbance, randomization, as_json: bool, text) -> None:
    """Print a training's ``result`` (with its disturbance and randomization, if any) or ``text()``.

    The text names the camera or sensor the run trained through, if not the ideal camera alone.
    """
    if "camera" in result:
        lines, sensor = text, result.get("sensor", "camera")
        water = ", ".join(f"{k} {v:g}" for k, v in result["water"].items() if k in ("turbidity", "burial"))

        def text() -> str:
            return f"{lines()}\ntrained through: camera {result['camera']}, sensor {sensor}, water {water}"

    if disturbance != _disturbance.NO_DISTURBANCE:
        result["disturbance"] = _disturbance.to_dict(disturbance)
    if randomization is not None:
        from pipefollow.sim.randomization import to_dict

        result["randomization"] = to_dict(randomization)
    echo_result(result, as_json, text)
