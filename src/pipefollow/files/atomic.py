"""Atomic file writes, and the one way the package reads a user's text file.

Every file the package writes goes through :func:`atomic_file`: the content goes to a temporary
file ``.<name>.<random>.tmp`` beside the target (never mistaken for a result), is flushed to
disk, and is then renamed over the target in one step. Pipeline and experiment files are read by
:func:`read_text_file`: UTF-8, a byte-order mark allowed, every problem one error naming the file;
the package's own ``.npz`` files (trials, policies) by :func:`read_npz_file`, without pickle.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

TMP_SUFFIX = ".tmp"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


# mkstemp creates files readable by their owner only; results should get the usual permissions.
_FILE_MODE = 0o666 & ~_umask()


@contextmanager
def _temporary_beside(path: Path, suffix: str) -> Iterator[tuple[int, str]]:
    """A new file ``.<name>.<random><suffix>`` beside ``path`` (parents are created): its descriptor and name.

    If the body fails, the file is removed; a failed write that names no file (a full disk) is
    raised again naming ``path``, the file the caller asked for.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
    except OSError as e:  # name the file the caller asked for, not the temporary one
        raise OSError(e.errno, e.strerror, str(path)) from None
    try:
        yield fd, tmp
    except BaseException as e:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(e, OSError) and e.errno is not None and e.filename is None:
            raise type(e)(e.errno, e.strerror, str(path)) from None
        raise


@contextmanager
def atomic_file(path: str | os.PathLike, mode: str = "wb") -> Iterator[IO]:
    """Open a temporary file for writing; on success it replaces ``path`` (parents are created)."""
    path = Path(path)
    with _temporary_beside(path, TMP_SUFFIX) as (fd, tmp):
        os.fchmod(fd, _FILE_MODE)
        with os.fdopen(fd, mode, **({"encoding": "utf-8"} if "b" not in mode else {})) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())  # the rename must not overtake the data (power loss, not just kill)
        os.replace(tmp, path)


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    with atomic_file(path, "w") as f:
        f.write(text)


@contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path beside ``path`` with the same suffix, for writers that take a file name.

    Some writers choose the format by the name's suffix (Matplotlib's animation writers, Pillow)
    or open the file themselves; on success the file replaces ``path``, on failure it is removed.
    """
    path = Path(path)
    with _temporary_beside(path, f"{TMP_SUFFIX}{path.suffix}") as (fd, tmp):
        os.close(fd)
        yield Path(tmp)
        os.chmod(tmp, _FILE_MODE)
        os.replace(tmp, path)


def read_text_file(path: Path, source: str, error: type[ValueError]) -> str:
    """The text of a UTF-8 file (a byte-order mark is skipped); problems raise ``error`` naming ``source``."""
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        raise error(f"{source}: no such file") from None
    except OSError as e:
        raise error(f"{source}: cannot read ({e.strerror})") from None
    try:
        return data.decode("utf-8-sig")  # editors on Windows may add a byte-order mark
    except UnicodeDecodeError as e:
        raise error(f"{source}: not UTF-8 text (byte {e.start})") from None


def read_npz_file(path: Path, source: str, error: type[ValueError], marker: str, kind: str) -> dict:
    """The arrays of an ``.npz`` file whose ``format`` entry is ``marker``, read without pickle.

    Problems raise ``error`` naming ``source``: no such file, not a readable ``.npz`` file, or not
    ``a pipefollow {kind}`` (no ``marker``).
    """
    import zipfile

    import numpy as np

    try:
        # Our own file object: np.load leaks the one it opens when the zip is damaged.
        with open(path, "rb") as f, np.load(f, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise error(f"{source}: no such file") from None
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as e:
        raise error(f"{source}: not a readable .npz file ({type(e).__name__})") from None
    if str(data.get("format", "")) != marker:
        raise error(f"{source}: not a pipefollow {kind} (no '{marker}' marker)")
    return data
