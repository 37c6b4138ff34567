"""One controller, one pipeline, deterministic episodes (σ = 0): what ``pipefollow evaluate`` runs.

:func:`evaluate` runs the episodes in the environment (with start noise, disturbances, a random
pipe per episode for ``random[:FAMILY]``, the vision camera), keeping the first episode's states
for an animation if asked; :class:`Evaluation` holds the statistics and writes the figures.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pipefollow import readings as rd
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.evaluation import success as sc
from pipefollow.files.paper_training import EPISODE_SECONDS, TEST_EPISODE_SECONDS, TRAINING_PIPELINES
from pipefollow.sim.disturbance import NO_DISTURBANCE, Disturbance, noise_count
from pipefollow.sim.pipe_names import RANDOM_PREFIX
from pipefollow.sim.suites import Suite


def default_seconds(pipeline: str) -> float:
    """The episode length (s) for ``pipeline``, the same as ``benchmark`` gives the same kind of pipe.

    The paper's training episode (``EPISODE_SECONDS``, 20 s) on its training pipes and on a training
    family ``random[:FAMILY]``; its validation episode (``TEST_EPISODE_SECONDS``, 60 s) on every other
    pipe: ``paper-validation``, a suite's pipe, a pipeline file.
    """
    training = pipeline in TRAINING_PIPELINES or pipeline.startswith(RANDOM_PREFIX)
    return EPISODE_SECONDS if training else TEST_EPISODE_SECONDS


def episodes_alike(pipe, start_noise: float, heading_noise: float, disturbance: Disturbance) -> bool:
    """Whether every episode is the same: no start noise, one fixed pipe, no random disturbances."""
    return not (start_noise or heading_noise or isinstance(pipe, Suite)) and not noise_count(disturbance)


def summary(stats, lengths) -> dict:
    """Mean return, pipe in view, progress and success over the episodes, and every episode's.

    ``lengths``: each episode's pipe length (m), for the success (:mod:`pipefollow.evaluation.success`).
    """
    full = np.array([s.as_full_row() for s in stats])
    rows = [
        {
            "return": s.ret,
            "pipe_in_view": s.pipe_in_view,
            "progress_m": s.progress_m,
            "time_lost_s": s.time_lost_s,
            **sc.episode_fields(row, length),
        }
        for s, row, length in zip(stats, full, lengths, strict=True)
    ]
    return {
        "mean_return": float(np.mean([r["return"] for r in rows])),
        "mean_pipe_in_view": float(np.mean([r["pipe_in_view"] for r in rows])),
        "mean_progress_m": float(np.mean([r["progress_m"] for r in rows])),
        **sc.summary(full, np.asarray(lengths, dtype=np.float64)),
        "episodes": rows,
    }


@dataclass(frozen=True)
class Evaluation:
    """The episodes of :func:`evaluate`.

    Attributes:
        stats: every episode's statistics (``ret``, ``pipe_in_view``, ``progress_m``,
            ``time_lost_s``, ``poses``).
        pipe: the first episode's pipe.
        seconds: the episode length (s).
        params: the simulated system.
        frames: the first episode's states, for :meth:`write_animation` (empty unless recorded).
        lengths: every episode's pipe length (m).
    """

    stats: list
    pipe: Any
    seconds: float
    params: Any
    frames: list = field(default_factory=list, repr=False)
    lengths: list = field(default_factory=list)

    def summary(self) -> dict:
        """:func:`summary` of the episodes."""
        return summary(self.stats, self.lengths)

    def write_plot(self, path: str | Path, name: str) -> None:
        """The first episode's trajectory on its pipe, the controller called ``name``."""
        from pipefollow.envs.render import plot_trajectories

        first = self.stats[0]
        title = f"{name} on {self.pipe.name}: return {first.ret:.2f}"
        plot_trajectories(self.pipe, {name: first.poses}, path, title=title)

    def write_animation(self, path: str | Path) -> None:
        """The first episode in the Fig. 2 view (needs ``record`` in :func:`evaluate`)."""
        from pipefollow.envs.animation import write_animation

        write_animation(self.pipe, self.frames, path, self.params)


def evaluate(
    agent,
    pipeline: str,
    pipe=None,
    *,
    episodes: int = 1,
    seconds: float | None = None,
    seed: int = 0,
    start_noise: float = 0.0,
    heading_noise: float = 0.0,
    readings: rd.Readings = rd.DEFAULT,
    disturbance: Disturbance = NO_DISTURBANCE,
    camera: dict | None = None,
    record: bool = False,
) -> Evaluation:
    """Run ``episodes`` deterministic episodes of ``agent`` on ``pipeline``; the first seeded with ``seed``.

    Args:
        agent: a controller (``act``), e.g. from :func:`~pipefollow.evaluation.benchmark.load_controller`.
        pipeline: a built-in name, a JSON file, a pipe of a suite or ``random[:FAMILY]``.
        pipe: ``pipeline`` resolved already (:func:`~pipefollow.sim.pipe_names.resolve_pipeline`).
        episodes: how many; they differ only by start noise, random disturbances or a random pipe.
        seconds: episode length (s) (default: :func:`default_seconds`).
        seed: seed of the first episode.
        start_noise: bound of the uniform lateral start offset (m).
        heading_noise: bound of the uniform start heading offset (degrees).
        readings: the readings of the simulation.
        disturbance: disturbances and faults.
        camera: the environment's camera arguments (``camera``, ``water``), or None for the ideal one.
        record: keep the first episode's states for :meth:`Evaluation.write_animation`.
    """
    from pipefollow.sim.pipe_names import resolve_pipeline
    from pipefollow.training.compiled import run_episode

    seconds = default_seconds(pipeline) if seconds is None else seconds
    pipe = resolve_pipeline(pipeline, seconds) if pipe is None else pipe
    env = PipelineFollowingEnv(
        pipeline if isinstance(pipe, Suite) else pipe,  # a family: the env draws a pipe every episode
        seconds,
        start_noise,
        heading_noise,
        params=rd.sim_params(readings)._replace(disturbance=disturbance),
        state=getattr(agent, "state", "paper"),  # what a learner observes (sim.observation)
        **(camera or {}),
    )
    stats, frames, lengths = [], [], []
    for e in range(episodes):
        if e == 0 and record:
            from pipefollow.envs.animation import Recorder

            recorder = Recorder(env)  # the same episode, with its states kept for the animation
            stats.append(run_episode(recorder, agent, seed=seed))
            frames = recorder.frames
        else:
            stats.append(run_episode(env, agent, seed=seed if e == 0 else None))
        lengths.append(env.pipeline.length)
        if e == 0:
            pipe = env.pipeline  # the first episode's pipe, for the plot and the animation
    return Evaluation(stats, pipe, env.episode_seconds, env.params, frames, lengths)
