"""The ``pipefollow`` command line."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click
import numpy as np

from pipefollow import disturbance as _disturbance
from pipefollow.disturbance import DisturbanceError
from pipefollow.experiments.config import MAX_EPISODES, MAX_SECONDS, ConfigError
from pipefollow.experiments.store import StoreError
from pipefollow.pipeline import PipelineError
from pipefollow.policy import PolicyError

USER_ERRORS: tuple[type[Exception], ...] = (
    PipelineError,
    PolicyError,
    ConfigError,
    StoreError,
    DisturbanceError,
)


class UserError(click.ClickException):
    """A one-line error about the user's input, exit status 2."""

    exit_code = 2

    def show(self, file=None) -> None:  # noqa: D102
        click.echo(f"pipefollow: error: {self.message}", err=True)


def _is_path_error(e: OSError) -> bool:
    """An error about a file or folder the user named (not an internal failure)."""
    import errno

    path_errors = (PermissionError, IsADirectoryError, NotADirectoryError, FileNotFoundError, FileExistsError)
    return isinstance(e, path_errors) or e.errno in (errno.ENOSPC, errno.EROFS, errno.ENAMETOOLONG)


def _guard(fn):
    """Turn the library's input errors into one-line CLI errors (exit 2, no traceback)."""
    import functools

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except USER_ERRORS as e:
            raise UserError(str(e)) from None
        except OSError as e:
            if not _is_path_error(e):
                raise
            name = e.filename2 or e.filename  # for a failed rename, the target
            where = f"'{name}': " if name else ""
            raise UserError(f"{where}{e.strerror or e}") from None

    return wrapper


class _OneLineErrors(click.Group):
    """Click's own usage errors (a bad option value, a missing option) on one line, exit 2."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.exceptions.Abort:
            click.echo("pipefollow: aborted", err=True)
            sys.exit(1)
        except click.ClickException as e:
            if isinstance(e, UserError):
                e.show()
            else:
                click.echo(f"pipefollow: error: {e.format_message()}", err=True)
            sys.exit(e.exit_code)
        sys.exit(rv if isinstance(rv, int) else 0)


def _finite(ctx, param, value):
    """Reject NaN and infinity, which click's ranges let through."""
    import math

    if value is not None and not math.isfinite(value):
        raise click.BadParameter(f"{value} is not a finite number", ctx=ctx, param=param)
    return value


@click.group(
    cls=_OneLineErrors,
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100},
)
@click.version_option(package_name="pipefollow")
def main() -> None:
    """Learn and evaluate AUV pipeline-following controllers (Fjerdingen et al., 2010)."""


def _writable_folder(path: str, option: str) -> Path:
    """Create the folder and check that files can be written there, before any long work."""
    import os
    import tempfile

    folder = Path(path)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".pipefollow-probe-")
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        raise UserError(f"{option} '{path}': cannot write there ({e.strerror or e})") from None
    return folder


def _reading_option(help_text: str):
    """``--reading ID`` (repeatable): readings of the paper's open points, ``key=value[,key=value]``."""
    return click.option("--reading", "readings", multiple=True, metavar="ID", help=help_text)


def _readings(ids, base: str = "default"):
    """The readings ``base`` (an id) changed by the ``--reading`` ids; a one-line error if malformed."""
    from pipefollow import readings as rd

    try:
        return rd.parse(ids, rd.parse(base, source="policy readings"), source="--reading")
    except rd.ReadingError as e:
        raise UserError(str(e)) from None


def _default_seconds(pipeline: str, seconds: float | None) -> float:
    if seconds is not None:
        return seconds
    return 60.0 if pipeline == "paper-validation" else 20.0


_LEARNING_RATES = ("alpha_v", "alpha_pi", "discount", "delta_k", "k_max", "forgetting")  # not train options


def load_controller(spec: str, seed: int, lookahead: float | None = None):
    """``heuristic``, ``los`` (lookahead Δ in m) or a policy file → an agent."""
    if lookahead is not None and spec != "los":
        raise UserError("--lookahead applies to --controller los only")
    if spec == "heuristic":
        from pipefollow.heuristic import Heuristic

        return Heuristic()
    if spec == "los":
        from pipefollow.los import DEFAULT_LOOKAHEAD, LOS

        return LOS(DEFAULT_LOOKAHEAD if lookahead is None else lookahead)
    from pipefollow.policy import load_policy

    return load_policy(spec, seed=seed)


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


@main.command()
@click.option(
    "--controller",
    default="heuristic",
    show_default=True,
    help="'heuristic', 'los' (line-of-sight guidance) or a policy file (.npz) written by 'pipefollow train'.",
)
@click.option(
    "--lookahead",
    type=click.FloatRange(min=0.0, min_open=True),
    callback=_finite,
    default=None,
    help="Lookahead distance Δ (m) of --controller los [default: 1.5].",
)
@click.option(
    "--pipeline",
    default="paper-left",
    show_default=True,
    help="Built-in name (paper-left, paper-right, paper-validation) or a JSON file.",
)
@click.option("--episodes", default=1, show_default=True, type=click.IntRange(min=1, max=MAX_EPISODES))
@click.option(
    "--seconds",
    type=click.FloatRange(min=1.0, max=MAX_SECONDS),
    callback=_finite,
    default=None,
    help="Episode length in seconds [default: 60 on paper-validation, else 20].",
)
@click.option("--seed", default=0, show_default=True, type=int, help="Seed of the start perturbation.")
@click.option(
    "--start-noise",
    default=0.0,
    show_default=True,
    type=click.FloatRange(min=0.0),
    callback=_finite,
    help="Uniform random lateral start offset up to this many metres.",
)
@click.option(
    "--heading-noise",
    default=0.0,
    show_default=True,
    type=click.FloatRange(min=0.0),
    callback=_finite,
    help="Uniform random start heading offset up to this many degrees.",
)
@click.option(
    "--plot",
    "plot_path",
    type=click.Path(dir_okay=False),
    default=None,
    help="Save a trajectory plot (PNG) of the first episode.",
)
@_reading_option("Reading of an open point, e.g. start_speed=cruise (repeatable) [default: the policy's].")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of a table.")
@_disturbance.click_options
@_guard
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
    readings,
    as_json,
    disturbance,
):
    """Evaluate a controller deterministically (σ = 0) on a pipeline."""
    from pipefollow.env import PipelineFollowingEnv
    from pipefollow.pipeline import resolve
    from pipefollow.readings import sim_params
    from pipefollow.training import run_episode

    pipe = resolve(pipeline)
    agent = load_controller(controller, seed, lookahead)
    reading = _readings(readings, getattr(agent, "readings", "default"))
    env = PipelineFollowingEnv(
        pipe,
        _default_seconds(pipeline, seconds),
        start_noise,
        heading_noise,
        params=sim_params(reading)._replace(disturbance=disturbance),
    )
    stats = []
    for e in range(episodes):
        stats.append(run_episode(env, agent, seed=seed if e == 0 else None))
    result = {
        "controller": controller,
        "pipeline": pipeline,
        "seconds": env.episode_seconds,
        "readings": reading.id,
        **_summary(stats),
    }
    if disturbance != _disturbance.NO_DISTURBANCE:
        result["disturbance"] = _disturbance.to_dict(disturbance)
    if plot_path:
        from pipefollow.render import plot_trajectories

        name = "heuristic" if controller == "heuristic" else Path(controller).stem
        plot_trajectories(
            pipe, {name: stats[0].poses}, plot_path, title=f"{name} on {pipe.name}: return {stats[0].ret:.2f}"
        )
        result["plot"] = str(plot_path)
    if as_json:
        click.echo(json.dumps(result))
        return
    click.echo(f"{controller} on {pipeline}, {episodes} episode(s) of {env.episode_seconds:g} s")
    click.echo(f"{'episode':>7} {'return':>9} {'in view':>8} {'progress':>9}")
    for i, row in enumerate(result["episodes"]):
        click.echo(f"{i:>7} {row['return']:>9.3f} {row['pipe_in_view']:>8.1%} {row['progress_m']:>8.2f}m")
    click.echo(
        f"{'mean':>7} {result['mean_return']:>9.3f} {result['mean_pipe_in_view']:>8.1%} "
        f"{result['mean_progress_m']:>8.2f}m"
    )
    if plot_path:
        click.echo(f"plot: {plot_path}")


@main.command()
@click.option(
    "--algorithm",
    type=click.Choice(["sarsa", "cacla", "ppo", "sac"]),
    required=True,
    help="The paper's learners, or PPO / SAC from Stable-Baselines3 (extra 'deep').",
)
@click.option(
    "--skew",
    type=click.FloatRange(min=0.0, max=180.0),
    callback=_finite,
    default=0.0,
    show_default=True,
    help="CACLA skew step Δγ in degrees (eq. 15): 11.25, 22.5 or 45 in the paper; 0 = Gaussian.",
)
@click.option("--supervised", is_flag=True, help="Supervised CACLA with the heuristic as supervisor.")
@click.option(
    "--pipeline",
    default="paper-left",
    show_default=True,
    help="Built-in name or JSON file to train on, or random[:FAMILY] for a new pipe every episode "
    "(families: see 'pipefollow suites'; random = random:mixed).",
)
@click.option("--episodes", default=500, show_default=True, type=click.IntRange(min=1, max=MAX_EPISODES))
@click.option(
    "--seconds",
    default=20.0,
    show_default=True,
    type=click.FloatRange(min=1.0, max=MAX_SECONDS),
    callback=_finite,
    help="Episode length in seconds.",
)
@click.option(
    "--steps",
    type=click.IntRange(min=1, max=100_000_000),
    default=None,
    help="PPO and SAC: budget in environment steps (decisions) [default: 100,000].",
)
@click.option("--seed", default=0, show_default=True, type=int)
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False),
    required=True,
    help="Folder for policy.npz and learning_curve.csv.",
)
@click.option(
    "--init",
    "init_policy",
    type=click.Path(dir_okay=False),
    default=None,
    help="Continue training from this policy file (e.g. left turns, then right turns).",
)
@_reading_option(
    "Reading of an open point, e.g. skew_step=weights or skew_sample=centred (repeatable; "
    "see docs/design.md) [default: the project's readings, or those of --init]."
)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object at the end.")
@_disturbance.click_options
@_guard
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
    readings,
    as_json,
    disturbance,
):
    """Train a learner; writes the policy and its learning curve."""
    if algorithm in ("ppo", "sac"):
        return _train_deep(algorithm, pipeline, seconds, steps, seed, out_dir, as_json, disturbance)
    if steps is not None:
        raise UserError("--steps applies to --algorithm ppo and sac only (use --episodes)")
    from pipefollow.agents import make_agent
    from pipefollow.readings import cacla_params, sigma_scale, sim_params
    from pipefollow.suites import Suite, resolve_training
    from pipefollow.training import STAT_NAMES, train_compiled, train_random_compiled

    if algorithm == "sarsa" and (skew or supervised):
        raise UserError("--skew and --supervised apply to --algorithm cacla only")
    pipe = resolve_training(pipeline)  # a Pipeline, or a Suite for random[:FAMILY]
    rng = np.random.default_rng(seed)
    if init_policy:
        from pipefollow.policy import load_policy

        agent = load_policy(init_policy)
        reading = _readings(readings, agent.readings)
        if agent.algorithm != algorithm:
            raise UserError(f"--init {init_policy}: holds a {agent.name} policy, not {algorithm}")
        if algorithm == "cacla":
            wanted = cacla_params(reading, skew, supervised=supervised)
            held = agent.params._replace(**{k: getattr(wanted, k) for k in _LEARNING_RATES})
            if held != wanted:
                raise UserError(
                    f"--init {init_policy}: holds a {agent.name} policy under readings "
                    f"'{agent.readings}'; its options differ from these"
                )
        agent.readings = reading.id
        agent.rng = rng
    else:
        reading = _readings(readings)
        agent = make_agent(algorithm, skew_deg=skew, supervised=supervised, rng=rng, readings=reading)
    out = _writable_folder(out_dir, "--out")  # before training, after the checks of --init
    show = not as_json and sys.stderr.isatty()
    with click.progressbar(
        length=episodes, label=f"training {agent.name}", file=sys.stderr, hidden=not show
    ) as bar:
        done = [0]

        def progress(n):
            bar.update(n - done[0])
            done[0] = n

        scale = sigma_scale(reading)
        schedule = dict(
            episode_seconds=seconds,
            sigma_start=scale,
            sigma_end=0.01 * scale,
            params=sim_params(reading)._replace(disturbance=disturbance),
            env_rng=np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0]),
            progress=progress,
        )
        if isinstance(pipe, Suite):  # a new pipe every episode, from a child of the seed's generator
            stats = train_random_compiled(agent, pipe, episodes, pipe_rng=rng.spawn(1)[0], **schedule)
        else:
            stats = train_compiled(agent, pipe, episodes, **schedule)
    from pipefollow.policy import save_policy
    from pipefollow.results import write_learning_curve

    policy_path = save_policy(agent, out / "policy.npz", pipeline=pipe.name, episodes=episodes, seed=seed)
    curve_path = write_learning_curve(out / "learning_curve.csv", stats, episodes)
    result = {
        "algorithm": agent.name,
        "readings": reading.id,
        "policy": str(policy_path),
        "learning_curve": str(curve_path),
        "returns": stats[:, 0].tolist(),
        **{f"final_mean_{n}": float(stats[-min(50, episodes) :, i].mean()) for i, n in enumerate(STAT_NAMES)},
    }
    if disturbance != _disturbance.NO_DISTURBANCE:
        result["disturbance"] = _disturbance.to_dict(disturbance)
    if as_json:
        click.echo(json.dumps(result))
        return
    k = min(10, episodes)
    click.echo(
        f"{agent.name}: mean return of the first {k} episodes {stats[:k, 0].mean():.2f}, "
        f"of the last {k} {stats[-k:, 0].mean():.2f}"
    )
    click.echo(f"policy: {policy_path}\nlearning curve: {curve_path}")


def _train_deep(algorithm, pipeline, seconds, steps, seed, out_dir, as_json, disturbance) -> None:
    """``train --algorithm ppo|sac``: :func:`pipefollow.deep.train_to_folder`."""
    from click.core import ParameterSource

    ctx = click.get_current_context()
    given = [
        f"--{name.replace('_', '-')}"
        for name in ("skew", "supervised", "episodes", "init_policy", "readings")
        if ctx.get_parameter_source(name) == ParameterSource.COMMANDLINE
    ]
    if given:
        raise UserError(f"{', '.join(given)} not available with --algorithm {algorithm} (see --steps)")
    try:
        from pipefollow import deep
    except ImportError as e:  # pipefollow.deep.DeepExtraMissing: torch or Stable-Baselines3 missing
        if type(e).__name__ != "DeepExtraMissing":
            raise
        raise UserError(str(e).split(" (")[0]) from None
    from pipefollow.suites import resolve_training

    resolve_training(pipeline)  # a bad pipeline fails before any work
    out = _writable_folder(out_dir, "--out")
    steps = 100_000 if steps is None else steps
    show = not as_json and sys.stderr.isatty()
    label = f"training {algorithm.upper()}"
    with click.progressbar(length=steps, label=label, file=sys.stderr, hidden=not show) as bar:
        done = [0]

        def progress(n):
            if n - done[0] >= 256 or n >= steps:
                bar.update(min(n, steps) - done[0])
                done[0] = min(n, steps)

        extra = {} if disturbance == _disturbance.NO_DISTURBANCE else {"disturbance": disturbance}
        result = deep.train_to_folder(
            algorithm, pipeline, out, steps=steps, seconds=seconds, seed=seed, progress=progress, **extra
        )
    if disturbance != _disturbance.NO_DISTURBANCE:
        result["disturbance"] = _disturbance.to_dict(disturbance)
    if as_json:
        click.echo(json.dumps(result))
        return
    r = result["returns"]
    k = min(10, len(r))
    click.echo(
        f"{algorithm.upper()}: {result['steps']} steps in {result['wall_s']:.1f} s; mean return of the "
        f"first {k} episodes {np.mean(r[:k]) if k else float('nan'):.2f}, of the last {k} "
        f"{np.mean(r[-k:]) if k else float('nan'):.2f}"
    )
    click.echo(f"policy: {result['policy']}\nhyper-parameters: {result['hyperparameters']}")


def _write_figures(run_dir: Path, required: bool) -> list[Path]:
    """Figures and REPORT.md through ``pipefollow.experiments.report``, if that module exists."""
    try:
        from pipefollow.experiments import report
    except ModuleNotFoundError as e:
        if e.name != "pipefollow.experiments.report":
            raise
        if required:
            raise click.ClickException(
                "figures need pipefollow.experiments.report, which is missing"
            ) from None
        click.echo("note: figures skipped (pipefollow.experiments.report is not available)", err=True)
        return []
    return [Path(p) for p in report.write_outputs(run_dir)]


@main.command()
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False),
    default=None,
    help="Run folder; running again with the same options resumes. "
    "[default: ./reproduction, ./reproduction-quick with --quick]",
)
@click.option(
    "--backend",
    default="process",
    show_default=True,
    metavar="serial|process|ray",
    help="Where trials run: in this process, in a local process pool, or on Ray.",
)
@click.option(
    "--workers",
    type=click.IntRange(min=1),
    default=None,
    help="Trials at the same time [default: all cores].",
)
@click.option(
    "--ray-address", default=None, help="Address of a running Ray cluster [default: a local instance]."
)
@click.option(
    "--repeats",
    type=click.IntRange(min=1),
    default=None,
    help="Repeats (seeds) of every trial [default: the experiment's, 5 for the paper].",
)
@click.option(
    "--episodes",
    type=click.IntRange(min=1),
    default=None,
    help="Episodes of every training phase [default: the experiment's, 500 for the paper].",
)
@click.option(
    "--seed", type=int, default=None, help="Seed of the first repeat [default: 2010 for the paper]."
)
@click.option(
    "--experiment",
    default="paper",
    show_default=True,
    help="A shipped experiment ('paper'; 'readings': the claims under each reading of the paper's open "
    "points) or an experiment TOML file.",
)
@click.option(
    "--trial",
    "trials",
    multiple=True,
    metavar="NAME",
    help="Run only this trial (repeatable) [default: all].",
)
@click.option(
    "--quick",
    is_flag=True,
    help="Small smoke-test version: 2 repeats, 30 episodes per phase, --out ./reproduction-quick.",
)
@_reading_option("Reading of an open point applied to every trial, e.g. start_speed=cruise (repeatable).")
@click.option("--no-figures", is_flag=True, help="Do not draw figures and REPORT.md.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object at the end.")
@_guard
def reproduce(
    out_dir,
    backend,
    workers,
    ray_address,
    repeats,
    episodes,
    seed,
    experiment,
    trials,
    quick,
    readings,
    no_figures,
    as_json,
):
    """Reproduce the paper's experiments: train every trial × seed, store results, draw the figures.

    The run folder holds config.json, one file per finished trial (trials/), the learned policies
    (policies/), results.csv and evaluation.csv (tidy tables for pandas), and the figures and
    REPORT.md. An interrupted run resumes where it stopped when started again with the same options.
    """
    from pipefollow.experiments import sensitivity
    from pipefollow.experiments.config import load_experiment, with_overrides
    from pipefollow.experiments.runner import RunInterrupted, run_experiment
    from pipefollow.experiments.store import summary

    if quick:
        repeats = 2 if repeats is None else repeats
        episodes = 30 if episodes is None else episodes
    base = load_experiment(experiment)
    exp = with_overrides(
        base, repeats=repeats, episodes=episodes, seed=seed, trials=list(trials), readings=list(readings)
    )
    exp = sensitivity.expand(exp)
    if not out_dir:
        stem = "reproduction" if base.name == "paper" else f"reproduction-{base.name}"
        out_dir = f"{stem}-quick" if quick else stem
    out = Path(out_dir)
    try:
        run = run_experiment(
            exp, out, backend=backend, workers=workers, ray_address=ray_address, show_progress=not as_json
        )
    except RunInterrupted as e:
        click.echo(f"pipefollow: {e.message}", err=True)
        sys.exit(130)
    outputs = list(run.tables)
    if not no_figures:
        outputs += _write_figures(run.run_dir, required=False)
    per_trial = summary(run.run_dir, exp)
    if as_json:
        click.echo(
            json.dumps(
                {
                    "run_dir": str(run.run_dir),
                    "backend": run.backend,
                    "workers": run.workers,
                    "trials_total": run.trials_total,
                    "trials_computed": run.trials_computed,
                    "trials_reused": run.trials_reused,
                    "wall_seconds": run.wall_seconds,
                    "outputs": [str(p) for p in outputs],
                    "trials": per_trial,
                }
            )
        )
        return
    click.echo(
        f"{exp.name}: {run.trials_total} trials ({run.trials_computed} computed, {run.trials_reused} reused) "
        f"in {run.wall_seconds:.1f} s, backend {run.backend} ({run.workers} workers)"
    )
    if exp.compare_readings:
        _echo_sensitivity(run.run_dir, outputs)
        return
    width = max(len(r["label"]) for r in per_trial.values()) if per_trial else 5
    click.echo(f"{'trial':<{width}}  {'return, last 50 (mean ± sd over seeds)':>38}  {'in view':>7}")
    for row in per_trial.values():
        ret = f"{row['mean_return_last50']:.2f} ± {row['std_return_last50']:.2f}"
        click.echo(f"{row['label']:<{width}}  {ret:>38}  {row['mean_pipe_in_view_last50']:>7.1%}")
    for name, row in per_trial.items():
        if exp.trial(name).evaluate_on:
            evals = ", ".join(f"{c} {v:.2f}" for c, v in row["evaluation_mean_return"].items())
            click.echo(f"{row['label']} on {row['evaluation_pipeline']} (mean return): {evals}")
    for p in outputs:
        click.echo(f"wrote {p}")


def _echo_sensitivity(run_dir: Path, outputs: list[Path]) -> None:
    """The per-claim lines of a sensitivity study."""
    from pipefollow.experiments import sensitivity

    s = sensitivity.load(run_dir)
    for claim in s.claim_ids():
        click.echo(f"claim {claim}: {s.verdict_line(claim)}")
    for p in outputs:
        click.echo(f"wrote {p}")


@main.command()
@click.argument("run_dir", type=click.Path(file_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object: the files written.")
@_guard
def plot(run_dir, as_json):
    """Redraw all figures and REPORT.md of a run folder from its stored results."""
    from pipefollow.experiments.store import read_config

    read_config(run_dir)  # a one-line error if RUN_DIR is not a run folder
    outputs = _write_figures(Path(run_dir), required=True)
    if as_json:
        click.echo(json.dumps({"run_dir": str(run_dir), "outputs": [str(p) for p in outputs]}))
        return
    for p in outputs:
        click.echo(f"wrote {p}")


@main.group(invoke_without_command=True)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of a table.")
@click.pass_context
def suites(ctx, as_json):
    """List the pipeline suites: training families and held-out test suites."""
    if ctx.invoked_subcommand is not None:
        return
    from pipefollow.suites import SUITES

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
@click.option(
    "--pipes",
    type=click.IntRange(min=1, max=100_000),
    default=None,
    help="Number of pipes [default: all of a held-out suite, 100 of a training family].",
)
@click.option(
    "--seconds",
    type=click.FloatRange(min=1.0, max=MAX_SECONDS),
    callback=_finite,
    default=60.0,
    show_default=True,
    help="Episode length the pipes must be long enough for.",
)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object: the files written.")
@_guard
def suites_export(name, out_dir, pipes, seconds, as_json):
    """Write the pipes of suite NAME as pipeline JSON files (NAME-000.json, ...)."""
    from pipefollow.suites import export_suite, get_suite, min_length_for

    suite = get_suite(name)
    n = pipes if pipes is not None else (suite.count or 100)
    if suite.count is not None and n > suite.count:
        raise UserError(f"--pipes {n}: suite '{name}' has {suite.count} pipes")
    out = _writable_folder(out_dir, "--out")
    paths = export_suite(suite, out, n, min_length_for(seconds))
    if as_json:
        click.echo(json.dumps({"suite": name, "files": [str(p) for p in paths]}))
        return
    click.echo(f"wrote {len(paths)} pipes of '{name}' to {out}")


def _benchmark_params():
    """The simulated system of a benchmark's episodes.

    Disturbance options of ``benchmark`` (current, camera noise, missed detections) are turned
    into fields of the returned :class:`~pipefollow.simulation.SimParams` here.
    """
    from pipefollow.simulation import PAPER_SIM

    return PAPER_SIM


@main.command()
@click.option(
    "--controller",
    default="heuristic",
    show_default=True,
    help="'heuristic' or a policy file (.npz) written by 'pipefollow train'.",
)
@click.option(
    "--suite", "suite_name", default="heldout", show_default=True, help="Suite (see 'pipefollow suites')."
)
@click.option(
    "--seconds",
    type=click.FloatRange(min=1.0, max=MAX_SECONDS),
    callback=_finite,
    default=60.0,
    show_default=True,
    help="Episode length in seconds.",
)
@click.option(
    "--pipes",
    type=click.IntRange(min=1, max=100_000),
    default=None,
    help="Number of pipes [default: all of a held-out suite, 100 of a training family].",
)
@click.option("--seed", default=0, show_default=True, type=int, help="Seed of the bootstrap resampling.")
@click.option(
    "--plot",
    "plot_path",
    type=click.Path(dir_okay=False),
    default=None,
    help="Save a PNG: per-pipe return differences to the heuristic and a few trajectories.",
)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of a table.")
@_guard
def benchmark(controller, suite_name, seconds, pipes, seed, plot_path, as_json):
    """Run a controller deterministically on every pipe of a suite, beside the heuristic.

    Reports the mean return with a bootstrap 95 % confidence interval, the interquartile mean,
    the success rate (pipe in view at ≥ 95 % of the decisions) and, for a controller other than
    the heuristic, the paired per-pipe difference to the heuristic with its confidence interval.
    """
    from pipefollow.benchmark import benchmark as run_benchmark
    from pipefollow.benchmark import format_summary
    from pipefollow.benchmark import load_controller as load_benchmark_controller
    from pipefollow.suites import get_suite

    suite = get_suite(suite_name)
    if suite.count is not None and pipes is not None and pipes > suite.count:
        raise UserError(f"--pipes {pipes}: suite '{suite_name}' has {suite.count} pipes")
    agent = load_benchmark_controller(controller, seed)
    run = run_benchmark(
        agent,
        suite,
        controller=controller,
        seconds=seconds,
        params=_benchmark_params(),
        n_pipes=pipes,
        seed=seed,
    )
    if plot_path:
        from pipefollow.benchmark_plot import plot_benchmark

        plot_benchmark(run, plot_path)
    if as_json:
        click.echo(json.dumps(run.summary))
        return
    click.echo(format_summary(run.summary, seconds))
    if plot_path:
        click.echo(f"plot: {plot_path}")


if __name__ == "__main__":  # pragma: no cover
    main()
