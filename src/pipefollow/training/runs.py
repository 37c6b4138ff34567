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
from pipefollow.learners.registry import learner
from pipefollow.sim.disturbance import NO_DISTURBANCE, Disturbance
from pipefollow.sim.episode import TRAINING_STAT_NAMES
from pipefollow.training.phases import phase_sigmas, train_phases


def step_sizes(algorithm: str) -> tuple[str, ...]:
    """The fields of a learner's parameter record that are its step sizes and discount (the registry's)."""
    return tuple(learner(algorithm).step_sizes.values())


def new_agent(
    algorithm: str, seed: int, reading: rd.Readings, skew_deg: float = 0.0, supervised: bool = False
):
    """A fresh agent of ``algorithm`` under ``reading``, its generator that of a run with ``seed``."""
    from pipefollow.training.agents import make_agent
    from pipefollow.training.phases import agent_rng

    rng = agent_rng(seed)
    return make_agent(algorithm, skew_deg=skew_deg, supervised=supervised, rng=rng, readings=reading)


def option_differences(
    agent, reading: rd.Readings, skew_deg: float | None, supervised: bool | None
) -> list[str]:
    """How a saved ``agent``'s options differ from those of a run continuing it; empty if they agree.

    ``skew_deg`` and ``supervised`` are the run's, or None where the run keeps the saved agent's.
    The step sizes and discount (:func:`step_sizes`) are always kept from the saved agent.
    Each difference reads ``field saved (this run: wanted)``.
    """
    from pipefollow.training.agents import make_agent

    held = agent.params
    keep = supervised if supervised is not None else bool(getattr(held, "supervised", False))
    wanted = make_agent(agent.algorithm, skew_deg=skew_deg or 0.0, supervised=keep, readings=reading).params
    if skew_deg is None and "skew" in wanted._fields:
        wanted = wanted._replace(skew=held.skew)
    kept = step_sizes(agent.algorithm)
    held = held._replace(**{k: getattr(wanted, k) for k in wanted._fields if k in kept})
    return [
        f"{f} {getattr(held, f)!r} (this run: {getattr(wanted, f)!r})"
        for f in wanted._fields
        if getattr(held, f) != getattr(wanted, f)
    ]


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

    def summary(self) -> dict:
        """The run as one JSON object: files, returns, and the means of the last 50 episodes."""
        stats, last = self.stats, min(50, len(self.stats))
        return {
            "algorithm": self.agent.name,
            "readings": self.readings.id,
            "policy": str(self.policy),
            "learning_curve": str(self.learning_curve),
            "returns": stats[:, 0].tolist(),
            **{f"final_mean_{n}": float(stats[-last:, i].mean()) for i, n in enumerate(TRAINING_STAT_NAMES)},
        }

    def text(self) -> str:
        """The run in three lines: mean returns of the first and last episodes, the files."""
        stats = self.stats
        k = min(10, len(stats))
        return (
            f"{self.agent.name}: mean return of the first {k} episodes {stats[:k, 0].mean():.2f}, "
            f"of the last {k} {stats[-k:, 0].mean():.2f}\npolicy: {self.policy}\n"
            f"learning curve: {self.learning_curve}"
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
    """
    from pipefollow.files.output_paths import remove_empty_folders
    from pipefollow.sim.pipe_names import resolve_training
    from pipefollow.training.outputs import write_training_outputs

    try:
        (stats,) = train_phases(
            agent,
            [(pipeline, episodes)],
            seed=seed,
            readings=readings,
            disturbance=disturbance,
            randomization=randomization,
            episode_seconds=seconds,
            progress=progress,
        )
        name = resolve_training(pipeline).name
        sigmas = phase_sigmas(episodes, readings)  # the σ train_phases trained with
        policy, curve = write_training_outputs(out, agent, stats, sigmas, pipeline=name, seed=seed)
        if tensorboard:
            write_tensorboard(tensorboard, stats, sigmas)
    except BaseException:
        remove_empty_folders(out, made)  # an interrupted or failed run leaves no empty folder behind
        raise
    return LearnerRun(agent, readings, stats, policy, curve)
