"""Animations of an episode in the paper's Fig. 2 view: a GIF (Pillow) or an MP4 (ffmpeg).

Record an episode with :class:`Recorder` (a Gymnasium wrapper that keeps the simulation state
after every decision, so the episode is exactly the one the caller runs), then write it with
:func:`write_animation`. One frame is drawn per 1-s decision, with Matplotlib's animation
writers: ``PillowWriter`` for ``.gif`` (Pillow comes with Matplotlib) and ``FFMpegWriter``
for ``.mp4`` (needs ``ffmpeg`` on the ``PATH``). With the vision camera each frame shows the
camera image beside the Fig. 2 view, with the detection (red) and the exact piece (green), as
the environment's ``render()`` does.
"""

from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass
from pathlib import Path

import gymnasium as gym
import numpy as np

from pipefollow.files.output_paths import OutputError, check_output_file
from pipefollow.sim import decision as sim
from pipefollow.sim.pipeline import Pipeline

ANIMATION_SUFFIXES = ("gif", "mp4")
PANEL_HEIGHT = 480  # pixels of the camera panel kept per frame (5 screen pixels per image pixel)


@dataclass(frozen=True)
class Frame:
    """The simulation state after a decision, that decision's reward and the return so far.

    ``camera``: the vision camera's panel (RGB, :data:`PANEL_HEIGHT` high) at that moment, or None.
    """

    state: np.ndarray
    reward: float | None
    total: float
    camera: np.ndarray | None = None


class Recorder(gym.Wrapper):
    """Keeps a :class:`Frame` for the reset and every step of the episode it wraps."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.frames: list[Frame] = []

    def reset(self, **kwargs):  # noqa: D102
        out = self.env.reset(**kwargs)
        self.frames = [Frame(self.env.unwrapped.state.copy(), None, 0.0, self._panel())]
        return out

    def step(self, action):  # noqa: D102
        obs, reward, terminated, truncated, info = self.env.step(action)
        total = self.frames[-1].total + float(reward) if self.frames else float(reward)
        self.frames.append(Frame(self.env.unwrapped.state.copy(), float(reward), total, self._panel()))
        return obs, reward, terminated, truncated, info

    def _panel(self) -> np.ndarray | None:
        vision = getattr(self.env.unwrapped, "_vision", None)
        return None if vision is None else vision.panel(PANEL_HEIGHT)


def check_animation_path(path: str | os.PathLike, option: str = "--animate") -> str:
    """Check before any work that ``path`` can be written; returns its format (``gif`` or ``mp4``).

    Raises:
        OutputError: another suffix, a parent that is a file, or ``.mp4`` without ffmpeg.
    """
    suffix = check_output_file(path, option, ANIMATION_SUFFIXES)
    if suffix == "mp4":
        from matplotlib import animation

        if not animation.writers.is_available("ffmpeg"):
            raise OutputError(
                f"{option} '{path}': .mp4 needs ffmpeg on the PATH; install it, or write a .gif"
            )
    return suffix


def write_animation(
    pipeline: Pipeline,
    frames: list[Frame],
    path: str | os.PathLike,
    params: sim.SimParams = sim.PAPER_SIM,
    fps: float = 4.0,
    hold_seconds: float = 1.0,
) -> Path:
    """Write the frames of an episode as an animation (format by suffix), atomically.

    Args:
        pipeline: the episode's pipe.
        frames: what :class:`Recorder` kept.
        path: a ``.gif`` or ``.mp4`` file.
        params: the simulation's parameters (camera footprint).
        fps: frames (decisions) per second of the animation.
        hold_seconds: the last frame stays this long.

    Returns:
        ``path``.
    """
    from matplotlib import animation

    from pipefollow.envs.render import Scene, new_figure
    from pipefollow.files.atomic import atomic_path

    if not frames:
        raise ValueError("no frames to animate")
    fmt = check_animation_path(path, "animation")
    poses = np.array([[f.state[sim.X], f.state[sim.Y], f.state[sim.PSI]] for f in frames])
    scene = Scene(pipeline, params, extent_points=poses)
    writer = animation.PillowWriter(fps=fps) if fmt == "gif" else animation.FFMpegWriter(fps=fps)
    hold = max(0, round(hold_seconds * fps))
    scene.draw()  # lays out the static parts once
    fig, show = scene.fig, None
    if frames[0].camera is not None:  # the camera panel beside the Fig. 2 view, in a figure of both
        scene.update(frames[0].state, poses[:1], frames[0].reward, frames[0].total)
        first = beside(scene.rgb(), frames[0].camera)
        fig = new_figure((first.shape[1] / 100.0, first.shape[0] / 100.0))
        ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
        ax.set_axis_off()
        show = ax.imshow(first, interpolation="nearest")
    with atomic_path(path) as tmp:
        writer.setup(fig, str(tmp), dpi=fig.dpi)
        try:
            for i, frame in enumerate(frames):
                scene.update(frame.state, poses[: i + 1], frame.reward, frame.total)
                if show is not None:
                    show.set_data(beside(scene.rgb(), frame.camera))
                for _ in range(1 + (hold if i == len(frames) - 1 else 0)):
                    writer.grab_frame()
        except BaseException:
            # stop the writer (ffmpeg's process) without letting its complaints hide the cause
            with contextlib.suppress(Exception):
                writer.finish()
            raise
        writer.finish()
    scene.close()
    return Path(path)


def beside(view: np.ndarray, panel: np.ndarray) -> np.ndarray:
    """Two RGB images side by side, the lower one padded with white below to the taller's height."""
    h = max(view.shape[0], panel.shape[0])

    def pad(img):
        out = np.full((h, img.shape[1], 3), 255, dtype=np.uint8)
        out[: img.shape[0]] = img
        return out

    return np.hstack([pad(view), pad(panel)])
