"""pipefollow: learning pipeline-following controllers for AUVs with reinforcement learning.

Importing the package registers the Gymnasium environment ``pipefollow/PipelineFollowing-v0``:
at once if Gymnasium is loaded, else as soon as it is. Importing the package loads neither
Gymnasium nor NumPy nor numba, so that ``pipefollow --help`` starts in a blink; numba's cache
folder is set by the packages that hold compiled code (:mod:`pipefollow.files.compile_cache`).
"""

from __future__ import annotations

import sys

# the one source of the version: pyproject.toml reads it from here (setuptools, without importing)
__version__ = "0.1.0"

ENV_ID = "pipefollow/PipelineFollowing-v0"


def register_envs() -> None:
    """Register the Gymnasium environment and its batched vector version (idempotent)."""
    from gymnasium.envs.registration import register, registry

    if ENV_ID not in registry:
        # The episode length is the env's own (``episode_seconds``); the spec carries its upper
        # bound, one decision per second, so that gym.make's TimeLimit never truncates earlier.
        register(
            id=ENV_ID,
            entry_point="pipefollow.envs.env:PipelineFollowingEnv",
            vector_entry_point="pipefollow.envs.vector_env:PipelineFollowingVectorEnv",
            max_episode_steps=86_400,  # pipefollow.envs.env.MAX_EPISODE_SECONDS / 1-s decisions
        )


class _RegisterOnGymnasiumImport:
    """A post-import hook: registers the environments once Gymnasium's registry module has run.

    A finder on ``sys.meta_path`` that answers only for ``gymnasium.envs.registration``: it
    takes the spec the other finders give and wraps its loader, so the registry is filled the
    moment it exists, whichever of ``import gymnasium`` and ``import pipefollow`` comes first.
    """

    NAME = "gymnasium.envs.registration"

    def find_spec(self, fullname, path=None, target=None):  # noqa: D102
        if fullname != self.NAME:
            return None
        sys.meta_path.remove(self)  # one-shot, and so that the real finders answer below
        for finder in sys.meta_path:
            spec = finder.find_spec(fullname, path, target) if hasattr(finder, "find_spec") else None
            if spec is not None:
                break
        else:
            return None
        if spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        exec_module = spec.loader.exec_module

        def exec_and_register(module):
            exec_module(module)
            register_envs()

        spec.loader.exec_module = exec_and_register
        return spec


if "gymnasium.envs.registration" in sys.modules:
    register_envs()
else:
    sys.meta_path.insert(0, _RegisterOnGymnasiumImport())
