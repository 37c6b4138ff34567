"""Pictures in the style of the paper's Figs. 2 and 4: pipe, AUV, camera footprint, waypoint, trail.

Maps are drawn with east to the right and north up. Matplotlib is imported here only, and
without pyplot, so rendering works headless and in worker processes.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping

import numpy as np

from pipefollow.sim import decision as sim
from pipefollow.sim.pipeline import Pipeline

PIPE_COLOR = "tab:red"
AUV_COLOR = "tab:blue"
CAMERA_COLOR = "tab:green"
TRAIL_COLORS = ("tab:blue", "tab:orange", "tab:purple", "tab:brown", "tab:gray")


def new_figure(size=(6.0, 6.0)):
    """A Matplotlib figure on the Agg canvas, outside pyplot (no global state, no window)."""
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


def _hull_outline(length: float = 0.9, width: float = 0.22) -> np.ndarray:
    """The AUV's outline seen from above, body coordinates (forward, starboard) in metres.

    A torpedo: rounded nose, cylindrical body, tapered tail with fins (the centre is the origin).
    """
    half, r = length / 2.0, width / 2.0
    arc = np.linspace(-math.pi / 2, math.pi / 2, 11)
    nose = [(half - r + r * math.cos(a), r * math.sin(a)) for a in arc]  # port → bow → starboard
    starboard_aft = [
        (-half + 0.22, r),  # end of the cylinder
        (-half + 0.07, 0.55 * r),  # taper
        (-half + 0.05, 1.6 * r),  # fin
        (-half - 0.03, 1.6 * r),
        (-half - 0.01, 0.35 * r),
        (-half, 0.0),  # stern
    ]
    port_aft = [(f, -lat) for f, lat in reversed(starboard_aft[:-1])]
    return np.array(nose + starboard_aft + port_aft, dtype=float)


HULL = _hull_outline()


def _to_map(x: float, y: float, psi: float, body: np.ndarray) -> np.ndarray:
    """Body points (forward, starboard) of an AUV at (x north, y east, ψ) → map points (east, north)."""
    c, s = math.cos(psi), math.sin(psi)
    north = x + c * body[:, 0] - s * body[:, 1]
    east = y + s * body[:, 0] + c * body[:, 1]
    return np.column_stack([east, north])


class Scene:
    """The paper's Fig. 2 view of one episode, drawn once and then updated frame by frame.

    The static parts (axes, grid, pipe, legend) are drawn once and kept as a background image;
    a frame restores it and draws only what moves: the AUV's hull and heading, the camera
    footprint, the detected piece of pipe (the line between its two ends, as the observation
    has them), the waypoint, the trail, and time and reward in the top-left corner. That is
    what makes a frame cheap (a few milliseconds instead of a full Matplotlib draw).

    Args:
        pipeline: the pipe.
        params: the simulation's parameters (for the camera footprint).
        extent_points: (n, 2) points (x north, y east) the view must show besides the pipe,
            e.g. a whole trajectory known in advance; the view also grows when the AUV leaves it.
        size: figure size in inches (100 dpi).
        pyplot: make the figure with pyplot, to show it in a window (``render_mode="human"``).
    """

    MARGIN = 3.5  # m around the pipe: the camera footprint reaches 3 m ahead

    def __init__(
        self,
        pipeline: Pipeline,
        params=sim.PAPER_SIM,
        extent_points: np.ndarray | None = None,
        size=(5.0, 5.0),
        pyplot: bool = False,
    ) -> None:
        from matplotlib.lines import Line2D
        from matplotlib.patches import Polygon

        self.pipeline, self.camera, self._pyplot = pipeline, params.camera, pyplot
        if pyplot:
            import matplotlib.pyplot as plt

            self.fig = plt.figure(figsize=size, dpi=100)
        else:
            self.fig = new_figure(size)
        self.ax = ax = self.fig.add_subplot()
        _draw_pipe(ax, pipeline)
        ax.set_title(pipeline.name)
        extent = [pipeline.points] + ([np.asarray(extent_points)[:, :2]] if extent_points is not None else [])
        allp = np.vstack(extent)
        self._lo, self._hi = allp.min(axis=0) - self.MARGIN, allp.max(axis=0) + self.MARGIN
        self._set_limits()
        moving = dict(animated=True)
        self.trail = ax.plot([], [], color=AUV_COLOR, lw=1, ls="--", **moving)[0]
        self.footprint = ax.add_patch(
            Polygon(np.zeros((4, 2)), closed=True, fill=False, ec=CAMERA_COLOR, lw=1.4, **moving)
        )
        self.piece = ax.plot([], [], color="gold", lw=3, solid_capstyle="round", **moving)[0]
        self.hull = ax.add_patch(Polygon(HULL, closed=True, fc=AUV_COLOR, ec="navy", lw=0.8, **moving))
        self.heading = ax.plot([], [], color="navy", lw=1.2, **moving)[0]
        self.waypoint = ax.plot([], [], "kx", ms=8, mew=2, **moving)[0]
        self.text = ax.text(
            0.02,
            0.98,
            "",
            transform=ax.transAxes,
            va="top",
            ha="left",
            fontsize=8,
            family="monospace",
            bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.85),
            **moving,
        )
        self._moving = [
            self.trail,
            self.footprint,
            self.piece,
            self.hull,
            self.heading,
            self.waypoint,
            self.text,
        ]
        # proxies: the legend is part of the static background
        handles = [
            Line2D([], [], color=PIPE_COLOR, lw=3, alpha=0.8, label="pipe"),
            Line2D([], [], color="gold", lw=3, label="detected piece"),
            Polygon(np.zeros((3, 2)), fill=False, ec=CAMERA_COLOR, lw=1.4, label="camera footprint"),
            Line2D([], [], color="k", marker="x", ls="", ms=8, mew=2, label="waypoint"),
            Line2D([], [], color=AUV_COLOR, lw=1, ls="--", label="trail"),
        ]
        self.legend = ax.legend(handles=handles, loc="best", fontsize=7, framealpha=0.85)
        self.fig.tight_layout()
        self._background = None

    def _set_limits(self) -> None:
        self.ax.set_xlim(self._lo[1], self._hi[1])
        self.ax.set_ylim(self._lo[0], self._hi[0])

    def _keep_in_view(self, x: float, y: float) -> None:
        """Grow the view (and redraw the background) if the AUV's surroundings leave it."""
        lo, hi = np.minimum(self._lo, [x - 3.2, y - 3.2]), np.maximum(self._hi, [x + 3.2, y + 3.2])
        if np.any(lo < self._lo) or np.any(hi > self._hi):
            self._lo, self._hi = lo - 1.0, hi + 1.0
            self._set_limits()
            self._background = None

    def update(
        self, state: np.ndarray, trail: np.ndarray, reward: float | None = None, total: float | None = None
    ):
        """Set the moving parts to ``state`` (a simulation state array) and ``trail`` ((n, 3) poses)."""
        x, y, psi = state[sim.X], state[sim.Y], state[sim.PSI]
        self._keep_in_view(x, y)
        trail = np.asarray(trail)
        if len(trail) > 1:
            self.trail.set_data(trail[:, 1], trail[:, 0])
        else:
            self.trail.set_data([], [])
        self.hull.set_xy(_to_map(x, y, psi, HULL))
        self.heading.set_data(*_to_map(x, y, psi, np.array([[0.45, 0.0], [1.1, 0.0]])).T)
        self.footprint.set_xy(_footprint(x, y, psi, self.camera))
        in_view = bool(state[sim.IN_VIEW])
        if in_view:  # camera (lateral, forward) → body (forward, starboard)
            ends = np.array([[state[sim.Y_NEAR], state[sim.X2]], [state[sim.Y1], state[sim.X1]]])
            self.piece.set_data(*_to_map(x, y, psi, ends).T)
        else:
            self.piece.set_data([], [])
        self.waypoint.set_data([state[sim.WP_Y]], [state[sim.WP_X]])
        lines = [f"t = {state[sim.TIME]:5.1f} s"]
        if reward is not None:
            lines.append(f"reward {reward:+7.2f}")
        if total is not None:
            lines.append(f"return {total:+7.2f}")
        lines.append("pipe in view" if in_view else "pipe lost: searching")
        self.text.set_text("\n".join(lines))
        return self

    def draw(self) -> None:
        """Draw the current frame on the canvas (the background once, then the moving parts)."""
        canvas = self.fig.canvas
        if self._background is None:
            canvas.draw()
            # "best" is searched on every full draw (an animation writer's savefig): keep the
            # place found now, clear of the pipe
            box = self.legend.get_window_extent()
            self.legend.set_loc(tuple(self.ax.transAxes.inverted().transform((box.x0, box.y0))))
            self._background = canvas.copy_from_bbox(self.fig.bbox)
        canvas.restore_region(self._background)
        for artist in self._moving:
            self.ax.draw_artist(artist)

    def rgb(self) -> np.ndarray:
        """The current frame as an (h, w, 3) uint8 array."""
        self.draw()
        return np.asarray(self.fig.canvas.buffer_rgba())[..., :3].copy()

    def open_window(self) -> None:
        """Show the (pyplot) figure in a window, if the Matplotlib backend can show windows."""
        if _interactive_backend():
            import matplotlib.pyplot as plt

            plt.show(block=False)

    def show(self, pause: float = 0.0) -> None:
        """Put the current frame on the screen and let the window's events run for ``pause`` s."""
        self.draw()
        canvas = self.fig.canvas
        canvas.blit(self.fig.bbox)
        if _interactive_backend():
            canvas.flush_events()
            canvas.start_event_loop(pause)

    def close(self) -> None:
        """Release the figure (and close its window, for a pyplot figure)."""
        if self._pyplot:  # a figure pyplot does not know is left to the garbage collector
            import matplotlib.pyplot as plt

            plt.close(self.fig)


def _interactive_backend() -> bool:
    """Whether Matplotlib's current backend shows windows (not Agg, PDF, a notebook's inline ...)."""
    import matplotlib

    backend = matplotlib.get_backend().lower()
    try:
        from matplotlib.backends import BackendFilter, backend_registry

        interactive = backend_registry.list_builtin(BackendFilter.INTERACTIVE)
    except ImportError:  # Matplotlib < 3.9
        from matplotlib import rcsetup

        interactive = rcsetup.interactive_bk
    return backend in {b.lower() for b in interactive}


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
    fig = new_figure((6.5, 6.5))
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

    from pipefollow.files.atomic import atomic_file
    from pipefollow.files.output_paths import image_formats

    fmt = Path(path).suffix.lower().lstrip(".") or "png"
    if fmt not in image_formats():
        raise ValueError(f"'{path}': '.{fmt}' is not an image format Matplotlib writes")
    with atomic_file(path) as f:
        fig.savefig(f, format=fmt, dpi=110)
