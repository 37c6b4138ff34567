"""pipefollow: learning pipeline-following controllers for AUVs with reinforcement learning.

Importing the package registers the Gymnasium environment ``pipefollow/PipelineFollowing-v0``.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("pipefollow")
except PackageNotFoundError:  # running from a source tree
    __version__ = "0.0.0"

ENV_ID = "pipefollow/PipelineFollowing-v0"


def register_envs() -> None:
    """Register the Gymnasium environment (idempotent)."""
    from gymnasium.envs.registration import register, registry

    if ENV_ID not in registry:
        register(id=ENV_ID, entry_point="pipefollow.env:PipelineFollowingEnv")


register_envs()
