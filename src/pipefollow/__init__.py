"""pipefollow: learning pipeline-following controllers for AUVs with reinforcement learning.

The Gymnasium environment ``pipefollow/PipelineFollowing-v0`` (:data:`ENV_ID`) and the other ids
of :data:`ENV_IDS` are registered when :mod:`pipefollow.envs` is imported, and by
``import pipefollow`` itself when Gymnasium is already loaded (``import gymnasium`` first, or
``gymnasium.make("pipefollow:...")``, Gymnasium's ``module:id`` form).
``gymnasium.make("pipefollow.envs:pipefollow/PipelineFollowing-v0")`` registers them whatever was
imported before, in any process (subprocess workers too). Importing the package alone loads
neither Gymnasium nor NumPy nor numba, so that ``pipefollow --help`` starts in a blink; numba's
cache folder is set by the packages that hold compiled code (:mod:`pipefollow.files.compile_cache`).
"""

from __future__ import annotations

import sys

from pipefollow.files.paper_training import EPISODE_SECONDS, TEST_EPISODE_SECONDS

RANDOM_EPISODE_SECONDS = 90.0  # the random-pipes id's episode (s): the deep-RL guide's regime

# the one source of the version: pyproject.toml reads it from here (setuptools, without importing)
__version__ = "0.1.0"

ENV_ID = "pipefollow/PipelineFollowing-v0"

# The registered ids (namespace/Name-vN, Gymnasium's form): the configurations people run, each
# with its own episode. Values: the environment's keyword arguments and the episode's decisions
# (its spec's max_episode_steps: one decision per second, so the episode's seconds).
ENV_IDS: dict[str, tuple[dict, int]] = {
    # the paper's training (§4.1): paper-left, 20-s episodes (the environment's defaults)
    ENV_ID: ({}, int(EPISODE_SECONDS)),
    # the same with the downward camera's grey image as the observation, (H, W, 1) uint8
    "pipefollow/PipelineFollowingImage-v0": ({"observation": "image"}, int(EPISODE_SECONDS)),
    # the same with the pipe detector on the camera image in the loop (extra 'vision')
    "pipefollow/PipelineFollowingVision-v0": ({"camera": "vision"}, int(EPISODE_SECONDS)),
    # a new random:mixed pipe every 90-s episode: the deep-RL and generalization training regime
    "pipefollow/PipelineFollowingRandom-v0": (
        {"pipeline": "random:mixed", "episode_seconds": RANDOM_EPISODE_SECONDS},
        int(RANDOM_EPISODE_SECONDS),
    ),
    # the paper's held-out validation pipe, 60-s episodes (§4.2, Table 1)
    "pipefollow/PipelineFollowingValidation-v0": (
        {"pipeline": "paper-validation", "episode_seconds": TEST_EPISODE_SECONDS},
        int(TEST_EPISODE_SECONDS),
    ),
}


def register_envs() -> None:
    """Register the Gymnasium environments of :data:`ENV_IDS` and their batched vector version (idempotent).

    Each id's ``max_episode_steps`` is its episode's decisions, so that ``gym.make``'s
    ``TimeLimit`` ends an episode at the same step as the environment does.
    """
    from gymnasium.envs.registration import register, registry

    for env_id, (kwargs, steps) in ENV_IDS.items():
        if env_id not in registry:
            register(
                id=env_id,
                entry_point="pipefollow.envs.env:PipelineFollowingEnv",
                vector_entry_point="pipefollow.envs.vector_env:PipelineFollowingVectorEnv",
                max_episode_steps=steps,
                kwargs=dict(kwargs),
            )


if "gymnasium" in sys.modules:  # loaded already, so registering costs nothing
    register_envs()
