"""The life of a run folder around a run: its lock, whether it is writable and complete.

What a failed run leaves behind is cleaned up here too. The files themselves (configuration,
trial files, policies, tables) are :mod:`pipefollow.experiments.store`'s.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from pipefollow.experiments.config import ConfigError, ExperimentConfig
from pipefollow.experiments.store import (
    CONFIG_FILE,
    StoreError,
    load_trial,
    policy_path,
    read_config,
    trial_path,
)
from pipefollow.experiments.tables import EVALUATION_FILE, RESULTS_FILE
from pipefollow.files.atomic import TMP_SUFFIX

LOCK_FILE = ".lock"


@contextmanager
def locked(run_dir: str | os.PathLike) -> Iterator[Path]:
    """Hold an exclusive lock on ``run_dir`` (created if missing) while the block runs.

    A second run in the same folder gets a :class:`ConfigError` instead of interleaving its files
    with the first one's. The lock dies with the process, so a killed run leaves no stale lock,
    and the lock file is removed when the block ends: a finished run folder holds results only.
    """
    run_dir = Path(run_dir)
    if run_dir.exists() and not run_dir.is_dir():
        raise ConfigError(f"--out '{run_dir}': exists and is not a folder")
    run_dir.mkdir(parents=True, exist_ok=True)
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX: no locking
        yield run_dir
        return
    lock = run_dir / LOCK_FILE
    while True:
        fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise ConfigError(f"run folder '{run_dir}' is in use by another pipefollow run") from None
        # The holder before us removes the file before it unlocks it: a lock on a file that is
        # no longer (or no longer the same file) at the path locks nothing, so take it again.
        try:
            current = os.stat(lock).st_ino
        except FileNotFoundError:
            current = None
        if current == os.fstat(fd).st_ino:
            break
        os.close(fd)
    try:
        yield run_dir
    finally:
        try:
            lock.unlink(missing_ok=True)  # while still holding it
        finally:
            os.close(fd)


def writable(run_dir: str | os.PathLike) -> bool:
    """Whether files can be created in the existing folder ``run_dir`` (false on read-only media)."""
    import errno
    import tempfile

    try:
        fd, probe = tempfile.mkstemp(dir=run_dir, prefix=".pipefollow-probe-")
    except OSError as e:
        if e.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
            return False
        raise
    os.close(fd)
    os.unlink(probe)
    return True


def is_complete(run_dir: str | os.PathLike, exp: ExperimentConfig) -> bool:
    """Whether ``run_dir`` holds every trial and both tables of ``exp``, checked by reading only."""
    run_dir = Path(run_dir)
    try:
        if read_config(run_dir) != exp:
            return False
    except StoreError:
        return False
    if not all((run_dir / name).is_file() for name in (RESULTS_FILE, EVALUATION_FILE)):
        return False
    for t in exp.trials:
        for seed in exp.seeds():
            if not policy_path(run_dir, t.name, seed).is_file():
                return False
            try:
                result = load_trial(run_dir, t.name, seed)
            except StoreError:
                return False
            if len(result.stats) != t.episodes:
                return False
    return True


def discard_unfinished(run_dir: str | os.PathLike, exp: ExperimentConfig, created: bool) -> None:
    """After a failed run: remove what no finished trial needs, so nothing half-made stays.

    Policy files without their trial file go (the policy is written first), then empty folders;
    if this run wrote ``config.json`` (``created``) and no trial finished, that goes too. Files of
    finished trials stay, so that running again resumes. Call it with the folder locked.
    """
    run_dir = Path(run_dir)
    any_finished = False
    for t in exp.trials:
        for seed in exp.seeds():
            if trial_path(run_dir, t.name, seed).exists():
                any_finished = True
            else:
                policy_path(run_dir, t.name, seed).unlink(missing_ok=True)
    for tmp in run_dir.rglob(f".*{TMP_SUFFIX}"):
        tmp.unlink(missing_ok=True)
    for sub in sorted(run_dir.glob("trials/*"), reverse=True) + [run_dir / "trials", run_dir / "policies"]:
        if sub.is_dir() and not any(sub.iterdir()):
            sub.rmdir()
    if created and not any_finished:
        (run_dir / CONFIG_FILE).unlink(missing_ok=True)
