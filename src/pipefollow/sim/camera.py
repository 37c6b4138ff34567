"""The downward camera: which piece of pipe is in view, and the observation it gives (paper §4).

Camera coordinates follow the paper: ``x`` lateral (body y, positive to starboard), ``y``
forward (body x), origin at the AUV's centre. The footprint is the rectangle
``x ∈ [-half_width, half_width]``, ``y ∈ [0, depth]``. The pipeline polyline is clipped to it
(Liang–Barsky per segment); consecutive clipped segments that meet at a vertex inside the
footprint form one visible piece. The observation uses the piece that continues from the AUV's
progress along the pipe:

* ``(x1, y1)``: the piece's far end (furthest along the pipe's direction),
* ``x2``: lateral position of its near end (``y_near`` is its forward position),
* ``e_dist = (x1 + x2) / 2`` and ``e_angl = atan2(x1 − x2, y1 − y_near)`` (docs/design.md).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from numba import njit

from pipefollow.sim.disturbance import NO_BURIAL


class CameraParams(NamedTuple):
    """Camera footprint in the body frame (docs/design.md; matches the paper's state ranges)."""

    half_width: float = 1.0  # lateral half-width of the footprint (m)
    depth: float = 3.0  # forward extent of the footprint from the AUV's centre (m)


PAPER_CAMERA = CameraParams()


class View(NamedTuple):
    """What :func:`observe` reports: the visible piece that continues from the AUV's progress."""

    in_view: bool  # whether any pipe is in view; if not, the other fields are zero
    x1: float  # the piece's far end (camera metres) ...
    y1: float
    x2: float  # ... and its near end
    y_near: float
    s_near: float  # arc length (m) of the near end ...
    s_far: float  # ... and of the far end


class Piece(NamedTuple):
    """A visible piece of pipe while :func:`observe` assembles the pieces and keeps the best one."""

    gap: float  # arc-length gap (m) between the piece and the AUV's progress; inf: no piece yet
    x1: float  # the far end (camera metres) ...
    y1: float
    x2: float  # ... and the near end
    y_near: float
    s_near: float  # arc length (m) of the near end ...
    s_far: float  # ... and of the far end


@njit(cache=True)
def to_camera(px, py, x, y, psi):
    """Earth point ``(px, py)`` in camera coordinates ``(lateral, forward)`` of pose (x, y, ψ)."""
    dx, dy = px - x, py - y
    cs, sn = math.cos(psi), math.sin(psi)
    return -sn * dx + cs * dy, cs * dx + sn * dy


@njit(cache=True)
def clip_segment(ax, ay, bx, by, xmin, xmax, ymin, ymax):
    """Liang–Barsky: parameters ``(t0, t1)`` of the part of a→b inside the box, or ``(1, 0)``."""
    t0, t1 = 0.0, 1.0
    dx, dy = bx - ax, by - ay
    for i in range(4):
        if i == 0:
            p, q = -dx, ax - xmin
        elif i == 1:
            p, q = dx, xmax - ax
        elif i == 2:
            p, q = -dy, ay - ymin
        else:
            p, q = dy, ymax - ay
        if p == 0.0:
            if q < 0.0:
                return 1.0, 0.0
        else:
            t = q / p
            if p < 0.0:
                if t > t1:
                    return 1.0, 0.0
                if t > t0:
                    t0 = t
            else:
                if t < t0:
                    return 1.0, 0.0
                if t < t1:
                    t1 = t
    return t0, t1


@njit(cache=True)
def observe(points, cum, x, y, psi, progress, cam, buried_from=None, buried_to=None):
    """What the camera sees from pose (x, y, ψ).

    Returns a :class:`View` ``(in_view, x1, y1, x2, y_near, s_near, s_far)``: the far end, the
    near end's lateral and forward position, and the arc lengths of the near and far ends of the
    chosen piece. When nothing is in view, ``in_view`` is False and the other values are zero.

    ``buried_from``/``buried_to`` (optional, sorted and disjoint arc-length intervals, unused
    slots ``inf``) are stretches the camera cannot see: they are cut out of the visible polyline,
    so a buried stretch splits a piece in two.
    """
    if buried_from is None:
        return _observe(points, cum, x, y, psi, progress, cam, NO_BURIAL, NO_BURIAL)
    return _observe(points, cum, x, y, psi, progress, cam, buried_from, buried_to)


@njit(cache=True)
def _observe(points, cum, x, y, psi, progress, cam, buried_from, buried_to):
    w, depth = cam.half_width, cam.depth
    buried = buried_from[0] < math.inf
    best = Piece(math.inf, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # the best piece so far
    piece = best  # the piece being assembled; its gap unused
    open_piece = False
    continues = False  # the open piece reached the end of its last segment
    ax, ay = to_camera(points[0, 0], points[0, 1], x, y, psi)
    for i in range(points.shape[0] - 1):
        bx, by = to_camera(points[i + 1, 0], points[i + 1, 1], x, y, psi)
        t0, t1 = clip_segment(ax, ay, bx, by, -w, w, 0.0, depth)
        seg = cum[i + 1] - cum[i]
        if t0 <= t1 and not buried:
            best, piece = _extend(
                best, piece, open_piece, continues, progress, ax, ay, bx, by, t0, t1, cum[i], seg
            )
            open_piece = True
            continues = t1 == 1.0
        elif t0 <= t1:
            # cut the buried intervals out of [t0, t1]
            ta = t0
            continues_next = False
            for k in range(len(buried_from)):
                lo = (buried_from[k] - cum[i]) / seg
                hi = (buried_to[k] - cum[i]) / seg
                if hi <= ta or lo >= t1:
                    continue
                if lo > ta:
                    best, piece = _extend(
                        best, piece, open_piece, continues, progress, ax, ay, bx, by, ta, lo, cum[i], seg
                    )
                    open_piece = True
                    continues = False
                ta = max(ta, hi)
                if ta >= t1:
                    break
            if ta < t1 or (ta == t1 and t0 == t1):
                best, piece = _extend(
                    best, piece, open_piece, continues, progress, ax, ay, bx, by, ta, t1, cum[i], seg
                )
                open_piece = True
                continues_next = t1 == 1.0
            continues = continues_next
        elif open_piece:
            best = _closer(best, piece, progress)
            open_piece = False
        ax, ay = bx, by
    if open_piece:
        best = _closer(best, piece, progress)
    return View(best.gap < math.inf, best.x1, best.y1, best.x2, best.y_near, best.s_near, best.s_far)


@njit(cache=True)
def _extend(best, piece, open_piece, continues, progress, ax, ay, bx, by, ta, tb, s0, seg):
    """Add the part ``[ta, tb]`` of segment a→b (arc length ``s0`` at a) to the pieces in view.

    It continues the open piece if that reached the end of the previous segment and this part
    starts at the segment's start; otherwise it closes the open piece and starts a new one.
    Returns the updated ``(best, piece)``.
    """
    if not (open_piece and continues and ta == 0.0):
        if open_piece:
            best = _closer(best, piece, progress)
        near_x, near_y = ax + ta * (bx - ax), ay + ta * (by - ay)
        piece = Piece(0.0, 0.0, 0.0, near_x, near_y, s0 + ta * seg, 0.0)
    far_x, far_y = ax + tb * (bx - ax), ay + tb * (by - ay)
    return best, Piece(0.0, far_x, far_y, piece.x2, piece.y_near, piece.s_near, s0 + tb * seg)


@njit(cache=True)
def _closer(best, piece, progress):
    """The better of two pieces: the smaller arc-length gap to the AUV's progress (first wins ties)."""
    s_near, s_far = piece.s_near, piece.s_far
    gap = s_near - progress if progress < s_near else max(progress - s_far, 0.0)
    if gap < best.gap:
        return Piece(gap, piece.x1, piece.y1, piece.x2, piece.y_near, s_near, s_far)
    return best


@njit(cache=True)
def tracking_errors(x1, y1, x2, y_near):
    """``e_dist`` (m) and ``e_angl`` (rad) of docs/design.md: pipe centred and vertical in the frame.

    ``e_angl`` is the angle between the pipe's line and the frame's vertical, in [−π/2, π/2]: a
    line's deviation from the vertical, whichever way the pipe runs. So the worst in-view reward
    of eq. 19 is about −(1 + (π/2)² + 4) ≈ −7.5 − v_x, above the −10 of a lost pipe (paper §4).
    """
    e_angl = math.atan2(x1 - x2, y1 - y_near)
    if e_angl > 0.5 * math.pi:
        e_angl -= math.pi
    elif e_angl < -0.5 * math.pi:
        e_angl += math.pi
    return 0.5 * (x1 + x2), e_angl
