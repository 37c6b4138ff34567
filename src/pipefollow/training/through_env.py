"""The paper's learners trained through a camera or sensor that their compiled loops do not have.

A learner's compiled loop (:mod:`pipefollow.training.compiled`, :mod:`pipefollow.training.random_pipes`)
sees what the ideal camera sees. The rendered camera with its detector and tracker, the sonar and
the fused sensor (:mod:`pipefollow.perception`) run frame by frame in Python, so a learner trains
through them in the environment: :func:`train_through_env` builds a
:class:`~pipefollow.envs.env.PipelineFollowingEnv` with the camera's arguments and runs
:func:`~pipefollow.training.compiled.train` in it, the same learner, updates and episode protocol
(the learner contract tests hold a compiled loop equal to its agent in the environment). What it
costs is the sensor's time, frame by frame (docs/decisions.md, "The paper's learners trained
through the sensor", gives it).

Randomness: the agent explores with its own generator; the environment draws the pipes of a
``random[:FAMILY]`` phase, the random disturbances, the images and the sonar's pings from its own,
seeded at the phase's first reset by :func:`env_seed` (a stream of the run's seed of its own, one
per phase). So through the ideal camera with random disturbances (``--camera-noise``, a current
that varies) the numbers differ from the compiled loop's, which draws them from another stream;
without random disturbances they are the compiled loop's.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pipefollow.sim import decision as sim
from pipefollow.training.compiled import train


def env_seed(seed: int, phase: int = 0) -> int:
    """The seed of a run's environment for its ``phase`` (0-based): child ``1 + phase`` of the run's seed.

    Child 0 is the compiled loops' (:func:`.phases.disturbance_rng`, and the same numbers as their
    random pipes' generator, the agent's generator's first child).
    """
    child = np.random.SeedSequence(seed, spawn_key=(1 + phase,))
    return int(child.generate_state(1, dtype=np.uint32)[0])


def train_through_env(
    agent,
    pipeline,
    episodes: int,
    *,
    camera: dict,
    seed: int,
    phase: int = 0,
    episode_seconds: float,
    sigma_start: float,
    sigma_end: float,
    params: sim.SimParams = sim.PAPER_SIM,
    randomization=None,
    progress: Callable[[int], None] | None = None,
) -> np.ndarray:
    """Train ``agent`` for ``episodes`` in an environment that observes through ``camera``.

    Args:
        agent: an agent of the registry.
        pipeline: what the environment takes for its pipes (a name, ``random[:FAMILY]``, a
            :class:`~pipefollow.sim.pipeline.Pipeline`).
        episodes: training episodes.
        sigma_start: σ of the first episode (normalized action units), falling linearly to
        sigma_end: σ of the last.
        camera: the environment's camera arguments (``camera``, ``water``, ``sensor``).
        seed: the run's seed, and
        phase: the phase's index: the environment's generator (:func:`env_seed`).
        episode_seconds: episode length (s).
        params: the simulated system, disturbances included.
        randomization: each episode's disturbances drawn from this instead (a resolved record).
        progress: called with the episodes done.

    Returns:
        (episodes, 4) statistics (:data:`~pipefollow.sim.episode.TRAINING_STAT_NAMES`), counted
        from what the exact camera saw.
    """
    from pipefollow.envs.env import PipelineFollowingEnv

    env = PipelineFollowingEnv(
        pipeline, episode_seconds=episode_seconds, params=params, randomization=randomization,
        state=agent.state, **camera,
    )  # fmt: skip
    callback = None if progress is None else (lambda e, _stats: progress(e + 1))
    try:
        return train(
            env, agent, episodes, sigma_start=sigma_start, sigma_end=sigma_end, callback=callback,
            seed=env_seed(seed, phase),
        )  # fmt: skip
    finally:
        env.close()


__all__ = ["env_seed", "train_through_env"]
