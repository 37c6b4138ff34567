"""Where numba keeps its on-disk cache of the package's compiled functions.

Numba revalidates a cached function against its own file only, not against the files of the
functions compiled into it: after an edit of ``sim/controller.py`` a cached ``sim.decision.decide``
would still run the old controller. A cache folder named after a hash of every module that holds
compiled code rules that out; edits elsewhere (the command line, the report) keep the cache.

Numba picks a function's cache folder when the function is decorated, so every package that
holds compiled modules calls :func:`configure_numba_cache` in its ``__init__``, before any of its
modules runs; importing the package alone (``import pipefollow``, ``pipefollow --help``) does not
import numba at all.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

_configured: list[str] = []  # the folder set, once per process


def cache_base() -> Path:
    """``$NUMBA_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/pipefollow`` (``~/.cache/pipefollow``)."""
    return Path(
        os.environ.get("NUMBA_CACHE_DIR")
        or Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "pipefollow"
    )


def configure_numba_cache() -> str | None:
    """Point numba's cache at ``cache_base()/numba-<hash of the compiled modules>`` (idempotent).

    Keeps the three most recently used folders of earlier source versions and removes older
    ones. If the folder is not writable, numba's default (``__pycache__``) is left in place.

    Returns:
        The cache folder, or None if numba's default is kept.
    """
    if _configured:
        return _configured[0] or None
    import numba

    from pipefollow.files.sources import compiled_modules, source_hash

    base = cache_base()
    target = base / f"numba-{source_hash(compiled_modules())}"
    try:
        target.mkdir(parents=True, exist_ok=True)
        probe = target / f".probe-{os.getpid()}"
        probe.touch()
        probe.unlink()
    except OSError:
        _configured.append("")
        return None
    numba.config.CACHE_DIR = str(target)
    _configured.append(str(target))
    try:
        others = sorted(
            (p for p in base.glob("numba-*") if p != target), key=lambda p: p.stat().st_mtime, reverse=True
        )
    except OSError:  # another process is pruning at the same time
        return str(target)
    for old in others[3:]:
        shutil.rmtree(old, ignore_errors=True)
    return str(target)
