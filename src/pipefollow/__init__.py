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


def source_hash(modules: tuple[str, ...] | None = None) -> str:
    """A short hash of the package's Python sources (all, or the named module files)."""
    import hashlib
    from pathlib import Path

    key = modules or ()
    if key not in _SOURCE_HASHES:
        root = Path(__file__).parent
        paths = sorted(root.rglob("*.py")) if modules is None else [root / m for m in sorted(modules)]
        digest = hashlib.sha1()
        for path in paths:
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(path.read_bytes())
        _SOURCE_HASHES[key] = digest.hexdigest()[:16]
    return _SOURCE_HASHES[key]


_SOURCE_HASHES: dict[tuple[str, ...], str] = {}


def _configure_numba_cache() -> None:
    """Keep numba's on-disk cache in step with all of the package's sources.

    Numba revalidates a cached function against its own file only, not against the files of
    the functions compiled into it: after an edit of ``controller.py`` a cached
    ``simulation.decide`` would still run the old controller. A cache folder named after a
    hash of every source file of the package rules that out. It lives under
    ``$NUMBA_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/pipefollow`` (``~/.cache/pipefollow``);
    if that is not writable, numba's default (``__pycache__``) is left in place.
    """
    import os
    import shutil
    from pathlib import Path

    import numba

    base = Path(
        os.environ.get("NUMBA_CACHE_DIR")
        or Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "pipefollow"
    )
    target = base / f"numba-{source_hash()}"
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
            entry_point="pipefollow.env:PipelineFollowingEnv",
            vector_entry_point="pipefollow.vector_env:PipelineFollowingVectorEnv",
            max_episode_steps=86_400,  # pipefollow.env.MAX_EPISODE_SECONDS / 1-s decisions
        )


register_envs()
