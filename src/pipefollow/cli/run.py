"""``pipefollow train``: a learner on a pipeline or a family of random pipes."""

from __future__ import annotations

import sys
from pathlib import Path

import click
import numpy as np

from pipefollow.cli.common import (
    UserError,
    apply_readings,
    echo_result,
    finite,
    guard,
    writable_folder,
)
from pipefollow.cli.options import (
    disturbance_options,
    episodes_option,
    json_option,
    out_option,
    pipeline_option,
    reading_option,
    seconds_option,
    seed_option,
)
from pipefollow.files.progress import progress as progress_report
from pipefollow.learners.registry import NAMES as LEARNER_NAMES
from pipefollow.sim import disturbance as _disturbance

# the learners' step sizes and discount: not options of train, kept from the policy under --init
_LEARNING_RATES = ("alpha", "alpha_v", "alpha_pi", "discount", "delta_k", "k_max", "forgetting")


@click.command()
@click.option(
    "--algorithm",
    type=click.Choice([*LEARNER_NAMES, "ppo", "sac"]),
    required=True,
    help="The paper's learners (sarsa, cacla; ac: the general actor-critic of eq. 9), or PPO / SAC "
    "from Stable-Baselines3 (extra 'deep').",
)
@click.option(
    "--skew",
    type=click.FloatRange(min=0.0, max=180.0),
    callback=finite,
    default=0.0,
    show_default=True,
    help="CACLA skew step Δγ in degrees (eq. 15): 11.25, 22.5 or 45 in the paper; 0 = Gaussian.",
)
@click.option(
    "--supervised",
    is_flag=True,
    help="The heuristic as supervisor: supervised CACLA (eq. 12) or actor-critic (eq. 11).",
)
@pipeline_option(
    "Built-in name or JSON file to train on, or random[:FAMILY] for a new pipe every episode "
    "(families: see 'pipefollow suites'; random = random:mixed)."
)
@episodes_option(500, "Training episodes (σ falls linearly from 1 to 0.01 over them); SARSA and CACLA.")
@seconds_option(default=20.0)
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
@guard
def train(
    algorithm,
    skew,
    supervised,
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
):
    """Train a learner; writes the policy and its learning curve.

    An --out folder that already holds them is refused unless --force is given. Ctrl-C stops
    without writing anything (exit status 130).
    """
    from pipefollow.training.outputs import TRAINING_OUTPUTS

    existing = [name for name in TRAINING_OUTPUTS if (Path(out_dir) / name).exists()]
    if existing and not force:
        raise UserError(f"--out '{out_dir}' already holds {existing[0]}; use --force to replace it")
    if randomization is not None:
        from pipefollow.sim.randomization import load

        randomization = load(randomization)
        if disturbance != _disturbance.NO_DISTURBANCE:
            raise UserError("--randomization replaces --current, --camera-noise and --miss-prob: give one")
    if tensorboard_dir:
        from pipefollow.files.tensorboard import TensorBoardMissing, check_available

        if algorithm in ("ppo", "sac"):
            raise UserError(f"--tensorboard applies to --algorithm sarsa and cacla, not {algorithm}")
        try:
            check_available()
        except TensorBoardMissing as e:
            raise UserError(str(e)) from None
    if algorithm in ("ppo", "sac"):
        return _train_deep(
            algorithm, pipeline, seconds, steps, seed, out_dir, as_json, disturbance, randomization
        )
    if steps is not None:
        raise UserError("--steps applies to --algorithm ppo and sac only (use --episodes)")
    from pipefollow.learners.registry import learner, taking
    from pipefollow.sim.suites import resolve_training
    from pipefollow.training.agents import make_agent
    from pipefollow.training.compiled import STAT_NAMES
    from pipefollow.training.phases import agent_rng, train_phases

    for option, flag, value in (("skew_deg", "--skew", skew), ("supervised", "--supervised", supervised)):
        if value and option not in learner(algorithm).options:
            raise UserError(f"{flag} applies to --algorithm {' and '.join(taking(option))} only")
    pipe = resolve_training(pipeline)  # a Pipeline, or a Suite for random[:FAMILY]
    rng = agent_rng(seed)
    if init_policy:
        from pipefollow.cli.common import policy_file
        from pipefollow.training.policy_files import load_policy

        init_policy = policy_file(init_policy, "--init")
        agent = load_policy(init_policy)
        reading = apply_readings(readings, agent.readings)
        if agent.algorithm != algorithm:
            raise UserError(f"--init {init_policy}: holds a {agent.name} policy, not {algorithm}")
        _check_init_options(agent, reading, init_policy, skew, supervised)
        agent.readings = reading.id
        agent.rng = rng
    else:
        reading = apply_readings(readings)
        agent = make_agent(algorithm, skew_deg=skew, supervised=supervised, rng=rng, readings=reading)
    from pipefollow.files.output_paths import first_missing, remove_empty_folders
    from pipefollow.training.outputs import write_training_outputs

    made = first_missing(out_dir)
    out = writable_folder(out_dir, "--out")  # before training, after the checks of --init
    try:
        with progress_report(episodes, f"training {agent.name}", hidden=as_json, unit="episodes") as bar:
            done = [0]

            def progress(n):
                bar.update(n - done[0])
                done[0] = n

            (stats,) = train_phases(
                agent,
                [(pipeline, episodes)],
                seed=seed,
                readings=reading,
                disturbance=disturbance,
                randomization=randomization,
                episode_seconds=seconds,
                progress=progress,
            )
        policy_path, curve_path = write_training_outputs(
            out, agent, stats, episodes, pipeline=pipe.name, seed=seed
        )
        if tensorboard_dir:
            from pipefollow.readings import sigma_scale

            _write_tensorboard(tensorboard_dir, stats, episodes, sigma_scale(reading))
    except BaseException as e:
        remove_empty_folders(out, made)  # an interrupted or failed run leaves no empty --out behind
        if isinstance(e, KeyboardInterrupt):
            click.echo(f"pipefollow: interrupted; nothing written to '{out_dir}'", err=True)
            sys.exit(130)
        raise
    result = {
        "algorithm": agent.name,
        "readings": reading.id,
        "policy": str(policy_path),
        "learning_curve": str(curve_path),
        "returns": stats[:, 0].tolist(),
        **{f"final_mean_{n}": float(stats[-min(50, episodes) :, i].mean()) for i, n in enumerate(STAT_NAMES)},
    }
    k = min(10, episodes)
    _echo_trained(
        result, disturbance, randomization, as_json,
        lambda: f"{agent.name}: mean return of the first {k} episodes {stats[:k, 0].mean():.2f}, "
        f"of the last {k} {stats[-k:, 0].mean():.2f}\npolicy: {policy_path}\nlearning curve: {curve_path}",
    )  # fmt: skip


def _write_tensorboard(folder, stats, episodes: int, scale: float) -> None:
    """Per-episode return, pipe in view, progress, time lost and σ (the schedule train used)."""
    from pipefollow.files.tensorboard import write_scalars
    from pipefollow.learners.exploration import linear_sigma
    from pipefollow.training.compiled import STAT_NAMES

    series = {name: stats[:, i] for i, name in enumerate(STAT_NAMES)}
    series["sigma"] = [linear_sigma(e, episodes, scale, 0.01 * scale) for e in range(episodes)]
    write_scalars(folder, series)


def _check_init_options(agent, reading, init_policy, skew, supervised) -> None:
    """``train --init``: the saved policy's --skew and --supervised unless given; differences named."""
    from click.core import ParameterSource

    from pipefollow.training.agents import make_agent

    ctx = click.get_current_context()
    given = {n for n in ("skew", "supervised") if ctx.get_parameter_source(n) == ParameterSource.COMMANDLINE}
    held = agent.params
    keep = supervised if "supervised" in given else bool(getattr(held, "supervised", False))
    skew_deg = skew if "skew" in given else 0.0
    wanted = make_agent(agent.algorithm, skew_deg=skew_deg, supervised=keep, readings=reading).params
    if "skew" not in given and "skew" in wanted._fields:
        wanted = wanted._replace(skew=held.skew)
    held = held._replace(**{k: getattr(wanted, k) for k in wanted._fields if k in _LEARNING_RATES})
    differ = [f"{f} {getattr(held, f)!r} (this run: {getattr(wanted, f)!r})" for f in wanted._fields
              if getattr(held, f) != getattr(wanted, f)]  # fmt: skip
    if differ:
        raise UserError(
            f"--init {init_policy}: holds a {agent.name} policy (readings '{agent.readings}') whose options "
            f"differ from this run's: {'; '.join(differ)}; give its options or none"
        )


def _train_deep(algorithm, pipeline, seconds, steps, seed, out_dir, as_json, disturbance, randomization=None):
    """``train --algorithm ppo|sac``: :func:`pipefollow.training.deep.train_to_folder`."""
    from click.core import ParameterSource

    ctx = click.get_current_context()
    option = {p.name: p.opts[0] for p in ctx.command.params}  # a parameter's name → its option
    given = [
        option[name]
        for name in ("skew", "supervised", "episodes", "init_policy", "readings")
        if ctx.get_parameter_source(name) == ParameterSource.COMMANDLINE
    ]
    if given:
        budget = "; its budget is --steps" if "--episodes" in given else ""
        raise UserError(f"{', '.join(given)} not available with --algorithm {algorithm}{budget}")
    try:
        from pipefollow.training import deep
    except ImportError as e:  # pipefollow.training.deep.DeepExtraMissing: torch or Stable-Baselines3 missing
        if type(e).__name__ != "DeepExtraMissing":
            raise
        raise UserError(str(e).split(" (")[0]) from None
    from pipefollow.sim.suites import resolve_training

    resolve_training(pipeline)  # a bad pipeline fails before any work
    out = writable_folder(out_dir, "--out")
    steps = 100_000 if steps is None else steps
    with progress_report(steps, f"training {algorithm.upper()}", hidden=as_json, unit="steps") as bar:
        done = [0]

        def progress(n):
            if n - done[0] >= 256 or n >= steps:
                bar.update(min(n, steps) - done[0])
                done[0] = min(n, steps)

        extra = {} if disturbance == _disturbance.NO_DISTURBANCE else {"disturbance": disturbance}
        if randomization is not None:
            extra["randomization"] = randomization
        result = deep.train_to_folder(
            algorithm, pipeline, out, steps=steps, seconds=seconds, seed=seed, progress=progress, **extra
        )
    r = result["returns"]
    k = min(10, len(r))
    _echo_trained(
        result, disturbance, randomization, as_json,
        lambda: f"{algorithm.upper()}: {result['steps']} steps in {result['wall_s']:.1f} s; "
        f"mean return of the first {k} episodes {np.mean(r[:k]) if k else float('nan'):.2f}, of the last {k} "
        f"{np.mean(r[-k:]) if k else float('nan'):.2f}\n"
        f"policy: {result['policy']}\nhyper-parameters: {result['hyperparameters']}",
    )  # fmt: skip


def _echo_trained(result: dict, disturbance, randomization, as_json: bool, text) -> None:
    """Print a training's ``result`` (with its disturbance and randomization, if any) or ``text()``."""
    if disturbance != _disturbance.NO_DISTURBANCE:
        result["disturbance"] = _disturbance.to_dict(disturbance)
    if randomization is not None:
        from pipefollow.sim.randomization import to_dict

        result["randomization"] = to_dict(randomization)
    echo_result(result, as_json, text)
