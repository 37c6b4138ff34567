"""A memory of the pipe the tracker has shown: its pieces, carried by the vehicle's navigation.

The tracker (:mod:`pipefollow.perception.track_step`) holds one straight line and a far end beyond
a bend. A piece of pipe that slides to the footprint's side as the vehicle turns, with less than
the pipe's width left in the image, is lost to the detector, and soon to the line, while the exact
camera still sees it. :class:`PieceMemory` keeps the pieces the tracker showed in the last
:attr:`MemoryParams.size` frames whose detection it took (events ``ACCEPTED``, ``BEND``,
``STARTED``, ``REPLACED``) when that detection was the camera's own (not the fused sensor's
sonar), each as its two ends in the vehicle's camera frame, moved frame by frame by the
navigation's motion as the tracker's far end is (:func:`~pipefollow.perception.track_step.moved`).
Where the track shows no pipe, the newest remembered piece that still crosses the footprint along
at least :attr:`MemoryParams.min_piece` is shown, clipped to it, its ends in their remembered order;
a piece is forgotten :attr:`MemoryParams.seconds` frames after it was shown. docs/decisions.md,
"A memory of the pieces shown", has the measurements behind the settings.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.track_step import (
    ACCEPTED,
    BEND,
    OUT_IN_VIEW,
    OUT_SIDE,
    OUT_X1,
    OUT_X2,
    OUT_Y1,
    OUT_Y_NEAR,
    REPLACED,
    STARTED,
    moved,
)
from pipefollow.sim.camera import clip_segment


class MemoryParams(NamedTuple):
    """How much of the pipe :class:`PieceMemory` keeps (docs/decisions.md, "A memory of the pieces shown")."""

    size: int = 20  # pieces kept, the newest first
    seconds: float = 20.0  # frames (1 s each) after which a piece is forgotten
    # m: a remembered piece crossing the footprint along less than this is not shown; 0: any crossing, as
    # the exact camera counts a piece in view
    min_piece: float = 0.0


MEMORY = MemoryParams()

# the columns of a remembered piece: its far end, its near end (camera frame), its age in frames
_X1, _Y1, _X2, _YN, _AGE = 0, 1, 2, 3, 4
_TAKEN = (ACCEPTED, BEND, STARTED, REPLACED)


@njit(cache=True)
def memory_step(P, n, motion, taken, out, seconds, min_piece, half_width, depth):
    """One frame: the pieces moved by ``motion``, ``out`` remembered if ``taken``, else a piece recalled.

    ``P`` holds ``n`` pieces, the newest first; returns the new count. ``out`` (a tracker's output)
    is rewritten with the newest remembered piece in view when it shows no pipe.
    """
    dl, df, dpsi = motion[0], motion[1], motion[2]
    c, s = math.cos(dpsi), math.sin(dpsi)
    for i in range(n):
        P[i, _X1], P[i, _Y1] = moved(P[i, _X1], P[i, _Y1], dl, df, c, s)
        P[i, _X2], P[i, _YN] = moved(P[i, _X2], P[i, _YN], dl, df, c, s)
        P[i, _AGE] += 1.0
    while n > 0 and P[n - 1, _AGE] > seconds:
        n -= 1
    if out[OUT_IN_VIEW] != 0.0:
        if taken:
            n = min(n + 1, P.shape[0])
            for i in range(n - 1, 0, -1):
                P[i, :] = P[i - 1, :]
            P[0, _X1], P[0, _Y1], P[0, _X2], P[0, _YN] = (
                out[OUT_X1],
                out[OUT_Y1],
                out[OUT_X2],
                out[OUT_Y_NEAR],
            )
            P[0, _AGE] = 0.0
        return n
    for i in range(n):
        ax, ay, bx, by = P[i, _X2], P[i, _YN], P[i, _X1], P[i, _Y1]
        t0, t1 = clip_segment(ax, ay, bx, by, -half_width, half_width, 0.0, depth)
        if t1 > t0 and (t1 - t0) * math.hypot(bx - ax, by - ay) >= min_piece:
            out[OUT_IN_VIEW] = 1.0
            out[OUT_X1], out[OUT_Y1] = ax + t1 * (bx - ax), ay + t1 * (by - ay)
            out[OUT_X2], out[OUT_Y_NEAR] = ax + t0 * (bx - ax), ay + t0 * (by - ay)
            out[OUT_SIDE] = 1.0 if out[OUT_X1] >= 0.0 else -1.0
            break
    return n


class PieceMemory:
    """The pieces of pipe a tracker showed from the detections it took (see the module docstring)."""

    def __init__(self, params: MemoryParams = MEMORY, half_width: float = 1.0, depth: float = 3.0) -> None:
        if params.size < 1 or params.seconds < 0.0 or params.min_piece < 0.0:
            raise ValueError(f"MemoryParams: size >= 1, seconds >= 0 and min_piece >= 0, got {params}")
        self.params = params
        self.half_width, self.depth = float(half_width), float(depth)
        self.pieces = np.zeros((int(params.size), 5))
        self.count = 0

    def reset(self) -> None:
        """A new episode (or a new start): nothing remembered."""
        self.count = 0

    def step(self, motion: np.ndarray, event: float, out: np.ndarray, own: bool = True) -> np.ndarray:
        """After the tracker's frame (``motion``, ``event``, output ``out``): ``out``, recalled if empty.

        ``own``: the frame's detection was the camera's own (not a second sensor's): only then is
        the piece shown remembered.
        """
        p = self.params
        self.count = memory_step(
            self.pieces, self.count, motion, own and event in _TAKEN, out,
            float(p.seconds), float(p.min_piece), self.half_width, self.depth,
        )  # fmt: skip
        return out

    def remembered(self) -> np.ndarray:
        """The pieces kept, the newest first: rows of far end, near end (camera frame) and age (frames)."""
        return self.pieces[: self.count].copy()


__all__ = ["MEMORY", "MemoryParams", "PieceMemory", "memory_step"]
