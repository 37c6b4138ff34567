"""Writing results: learning curves and tables as CSV, always atomically."""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from pipefollow.atomic import write_text_atomic
from pipefollow.exploration import linear_sigma
from pipefollow.training import STAT_NAMES


def csv_text(header: Sequence[str], rows: Iterable[Sequence]) -> str:
    """CSV text with a header line; floats keep full precision."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for row in rows:
        w.writerow([repr(float(v)) if isinstance(v, (float, np.floating)) else v for v in row])
    return buf.getvalue()


def write_learning_curve(
    path: str | Path, stats: np.ndarray, episodes: int, sigma_start: float = 1.0, sigma_end: float = 0.01
) -> Path:
    """One row per episode: ``episode, sigma, return, pipe_in_view, progress_m, time_lost_s``."""
    path = Path(path)
    rows = ([e, linear_sigma(e, episodes, sigma_start, sigma_end), *stats[e]] for e in range(len(stats)))
    write_text_atomic(path, csv_text(["episode", "sigma", *STAT_NAMES], rows))
    return path
