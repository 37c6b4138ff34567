"""Writing results: learning curves and tables as CSV, always atomically."""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from pipefollow.files.atomic import write_text_atomic
from pipefollow.sim.episode import TRAINING_STAT_NAMES


def csv_text(header: Sequence[str], rows: Iterable[Sequence]) -> str:
    """CSV text with a header line; floats keep full precision."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for row in rows:
        w.writerow([repr(float(v)) if isinstance(v, (float, np.floating)) else v for v in row])
    return buf.getvalue()


def write_learning_curve(path: str | Path, stats: np.ndarray, sigmas: np.ndarray) -> Path:
    """One row per episode: ``episode, sigma, return, pipe_in_view, progress_m, time_lost_s``.

    ``sigmas`` is the σ each episode trained with (``training.phases.phase_sigmas``).
    """
    path = Path(path)
    rows = ([e, sigmas[e], *stats[e]] for e in range(len(stats)))
    write_text_atomic(path, csv_text(["episode", "sigma", *TRAINING_STAT_NAMES], rows))
    return path


TRAINING_OUTPUTS = ("policy.npz", "learning_curve.csv")


def write_training_outputs(
    out: Path, agent, stats: np.ndarray, sigmas: np.ndarray, options: dict | None = None, **metadata
) -> tuple[Path, Path]:
    """Write ``policy.npz`` and ``learning_curve.csv`` of a training run into ``out``, as a pair.

    ``sigmas`` is the σ of every training episode, as the learner ran it (normalized action units);
    ``options`` the learner options it trained with (stored in the policy file).

    Each file is written atomically; if the second cannot be written (a full disk), the first is
    removed again, so that ``out`` never holds one without the other from this run.
    """
    from pipefollow.training.policy_files import save_policy

    policy_name, curve_name = TRAINING_OUTPUTS
    policy_path = save_policy(
        agent, Path(out) / policy_name, options=options, episodes=len(sigmas), **metadata
    )
    try:
        curve_path = write_learning_curve(Path(out) / curve_name, stats, sigmas)
    except BaseException:
        policy_path.unlink(missing_ok=True)
        raise
    return policy_path, curve_path
