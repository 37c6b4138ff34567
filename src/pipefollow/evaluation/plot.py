"""The picture of a benchmark: per-pipe return differences to the heuristic, and a few trajectories."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from pipefollow.envs.render import PIPE_COLOR, new_figure, save_figure
from pipefollow.evaluation.benchmark import BenchmarkRun


def plot_benchmark(run: BenchmarkRun, path: str | os.PathLike) -> None:
    """Draw a benchmark's figure and write it atomically, in the format its suffix names.

    Left: the paired per-pipe differences (controller − heuristic), sorted, with the mean and its
    CI (for the heuristic itself: its sorted returns, mean and CI). Right: the worst, median and
    best pipe of the controller, with its trajectory and the heuristic's.
    """
    s = run.summary
    is_heuristic = "vs_heuristic" not in s
    fig = new_figure((12.0, 4.8))
    grid = fig.add_gridspec(1, 4, width_ratios=[1.6, 1, 1, 1])
    ax = fig.add_subplot(grid[0, 0])
    if is_heuristic:
        values, mean, (lo, hi) = run.returns, s["mean_return"], s["ci95_mean"]
        ylabel = "return per pipe"
    else:
        v = s["vs_heuristic"]
        values, mean, (lo, hi) = run.returns - run.heuristic_returns, v["mean_diff"], v["ci95_diff"]
        ylabel = "return − heuristic's return, per pipe"
        ax.axhline(0.0, color="k", lw=0.8)
    order = np.sort(values)
    ax.bar(np.arange(len(order)), order, width=1.0, color=np.where(order >= 0, "tab:blue", "tab:orange"))
    ax.axhspan(lo, hi, color="tab:green", alpha=0.25, label=f"95 % CI of the mean [{lo:.1f}, {hi:.1f}]")
    ax.axhline(mean, color="tab:green", lw=1.5, label=f"mean {mean:.2f}")
    ax.set_xlabel("pipes, sorted")
    ax.set_ylabel(ylabel)
    name = Path(s["controller"]).stem if s["controller"].endswith(".npz") else s["controller"]
    ax.set_title(f"{name} on '{s['suite']}' ({s['n_episodes']} pipes)", fontsize=9)
    ax.legend(fontsize=8, loc="upper left")
    ranked = np.argsort(run.returns, kind="stable")
    picks = [("worst", ranked[0]), ("median", ranked[len(ranked) // 2]), ("best", ranked[-1])]
    for j, (label, i) in enumerate(picks):
        axt = fig.add_subplot(grid[0, j + 1])
        pipe = run.pipes[i]
        axt.plot(pipe.points[:, 1], pipe.points[:, 0], color=PIPE_COLOR, lw=3, alpha=0.6)
        axt.plot(run.heuristic_poses[i][:, 1], run.heuristic_poses[i][:, 0], color="tab:gray", lw=1.2,
                 label=f"heuristic {run.heuristic_returns[i]:.1f}")  # fmt: skip
        if not is_heuristic:
            axt.plot(run.poses[i][:, 1], run.poses[i][:, 0], color="tab:blue", lw=1.2,
                     label=f"controller {run.returns[i]:.1f}")  # fmt: skip
        axt.plot(pipe.points[0, 1], pipe.points[0, 0], "ko", ms=4)
        axt.set_aspect("equal", adjustable="datalim")
        axt.set_title(f"{label}: {pipe.name}", fontsize=9)
        axt.legend(fontsize=7, loc="best")
        axt.set_xlabel("east (m)")
        if j == 0:
            axt.set_ylabel("north (m)")
    fig.tight_layout()
    save_figure(fig, path)


def plot_comparison(summary: dict, path: str | os.PathLike) -> None:
    """Draw a comparison (:func:`pipefollow.evaluation.compare.compare`) and write it atomically.

    Left: IQM and mean of each learner with their 95 % stratified-bootstrap intervals. Right: the
    performance profiles, the share of runs × pipes with a return above τ, with their intervals.
    """
    learners = summary["learners"]
    labels = list(learners)
    fig = new_figure((12.0, 0.9 + 0.45 * len(labels) + 3.0))
    grid = fig.add_gridspec(1, 3, width_ratios=[1, 1, 2])
    for col, key in enumerate(("iqm", "mean")):
        ax = fig.add_subplot(grid[0, col])
        for row, label in enumerate(labels):
            s = learners[label]
            lo, hi = s[f"ci95_{key}"]
            ax.plot([lo, hi], [row, row], color=f"C{row}", lw=6, alpha=0.5, solid_capstyle="butt")
            ax.plot([s[key]], [row], "|", color="k", ms=14)
        ax.set_yticks(range(len(labels)), labels if col == 0 else [""] * len(labels))
        ax.set_ylim(-0.7, len(labels) - 0.3)
        ax.invert_yaxis()
        ax.set_xlabel(f"{'IQM' if key == 'iqm' else 'mean'} of the return")
        ax.grid(axis="x", alpha=0.3)
    ax = fig.add_subplot(grid[0, 2])
    for row, label in enumerate(labels):
        p = learners[label]["profile"]
        runs = learners[label]["runs"]
        ax.plot(p["tau"], p["share"], color=f"C{row}", lw=1.5, label=f"{label} ({runs} runs)")
        ax.fill_between(p["tau"], p["ci95_low"], p["ci95_high"], color=f"C{row}", alpha=0.2, lw=0)
    ax.set_xlabel("return τ")
    ax.set_ylabel("share of runs × pipes with a return > τ")
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.suptitle(f"{summary.get('suite', '')}: {summary['pipes']} pipes, 95 % stratified-bootstrap intervals",
                 fontsize=10)  # fmt: skip
    fig.tight_layout()
    save_figure(fig, path)
