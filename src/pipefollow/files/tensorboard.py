"""Per-episode series of a training as TensorBoard scalars (optional extra ``tensorboard``).

``pipefollow train --tensorboard DIR`` writes, after the training, one event file under ``DIR``
with a scalar per episode for each series (``episode/return``, ``episode/pipe_in_view``,
``episode/sigma``, …); ``tensorboard --logdir DIR`` shows them. The writer is TensorBoard's own
(``tensorboard.summary.Writer``), so neither torch nor TensorFlow is needed.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path


class TensorBoardMissing(ImportError):
    """The tensorboard package is not installed."""


def check_available() -> None:
    """Raise :class:`TensorBoardMissing` (with the install line) before any work, if it is missing."""
    try:
        import tensorboard.summary  # noqa: F401
    except ImportError as e:
        raise TensorBoardMissing(
            "--tensorboard needs the optional extra 'tensorboard' (pip install 'pipefollow[tensorboard]')"
        ) from e


def write_scalars(
    folder: str | os.PathLike, series: Mapping[str, Sequence[float]], prefix: str = "episode"
) -> Path:
    """Write ``series`` (name → one value per episode) as scalars ``prefix/name`` at steps 0, 1, …."""
    check_available()
    from tensorboard.summary import Writer

    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    writer = Writer(str(out))
    try:
        for name, values in series.items():
            for step, value in enumerate(values):
                writer.add_scalar(f"{prefix}/{name}", float(value), step=step)
    finally:
        writer.close()
    return out
