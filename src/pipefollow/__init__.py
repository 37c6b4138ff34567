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


def _configure_numba_cache() -> None:
    """Keep numba's on-disk cache in step with all of the package's sources.

    Numba revalidates a cached function against its own file only, not against the files of
    the functions compiled into it: after an edit of ``sim/controller.py`` a cached
    ``sim.decision.decide`` would still run the old controller. A cache folder named after a
    hash of every module that holds compiled code rules that out; edits elsewhere (the command
    line, the report) keep the cache. It lives under
    ``$NUMBA_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/pipefollow`` (``~/.cache/pipefollow``);
    if that is not writable, numba's default (``__pycache__``) is left in place.
    """
    import os
    import shutil
    from pathlib import Path

    import numba

    from pipefollow.files.sources import compiled_modules, source_hash

    base = Path(
        os.environ.get("NUMBA_CACHE_DIR")
        or Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "pipefollow"
    )
    target = base / f"numba-{source_hash(compiled_modules())}"
    try:
        target.mkdir(parents=True, exist_ok=True)
        probe = target / f".probe-{os.getpid()}"
        probe.touch()
        probe.unlink()
    except OSError:
        return
    numba.config.CACHE_DIR = str(target)
    # keep the three most recently used caches of earlier source versions, drop the rest
    try:
        others = sorted(
            (p for p in base.glob("numba-*") if p != target), key=lambda p: p.stat().st_mtime, reverse=True
        )
    except OSError:  # another process is pruning at the same time
        return
    for old in others[3:]:
        shutil.rmtree(old, ignore_errors=True)


_configure_numba_cache()


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


register_envs()
