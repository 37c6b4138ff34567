"""Pictures in the style of the paper's Figs. 2 and 4: pipe, AUV, camera footprint, waypoint, trail.

Maps are drawn with east to the right and north up. Matplotlib is imported here only, and
without pyplot, so rendering works headless and in worker processes.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping

import numpy as np

from pipefollow import simulation as sim
from pipefollow.pipeline import Pipeline

PIPE_COLOR = "tab:red"
AUV_COLOR = "tab:blue"
CAMERA_COLOR = "tab:green"
TRAIL_COLORS = ("tab:blue", "tab:orange", "tab:purple", "tab:brown", "tab:gray")


def _figure(size=(6.0, 6.0)):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, dpi=100)
    FigureCanvasAgg(fig)
    return fig


def _auv_triangle(x, y, psi, size=0.35):
    """Corners (east, north) of a triangle pointing along the heading."""
    body = np.array([[1.0, 0.0], [-0.6, 0.5], [-0.6, -0.5]]) * size
    c, s = math.cos(psi), math.sin(psi)
    north = x + c * body[:, 0] - s * body[:, 1]
    east = y + s * body[:, 0] + c * body[:, 1]
    return np.column_stack([east, north])


def _footprint(x, y, psi, cam):
    """Corners (east, north) of the camera footprint."""
    corners = [
        (0.0, -cam.half_width),
        (cam.depth, -cam.half_width),
        (cam.depth, cam.half_width),
        (0.0, cam.half_width),
    ]
    c, s = math.cos(psi), math.sin(psi)
    return np.array([(y + s * f + c * lat, x + c * f - s * lat) for f, lat in corners])


def _draw_pipe(ax, pipeline: Pipeline) -> None:
    ax.plot(
        pipeline.points[:, 1],
        pipeline.points[:, 0],
        color=PIPE_COLOR,
        lw=3,
        alpha=0.8,
        label="pipe",
        solid_capstyle="round",
    )
    ax.set_aspect("equal")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.grid(alpha=0.3)


def _draw_auv(ax, pose, cam, color=AUV_COLOR, alpha=1.0) -> None:
    from matplotlib.patches import Polygon

    x, y, psi = pose
    ax.add_patch(
        Polygon(_footprint(x, y, psi, cam), closed=True, fill=False, ec=CAMERA_COLOR, lw=1.2, alpha=alpha)
    )
    ax.add_patch(Polygon(_auv_triangle(x, y, psi), closed=True, color=color, alpha=alpha))


def draw_scene(pipeline: Pipeline, state: np.ndarray, trail: np.ndarray, params=sim.PAPER_SIM) -> np.ndarray:
    """Fig. 2 view of one moment as an RGB array: pipe, AUV, camera footprint, waypoint and trail."""
    fig = _figure((5.0, 5.0))
    ax = fig.add_subplot()
    _draw_pipe(ax, pipeline)
    if len(trail) > 1:
        ax.plot(trail[:, 1], trail[:, 0], color=AUV_COLOR, lw=1, ls="--", label="trail")
    pose = (state[sim.X], state[sim.Y], state[sim.PSI])
    _draw_auv(ax, pose, params.camera)
    ax.plot(state[sim.WP_Y], state[sim.WP_X], "kx", ms=8, label="waypoint")
    lost = "" if state[sim.IN_VIEW] else "  (pipe lost: searching)"
    ax.set_title(f"t = {state[sim.TIME]:.0f} s{lost}")
    _frame(ax, pipeline, [trail], margin=3.5)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()


def _frame(ax, pipeline: Pipeline, trails, margin=1.5) -> None:
    pts = [pipeline.points] + [np.asarray(t)[:, :2] for t in trails if len(t)]
    allp = np.vstack(pts)
    lo, hi = allp.min(axis=0) - margin, allp.max(axis=0) + margin
    ax.set_xlim(lo[1], hi[1])
    ax.set_ylim(lo[0], hi[0])


def plot_trajectories(
    pipeline: Pipeline,
    trajectories: Mapping[str, np.ndarray],
    path: str | os.PathLike | None = None,
    title: str | None = None,
    params=sim.PAPER_SIM,
    every: int = 4,
):
    """Plot whole trajectories (poses ``(n, 3)``: x north, y east, ψ) over the pipe, Fig. 2/4 style.

    The AUV and its camera footprint are drawn every ``every`` decisions. Saves to ``path``
    (PNG, written atomically) when given; returns the figure.
    """
    fig = _figure((6.5, 6.5))
    ax = fig.add_subplot()
    _draw_pipe(ax, pipeline)
    for i, (label, poses) in enumerate(trajectories.items()):
        poses = np.asarray(poses)
        color = TRAIL_COLORS[i % len(TRAIL_COLORS)]
        ax.plot(poses[:, 1], poses[:, 0], color=color, lw=1.5, label=label)
        for pose in poses[::every]:
            _draw_auv(ax, pose, params.camera, color=color, alpha=0.45)
    ax.plot(pipeline.points[0, 1], pipeline.points[0, 0], "ko", ms=5, label="start")
    _frame(ax, pipeline, list(trajectories.values()))
    ax.legend(loc="best", fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    if path is not None:
        save_figure(fig, path)
    return fig


def save_figure(fig, path: str | os.PathLike) -> None:
    """Save a figure atomically, in the format its suffix names (PNG without a suffix).

    Raises:
        ValueError: a suffix that is not an image format Matplotlib writes.
    """
    from pathlib import Path

    from pipefollow.atomic import atomic_file
    from pipefollow.outputs import image_formats

    fmt = Path(path).suffix.lower().lstrip(".") or "png"
    if fmt not in image_formats():
        raise ValueError(f"'{path}': '.{fmt}' is not an image format Matplotlib writes")
    with atomic_file(path) as f:
        fig.savefig(f, format=fmt, dpi=110)
