"""A pipe tracker: the pipe as a line fixed in the world, carried by the vehicle's navigation.

The detector (:mod:`pipefollow.perception.detector`) judges every frame on its own: it swaps the
ends when the pipe crosses the view, loses the pipe in a frame without edges, and at a hook may
report only the leg before the corner in one frame and the piece after it in the next. The
tracker keeps what earlier frames showed.

**State.** The pipe's current leg is a straight line fixed in the world, held in the vehicle's
camera frame (x lateral to starboard, y forward, origin at the vehicle's centre) as its direction
``θ`` (rad from the forward axis towards starboard; the line runs along ``u = (sin θ, cos θ)``, the
pipe's own direction) and its signed offset ``d`` (m) along ``n = (cos θ, −sin θ)``: the line is
``p(t) = d·n + t·u``. The same line in earth coordinates would be badly conditioned far from the
origin; held in the vehicle's frame it is re-expressed at every frame by the vehicle's motion,
which is the world-fixed line seen from the new pose. Beside it: the far end seen beyond a bend
and the end seen on the line (world points, moved the same way), and a candidate line.

**Prediction** (an extended Kalman filter): the vehicle moves ``(Δl, Δf)`` (lateral, forward,
in the earlier frame) and turns ``Δψ`` (to starboard) as its *navigation* reports them
(:class:`Navigation`: a DVL's velocity and a gyro's heading change, with their noise, scale error
and bias drift from a seeded generator, not the simulator's truth)::

    θ' = θ − Δψ        d' = d − Δl·cos θ + Δf·sin θ

The process noise is the navigation's (through the Jacobian in ``(Δl, Δf, Δψ)``) plus the pipe's
own bending: a random walk of ``θ`` and ``d`` per metre travelled (:class:`TrackParams`).

**Correction.** Each detected end is tested against the line (a χ² gate with 1 degree of
freedom on its offset from it). Both ends on it: they are ordered along the line (so swapped
ends are put back) and the line through them updates the filter inside a χ² gate with 2 degrees
of freedom (else the near end alone does). One end on it, nearer than the other to where the
line enters the view: the pipe bends in view; that end updates the line and the other is the far
end beyond the bend, and the line ends at the corner (taken where the far end lies along it),
so its extension beyond is not shown once the far end is out of view; unless, with no bend being
followed, the end off the line lies within :attr:`TrackParams.cross_border` of the view's near
border and more than :attr:`TrackParams.bend_behind` behind the other along the line's way:
then the vehicle crosses the pipe where the line grazes the view's side, and the end off the
line is the near one (``track_step._crossed``; in a frame left to the sonar, ``UNSEARCHED_FRAME``,
also when the line runs back towards the vehicle, however far behind: a hook's next leg the
imaging sonar showed before its corner reached the footprint). The end off the line is the near
one as well when the end on it lies where the line leaves the view by a side or the far border
(within :attr:`TrackParams.exit_reach` of that exit, in the exit's half of the line's piece in
view) and the other end inside the view (``track_step._leaves_on_line``): a bend's near end is
where the pipe enters the view, so the pipe comes from that other end, a corner the vehicle is
over. If the pipe leaves the view at the end on the line (a side or the far border), the line
starts again from the piece seen, else that end corrects it.
Otherwise the detection is rejected: it starts (or feeds) a candidate line that replaces the line when seen
:attr:`TrackParams.confirm` times, and at once if it starts where the line enters the view (an
arc the line cannot follow), ends where the far end beyond a bend was seen (the next leg), or if
the line is out of view. A new line keeps the pipe's way (``track_step._reversed``): the next
leg after a bend runs towards the far end seen beyond it (also a hook's leg running back near
parallel); otherwise the last line's way when the two are near parallel, else away from the
corner where they meet; never the detector's order of the ends, which swaps.
Through missed detections the prediction goes on and its uncertainty grows; beyond
``max_misses`` frames (``edge_misses`` while the line's piece in view is shorter than
``edge_piece``: the detector misses short pieces at the view's edge, though not in a murky frame;
``unsearched_misses`` after a frame the detector did not search, whose measurement is a second
sensor's), or an offset uncertain by more than ``max_offset_sd`` (:class:`TrackParams`), the pipe
is lost.

**Observation.** In the exact camera's format (:mod:`pipefollow.sim.camera`): the near end is
the accepted detection's (else where the line enters the view), the far end the far end beyond a
bend while that is in view (also in frames where the detector stops at the corner), else where
the line leaves the view or was seen to end; the in-view flag; the side to search on when it is
out of view (towards the far end beyond a bend). Where the track shows no pipe, the memory of
the pieces it showed (:mod:`pipefollow.perception.piece_memory`, moved by the same navigation)
shows the newest one still in the footprint (``memory=None`` leaves it out).

All of it is compiled (:func:`~pipefollow.perception.track_step.track_step`, one call per frame; no
``fastmath``); the filter and the line's geometry are :mod:`pipefollow.perception.line_ekf`'s, the
navigation :mod:`pipefollow.perception.navigation`'s; :class:`PipeTracker` holds the arrays and
the navigation.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from pipefollow.perception.line_ekf import CHI2_1DOF_99, along, point_correct, point_innovation
from pipefollow.perception.navigation import NAV, Navigation, NavParams
from pipefollow.perception.piece_memory import MEMORY, MemoryParams, PieceMemory
from pipefollow.perception.track_step import (
    ACTIVE,
    CLEAR_FRAME,
    CONFIDENCE,
    EVENT,
    HAD_LINE,
    MISS,
    OUT_IN_VIEW,
    OUT_SIDE,
    OUT_SIZE,
    SIDE,
    TH,
    TRACK,
    TrackParams,
    new_track,
    observe_track,
    pack_params,
    track_step,
)

# the event codes a caller compares PipeTracker.event with, and the state's slots track_point uses
__all__ = ["PipeTracker", "track_point"]


@njit(cache=True)
def track_point(T, px, py, point_sd, gate):
    """A point the pipe passes through (a second sensor's fix, camera metres) updates the line.

    The point must lie on the tracked line within ``gate`` (squared Mahalanobis distance, 1 degree
    of freedom; :func:`point_innovation` with the point's own error ``point_sd``); then it corrects
    the line (:func:`point_correct`) and counts as a sighting (the misses start again). Returns
    whether it was taken; without a line nothing happens.
    """
    if T[ACTIVE] == 0.0:
        return False
    nu, j, S, m2 = point_innovation(T, TH, px, py, point_sd)
    if m2 > gate:
        return False
    point_correct(T, TH, nu, j, S)
    T[MISS] = 0.0
    return True


class PipeTracker:
    """One camera's track of the pipe (see the module docstring), fed one detection per frame."""

    def __init__(
        self,
        half_width: float = 1.0,
        depth: float = 3.0,
        params: TrackParams = TRACK,
        nav: NavParams = NAV,
        dt: float = 1.0,
        memory: MemoryParams | None = MEMORY,
    ) -> None:
        self.half_width, self.depth = float(half_width), float(depth)
        self.params = params
        self._tp = pack_params(params)
        self.navigation = Navigation(nav, dt)
        self.state = new_track()
        self.out = np.zeros(OUT_SIZE)
        self._det = np.zeros(4)
        self._still = np.zeros(3)
        self._pose: tuple[float, float, float] | None = None
        self.memory = None if memory is None else PieceMemory(memory, self.half_width, self.depth)

    def reset(self, rng: np.random.Generator, pose: tuple[float, float, float]) -> None:
        """A new episode at the true ``pose``: an empty track; the navigation's errors from ``rng``."""
        self.navigation.reset(rng)
        self.start()
        self._pose = pose

    def start(self) -> None:
        """An empty track; the next frame is the first (no motion before it), the navigation as it is."""
        self.state[:] = new_track()
        self._pose = None
        if self.memory is not None:
            self.memory.reset()

    def step(
        self,
        pose: tuple[float, float, float],
        found: bool,
        det: tuple[float, float, float, float],
        frame: int = CLEAR_FRAME,
        own: bool = True,
    ) -> np.ndarray:
        """A frame from the true ``pose`` with the detection ``det`` = (x1, y1, x2, y_near): the observation.

        ``frame``: what the frame was to the detector (``track_step.CLEAR_FRAME``, ``MURKY_FRAME``:
        no short piece carried longer, ``UNSEARCHED_FRAME``: ``det`` is a second sensor's and the
        line is carried :attr:`TrackParams.unsearched_misses` frames without a sighting).
        ``own``: ``det`` is the camera's own detection (not a second sensor's): the memory keeps
        only such pieces. Returns the output array (in view, x1, y1, x2, y_near, side), reused
        frame after frame.
        """
        if self._pose is None:
            motion = self._still
        else:
            motion = self.navigation.motion(self._pose, pose)
        self._pose = pose
        d = self._det
        d[0], d[1], d[2], d[3] = det
        track_step(
            self.state, found, d, motion, self.navigation.variances, self._tp,
            self.half_width, self.depth, self.out, frame,
        )  # fmt: skip
        if self.memory is not None:
            self.memory.step(motion, self.state[EVENT], self.out, own)
        return self.out

    def point(self, x: float, y: float, point_sd: float, gate: float = CHI2_1DOF_99) -> np.ndarray:
        """After :meth:`step`: a second sensor's point on the pipe (:func:`track_point`).

        Returns the observation: the output array of :meth:`step`, rewritten if the point was taken.
        """
        if track_point(self.state, float(x), float(y), float(point_sd), float(gate)):
            observe_track(self.state, self._tp, self.half_width, self.depth, self.out)
        return self.out

    def search_towards(self, x: float) -> np.ndarray:
        """While no pipe is in view: search on the side of ``x`` (a second sensor's sighting off the view).

        Returns the observation: the output array of :meth:`step` with its side set.
        """
        if self.out[OUT_IN_VIEW] == 0.0:
            side = 1.0 if x >= 0.0 else -1.0
            self.state[SIDE] = side
            self.out[OUT_SIDE] = side
        return self.out

    def ordered(self, x1: float, y1: float, x2: float, y_near: float) -> tuple[float, float, float, float]:
        """A piece's ends (far ``x1, y1``, near ``x2, y_near``) taken the way of the tracked line.

        Of the line last tracked if it is lost (it is still predicted), which keeps the pipe's way
        (``track_step._reversed``); as given while no line was tracked yet.
        """
        T = self.state
        if T[HAD_LINE] != 0.0 and along(T[TH], x1 - x2, y1 - y_near) < 0.0:
            return x2, y_near, x1, y1
        return x1, y1, x2, y_near

    @property
    def confidence(self) -> float:
        """How well the tracked offset is known, in [0, 1] (0 without a track)."""
        return float(self.state[CONFIDENCE])

    @property
    def event(self) -> float:
        """What the last detection did: ``track_step.ACCEPTED``, ``BEND``, ``REJECTED``, ..."""
        return float(self.state[EVENT])
