"""pipefollow: learning pipeline-following controllers for AUVs with reinforcement learning.

The Gymnasium environment ``pipefollow/PipelineFollowing-v0`` (:data:`ENV_ID`) is registered
when :mod:`pipefollow.envs` is imported, and by ``import pipefollow`` itself when Gymnasium is
already loaded (``import gymnasium`` first, or ``gymnasium.make("pipefollow:...")``, Gymnasium's
``module:id`` form). ``gymnasium.make("pipefollow.envs:pipefollow/PipelineFollowing-v0")``
registers it whatever was imported before, in any process (subprocess workers too). Importing
the package alone loads neither Gymnasium nor NumPy nor numba, so that ``pipefollow --help``
starts in a blink; numba's cache folder is set by the packages that hold compiled code
(:mod:`pipefollow.files.compile_cache`).
"""

from __future__ import annotations

import sys

# the one source of the version: pyproject.toml reads it from here (setuptools, without importing)
__version__ = "0.1.0"

ENV_ID = "pipefollow/PipelineFollowing-v0"


def register_envs() -> None:
    """Register the Gymnasium environment and its batched vector version (idempotent)."""
    from gymnasium.envs.registration import register, registry

    from pipefollow.files.limits import MAX_EPISODE_SECONDS

    if ENV_ID not in registry:
        # The episode length is the env's own (``episode_seconds``); the spec carries its upper
        # bound, one decision per second, so that gym.make's TimeLimit never truncates earlier.
        register(
            id=ENV_ID,
            entry_point="pipefollow.envs.env:PipelineFollowingEnv",
            vector_entry_point="pipefollow.envs.vector_env:PipelineFollowingVectorEnv",
            max_episode_steps=int(MAX_EPISODE_SECONDS),  # at most one decision per second
        )


if "gymnasium" in sys.modules:  # loaded already, so registering costs nothing
    register_envs()
