"""Learning-curve figures in the style of the paper's Figs. 5–7.

The paper (§5) shows the accumulated reward per episode, averaged over 5 repeats and smoothed
with "a sliding average of 10 episodes". Here each curve is that mean; the shaded band is the
spread across repeats (minimum to maximum of the smoothed repeat curves), so a reader sees
whether every repeat learned or only the average did. Matplotlib is imported without pyplot,
so drawing works headless and in worker processes.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

import numpy as np

from pipefollow.envs.render import new_figure, save_figure

SMOOTHING_EPISODES = 10  # sliding-average window (paper §5)
CURVE_FIGURE_SIZE = (7.0, 4.5)  # inches, at 100 dpi


def sliding_average(x, window: int = SMOOTHING_EPISODES) -> np.ndarray:
    """Trailing sliding average along the last axis.

    Point ``i`` is the mean of ``x[i - window + 1 : i + 1]``. The first ``window - 1`` points
    average what is available (``x[0 : i + 1]``), so the curve starts at the first episode and
    has the length of ``x``, rather than being shifted or padded.

    Args:
        x: values, 1-D or N-D (averaged along the last axis).
        window: window length (episodes), at least 1.

    Returns:
        float64 array of the shape of ``x``.

    Raises:
        ValueError: if ``window`` is below 1.
    """
    if window < 1:
        raise ValueError(f"window must be at least 1, got {window}")
    x = np.asarray(x, dtype=np.float64)
    n = x.shape[-1]
    zero = np.zeros((*x.shape[:-1], 1))
    cum = np.concatenate([zero, np.cumsum(x, axis=-1)], axis=-1)
    hi = np.arange(1, n + 1)
    lo = np.maximum(hi - window, 0)
    return (cum[..., hi] - cum[..., lo]) / (hi - lo)


def learning_curve_figure(
    curves: Mapping[str, np.ndarray],
    path: str | os.PathLike | None,
    title: str,
    reference: float | None = None,
    window: int = SMOOTHING_EPISODES,
):
    """Draw learning curves, Figs. 5–7 style, and save them as PNG (atomically) when ``path`` is given.

    Args:
        curves: label → (repeats, episodes) accumulated reward per training episode.
        path: where to save the PNG, or None.
        title: figure title.
        reference: the heuristic's return on the same pipeline, drawn as a dashed line; None = none.
        window: sliding-average window (episodes).

    Returns:
        The matplotlib figure.
    """
    fig = new_figure(CURVE_FIGURE_SIZE)
    ax = fig.add_subplot()
    for i, (label, returns) in enumerate(curves.items()):
        returns = np.atleast_2d(np.asarray(returns, dtype=np.float64))
        smooth = sliding_average(returns, window)
        episodes = np.arange(smooth.shape[1])
        color = f"C{i % 10}"
        n = smooth.shape[0]
        ax.plot(episodes, smooth.mean(axis=0), color=color, lw=1.5, label=f"{label} (n = {n})")
        if n > 1:
            ax.fill_between(episodes, smooth.min(axis=0), smooth.max(axis=0), color=color, alpha=0.2, lw=0)
    if reference is not None and np.isfinite(reference):
        ax.axhline(reference, color="k", ls="--", lw=1, label=f"heuristic, σ = 0 ({reference:.2f})")
    ax.set_xlabel(f"episode  (mean over repeats, {window}-episode sliding average; band: min–max of repeats)")
    ax.set_ylabel("accumulated reward per episode")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    if path is not None:
        save_figure(fig, path)
    return fig


def trajectories_figure(
    pipeline, trajectories: Mapping[str, np.ndarray], path: str | os.PathLike | None, title: str
):
    """Evaluation trajectories over a pipeline (paper Fig. 4 view), saved as PNG when ``path`` is given.

    Args:
        pipeline: a :class:`~pipefollow.sim.pipeline.Pipeline`, built-in name or pipeline file.
        trajectories: legend label → (n, 3) poses (x north, y east, ψ).
        path: where to save the PNG, or None.
        title: figure title.

    Returns:
        The matplotlib figure.
    """
    from pipefollow.envs.render import plot_trajectories
    from pipefollow.sim.pipe_names import resolve_fixed

    return plot_trajectories(resolve_fixed(pipeline), trajectories, path, title=title)
