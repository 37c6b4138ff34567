"""A learner of the registry trained into a folder: ``policy.npz``, ``learning_curve.csv``, TensorBoard.

What ``pipefollow train --algorithm sarsa|cacla|ac`` does once its options are checked: make the
agent (or continue a saved one: ``--init``), train it through
:func:`~pipefollow.training.phases.train_phases`, write its files (:func:`train_into`) and
summarise the run (:class:`LearnerRun`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipefollow import readings as rd
from pipefollow.files.paper_training import EPISODE_SECONDS, TRAINING_EPISODES
from pipefollow.learners.exploration import SIGMA_END, SIGMA_START
from pipefollow.learners.registry import learner
from pipefollow.sim.disturbance import NO_DISTURBANCE, Disturbance
from pipefollow.sim.episode import TRAINING_STAT_NAMES
from pipefollow.training.phases import phase_sigmas, train_phases


def step_sizes(algorithm: str) -> tuple[str, ...]:
    """The fields of a learner's parameter record that are its step sizes and discount (the registry's)."""
    return tuple(learner(algorithm).step_sizes.values())


def new_agent(
    algorithm: str, seed: int, reading: rd.Readings, skew_deg: float = 0.0, supervised: bool = False,
    **options,
):  # fmt: skip
    """A fresh agent of ``algorithm`` under ``reading``, its generator that of a run with ``seed``.

    ``options`` are more values of :data:`~pipefollow.learners.options.LEARNER_OPTIONS` (by their
    names: ``critic_lambda``, ``alpha_v``, ``state``, …), read by
    :func:`~pipefollow.learners.registry.agent_options` as experiment trials read theirs.
    """
    from pipefollow.learners.registry import agent_options
    from pipefollow.training.agents import make_agent
    from pipefollow.training.phases import agent_rng

    values = agent_options(algorithm, {"skew_deg": skew_deg, "supervised": supervised, **options})
    return make_agent(algorithm, rng=agent_rng(seed), readings=reading, **values)


def run_options(agent, given: dict) -> dict:
    """The learner options of a run of ``agent``: every option of the table its learner takes.

    ``given`` (option → value) wins over what the agent's record holds (:func:`saved_options`, its
    skew step in degrees), that over the defaults; the σ schedule's defaults are the paper's.
    """
    from pipefollow.learners.options import LEARNER_OPTIONS
    from pipefollow.learners.registry import learner_of, takes

    kind = learner_of(agent)
    held = saved_options(agent)
    if "skew" in agent.params._fields:
        held["skew_deg"] = _skew_deg(agent)
    taken = [o for o in LEARNER_OPTIONS if takes(kind, o.name)]
    return {o.name: given.get(o.name, held.get(o.name, o.default)) for o in taken}


def _skew_deg(agent) -> float:
    """The skew step of ``agent``'s record in degrees, under its readings' ``skew_unit``."""
    import math

    from pipefollow.learners.exploration import DEGREES_PER_GAMMA

    skew = float(agent.params.skew)
    return math.degrees(skew) if rd.parse(agent.readings).skew_unit == "rad" else skew * DEGREES_PER_GAMMA


def saved_options(agent) -> dict:
    """The learner options a saved ``agent`` holds, read from its record (skew and σ excepted).

    Switches and step sizes of its learner (:func:`~pipefollow.learners.registry.takes`) by the
    record's fields (a code by its name), and its state. The skew step is kept as the record holds
    it (its unit depends on the readings); the σ schedule is not in the record.
    """
    from pipefollow.learners.actor_critic import ACTOR_UPDATES
    from pipefollow.learners.cacla_update import ACTOR_REPEATS
    from pipefollow.learners.options import LEARNER_OPTIONS
    from pipefollow.learners.registry import takes

    kind, held = learner(agent.algorithm), agent.params
    names = {"actor_repeats": ACTOR_REPEATS, "actor_update": ACTOR_UPDATES}
    out = {}
    for o in LEARNER_OPTIONS:
        if not takes(kind, o.name) or o.group in ("schedule", "state") or o.name == "skew_deg":
            continue
        value = getattr(held, kind.step_sizes.get(o.name, o.name))
        if o.name in names:
            value = {code: name for name, code in names[o.name].items()}[int(value)]
        out[o.name] = bool(value) if o.kind is bool else value
    out["state"] = agent.state
    return out


def option_differences(
    agent, reading: rd.Readings, skew_deg: float | None = None, supervised: bool | None = None, **given
) -> list[str]:
    """How a saved ``agent``'s options differ from those of a run continuing it; empty if they agree.

    ``skew_deg``, ``supervised`` and ``given`` (more options of the table by name) are the run's;
    the options not given are the saved agent's (:func:`saved_options`). Each difference reads
    ``field saved (this run: wanted)``, over the fields of the learner's record and its state.
    """
    from pipefollow.learners.registry import agent_options
    from pipefollow.training.agents import make_agent

    held = agent.params
    if skew_deg is not None:
        given["skew_deg"] = skew_deg
    if supervised is not None:
        given["supervised"] = supervised
    values = {**saved_options(agent), **given}
    values = {k: v for k, v in values.items() if k not in ("sigma_start", "sigma_end")}
    wanted = make_agent(agent.algorithm, readings=reading, **agent_options(agent.algorithm, values))
    if "skew_deg" not in given and "skew" in wanted.params._fields:
        wanted.params = wanted.params._replace(skew=held.skew)
    out = [
        f"{f} {getattr(held, f)!r} (this run: {getattr(wanted.params, f)!r})"
        for f in wanted.params._fields
        if getattr(held, f) != getattr(wanted.params, f)
    ]
    if wanted.state != agent.state:
        out.append(f"state {agent.state!r} (this run: {wanted.state!r})")
    return out


def write_tensorboard(folder, stats: np.ndarray, sigmas: np.ndarray) -> None:
    """Per-episode return, pipe in view, progress, time lost and σ (``sigmas``: the schedule trained with)."""
    from pipefollow.files.tensorboard import write_scalars

    series = {name: stats[:, i] for i, name in enumerate(TRAINING_STAT_NAMES)}
    series["sigma"] = list(sigmas)
    write_scalars(folder, series)


@dataclass(frozen=True)
class LearnerRun:
    """A finished training written into a folder.

    Attributes:
        agent: the trained agent.
        readings: the readings it trained under.
        stats: one row of :data:`~pipefollow.sim.episode.TRAINING_STAT_NAMES` per episode.
        policy: the policy file written.
        learning_curve: the learning curve written.
    """

    agent: object
    readings: rd.Readings
    stats: np.ndarray
    policy: Path
    learning_curve: Path
    options: dict  # the learner options it trained with (run_options)

    def summary(self) -> dict:
        """The run as one JSON object: files, returns, and the means of the last 50 episodes."""
        stats, last = self.stats, min(50, len(self.stats))
        return {
            "algorithm": self.agent.name,
            "readings": self.readings.id,
            "options": self.options,
            "policy": str(self.policy),
            "learning_curve": str(self.learning_curve),
            "returns": stats[:, 0].tolist(),
            **{f"final_mean_{n}": float(stats[-last:, i].mean()) for i, n in enumerate(TRAINING_STAT_NAMES)},
        }

    def text(self) -> str:
        """The run in three lines: mean returns of the first and last episodes, the files."""
        stats = self.stats
        k = min(10, len(stats))
        from pipefollow.learners.options import describe

        options = describe(self.options) or "the paper's"
        return (
            f"{self.agent.name}: mean return of the first {k} episodes {stats[:k, 0].mean():.2f}, "
            f"of the last {k} {stats[-k:, 0].mean():.2f}\noptions: {options}\n"
            f"policy: {self.policy}\nlearning curve: {self.learning_curve}"
        )


def train_into(
    out: Path,
    agent,
    pipeline: str,
    episodes: int = TRAINING_EPISODES,
    *,
    seed: int,
    readings: rd.Readings = rd.DEFAULT,
    disturbance: Disturbance = NO_DISTURBANCE,
    randomization=None,
    seconds: float = EPISODE_SECONDS,
    progress: Callable[[int], None] | None = None,
    tensorboard: str | Path | None = None,
    made: Path | None = None,
    sigma_start: float = SIGMA_START,
    sigma_end: float = SIGMA_END,
    options: dict | None = None,
    camera: dict | None = None,
) -> LearnerRun:
    """Train ``agent`` on ``pipeline`` for ``episodes`` and write its policy and learning curve into ``out``.

    Args:
        out: an existing, writable folder.
        agent: an agent of the registry, its ``rng`` from :func:`~pipefollow.training.phases.agent_rng`.
        pipeline: a built-in name, a JSON file or ``random[:FAMILY]``.
        episodes: training episodes (σ falls linearly over them: :func:`.phases.phase_sigmas`).
        seed: the run's seed (random pipes and disturbances; recorded in the policy file).
        readings: the readings it trains under.
        disturbance: fixed disturbances, or
        randomization: each episode's disturbances drawn from this (not both).
        seconds: episode length (s).
        progress: called with the episodes done.
        tensorboard: a folder for TensorBoard scalars, or None.
        made: the outermost folder of ``out`` the caller created: removed again, if empty, when
            training fails or is interrupted.
        sigma_start: σ of the first episode (the paper's units, :func:`.phases.phase_sigmas`), and
        sigma_end: of the last.
        options: the learner options given for the run (option → value): stored with the policy,
            completed by :func:`run_options`.
        camera: the environment's camera arguments (``camera``, ``water``, ``sensor``) to train
            through (:mod:`pipefollow.training.through_env`); None: the ideal camera's compiled loop.
    """
    from pipefollow.files.output_paths import remove_empty_folders
    from pipefollow.sim.pipe_names import resolve_training
    from pipefollow.training.outputs import write_training_outputs
    from pipefollow.training.policy_files import trained_through

    try:
        (stats,) = train_phases(
            agent,
            [(pipeline, episodes)],
            seed=seed,
            readings=readings,
            disturbance=disturbance,
            randomization=randomization,
            episode_seconds=seconds,
            sigma_start=sigma_start,
            sigma_end=sigma_end,
            progress=progress,
            camera=camera,
        )
        name = resolve_training(pipeline).name
        sigmas = phase_sigmas(episodes, readings, sigma_start, sigma_end)  # the σ train_phases trained with
        values = run_options(agent, {**(options or {}), "sigma_start": sigma_start, "sigma_end": sigma_end})
        through = {} if camera is None else {"trained_through": trained_through(camera)}
        policy, curve = write_training_outputs(
            out, agent, stats, sigmas, options=values, pipeline=name, seed=seed, **through
        )
        if tensorboard:
            write_tensorboard(tensorboard, stats, sigmas)
    except BaseException:
        remove_empty_folders(out, made)  # an interrupted or failed run leaves no empty folder behind
        raise
    return LearnerRun(agent, readings, stats, policy, curve, values)
