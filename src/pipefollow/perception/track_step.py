"""The tracker's compiled frame step: the state's slots, the settings, and how a detection is taken.

:func:`track_step` predicts the line by the navigation's motion, takes or rejects the frame's
detection (:mod:`pipefollow.perception.tracker` describes the rules) and writes the observation
(:func:`observe_track`); the filter and the line's geometry are :mod:`pipefollow.perception.line_ekf`'s.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.line_ekf import (
    CHI2_1DOF_90,
    CHI2_2DOF_99,
    along,
    correct,
    crossing,
    in_footprint,
    innovation,
    inside,
    measured_line,
    on_line,
    oriented,
    point_correct,
    point_innovation,
    predict,
)
from pipefollow.sim import records
from pipefollow.sim.controller import wrap_angle as wrap


class TrackParams(NamedTuple):
    """The tracker's settings (docs/decisions.md "pipe tracker" has the reasons)."""

    point_sd: float = 0.05  # a detected end's error (m) along each axis: 1.6 pixels
    bend_sd: float = 0.2  # the pipe's direction's random walk (rad per √m travelled): arcs and bends
    shift_sd: float = 0.03  # the pipe's offset's random walk (m per √m travelled)
    gate: float = CHI2_2DOF_99  # Mahalanobis gate of a detection's line (squared, 2 degrees of freedom)
    point_gate: float = CHI2_1DOF_90  # ... and of a detected end on the line (1 degree of freedom)
    max_misses: int = 2  # frames the line (and a far end beyond a bend) is carried without a detection
    max_offset_sd: float = 0.4  # m: a line whose offset is this uncertain is lost
    confirm: int = 2  # frames in a row a new line must be seen in to replace a tracked one in view
    border: float = 0.06  # m: a detected far end this near the footprint's border is where the pipe leaves it
    far_margin: float = (
        0.25  # m: a far end beyond a bend this far outside the footprint still shows (on its border)
    )
    far_match: float = (
        0.4  # m: a new line whose end lies this near the far end beyond a bend continues the pipe
    )
    near_reach: float = 0.5  # m: a rejected detection with an end this near the line's entry: the pipe
    edge_misses: int = 5  # frames a line is carried without a detection while its piece in view is short
    edge_piece: float = 0.6  # m: a piece in view shorter than this is short (the detector misses such pieces)
    # frames a line is carried without a sighting after a frame the detector did not search (a murky
    # frame of the fused sensor, fed by the sonar alone): the camera's 2 kept a lagging line at the
    # sonar's bends (docs/decisions.md, "Murky frames left to the sonar")
    unsearched_misses: int = 1
    # m: an end off the line this far behind the end on it (along the line's way) is no bend's far
    # end but where the pipe comes from (docs/decisions.md, "The way of a piece the vehicle crosses")
    bend_behind: float = 0.3
    # m: the end off the line of a piece the vehicle crosses lies this near the view's near border:
    # ``border`` and a quarter of the 0.25-m pipe, as a half-buried pipe's visible half ends beside
    # its axis (docs/decisions.md, "Half buried at sharp turns"); an end farther than this from the
    # sides and the far border lies inside the view (``_leaves_on_line``)
    cross_border: float = 0.12
    # m: an end on the line this near (along it) where the line leaves the view, at a side or the far
    # border, is where the pipe leaves the view, no bend's near end (docs/decisions.md, "A corner
    # the vehicle is over")
    exit_reach: float = 0.3


TRACK = TrackParams()
# where each setting sits in pack_params' array, from the field names (the compiled code reads them so)
_AT = records.offsets(TRACK)
_POINT_SD, _BEND_SD, _SHIFT_SD, _GATE, _POINT_GATE = (
    _AT[n] for n in ("point_sd", "bend_sd", "shift_sd", "gate", "point_gate")
)
_MAX_MISSES, _MAX_OFFSET_SD, _CONFIRM, _BORDER, _FAR_MARGIN, _FAR_MATCH = (
    _AT[n] for n in ("max_misses", "max_offset_sd", "confirm", "border", "far_margin", "far_match")
)
_NEAR_REACH, _EDGE_MISSES, _EDGE_PIECE, _UNSEARCHED_MISSES, _BEND_BEHIND, _CROSS_BORDER = (
    _AT[n]
    for n in ("near_reach", "edge_misses", "edge_piece", "unsearched_misses", "bend_behind", "cross_border")
)
_EXIT_REACH = _AT["exit_reach"]

# what the frame is to the tracker (track_step's ``frame``): searched by the detector in a clear
# frame; searched in a murky one (below visibility.EDGE_CONTRAST: its misses are not of short
# pieces, so no edge carry); not searched (the measurement another sensor's: unsearched_misses)
CLEAR_FRAME, MURKY_FRAME, UNSEARCHED_FRAME = 0, 1, 2

# slots of a track's state array: the line, its covariance (Pθθ, Pθd, Pdd), the far end seen
# beyond a bend (off the line), the end seen on the line (where it ends or turns), the candidate
# line, and bookkeeping
TH, D, P, ACTIVE, MISS = 0, 1, 2, 5, 6
HAS_FAR, FAR_X, FAR_Y, FAR_AGE = 7, 8, 9, 10
HAS_END, END_X, END_Y = 11, 12, 13
C_TH, C_D, C_P, C_ACTIVE, C_HITS = 14, 15, 16, 19, 20
SIDE, CONFIDENCE, HAD_LINE, EVENT = 21, 22, 23, 24  # HAD_LINE: a line was tracked (it is still predicted)
NEAR_X, NEAR_Y, HAS_NEAR = 25, 26, 27  # this frame's accepted near end
STATE_SIZE = 28
# EVENT: what the frame's detection did
NO_DETECTION, ACCEPTED, BEND, REJECTED, STARTED, REPLACED = 0.0, 1.0, 2.0, 3.0, 4.0, 5.0
# slots of the output
OUT_IN_VIEW, OUT_X1, OUT_Y1, OUT_X2, OUT_Y_NEAR, OUT_SIDE = 0, 1, 2, 3, 4, 5
OUT_SIZE = 6
REACH = 20.0  # m: a line is clipped to the footprint as a segment this far either side of its foot


def pack_params(p: TrackParams) -> np.ndarray:
    """The settings as the compiled code takes them (in field order, read by name: ``_AT``)."""
    return records.pack(p)


@njit(cache=True)
def moved(x, y, dl, df, c, s):
    """A world-fixed point ``(x, y)`` of the camera frame seen from the frame after the motion.

    The motion is the navigation's ``(Δl, Δf, Δψ)`` with ``c, s = cos Δψ, sin Δψ``.
    """
    ex, ey = x - dl, y - df
    return c * ex - s * ey, s * ex + c * ey


@njit(cache=True)
def _start(T, o, th, d, r_tt, r_td, r_dd):
    T[o], T[o + 1] = th, d
    T[o + 2], T[o + 3], T[o + 4] = r_tt, r_td, r_dd


PARALLEL = math.sin(math.radians(25.0))  # lines closer in direction than this have no corner worth the name


@njit(cache=True)
def _line_end(T, hw, depth):
    """The line's part in view ``(t0, t1)`` (t0 > t1 if none), up to where it was seen to end."""
    a, b = in_footprint(T[TH], T[D], -REACH, REACH, hw, depth)
    if T[HAS_END] != 0.0:
        b = min(b, along(T[TH], T[END_X], T[END_Y]))
    return a, b


@njit(cache=True)
def _take_end(T, fx, fy, hw, depth, border):
    """A far end on the line: where the pipe is seen to end or turn (inside), or that it goes on (border)."""
    if min(hw - abs(fx), fy, depth - fy) > border:
        T[HAS_END], T[END_X], T[END_Y] = 1.0, fx, fy
    else:
        T[HAS_END], T[HAS_FAR] = 0.0, 0.0  # the pipe leaves the view straight on


# how a new line's direction is chosen (_start_line's ``mode``)
AS_GIVEN = 0  # the ends as given: the caller ordered them
TOWARDS_FAR = 1  # the leg after a bend, through the far end seen beyond it
AFTER_LINE = 2  # the line was out of view or lost: the pipe seen again
CONTRADICTED = 3  # the line in view was contradicted frame after frame: it was wrong, or left behind


@njit(cache=True)
def _reversed(T, x1, y1, x2, y_near, th, d, mode, point_sd):
    """Whether the line ``(θ, d)`` through a detection, read from its near end to its far end, runs backwards.

    A line fixed in the world keeps its direction: a new line takes the last line's way, never the
    detector's order of its ends (which swaps where the pipe crosses the view), unless a bend lies
    between them. The leg after a bend (``TOWARDS_FAR``) runs towards the far end seen beyond the
    bend, near parallel to the last line or not (a hook's next leg runs back beside the first).
    Otherwise, near parallel (within :data:`PARALLEL`): the last line's way; else the last line
    meets the new one at a corner, from which the pipe runs on, away from the crossing. A crossing
    *on* the piece seen is no corner (the pipe runs on both sides of it): the last line was wrong.
    Contradicted in view (``CONTRADICTED``) it was seen a frame or two before, and the new line
    takes its nearer way; lost or out of view (``AFTER_LINE``) it was carried blind, and the pipe
    comes from the piece's end nearer the vehicle.
    """
    if mode == AS_GIVEN or T[HAD_LINE] == 0.0:
        return False
    if mode == TOWARDS_FAR and T[HAS_FAR] != 0.0:
        # the pipe goes on towards the far end seen beyond the bend: the end nearer it is the far one
        # (also when the next leg runs back near parallel: a hook's, whose way is not the last line's)
        return math.hypot(x2 - T[FAR_X], y_near - T[FAR_Y]) < math.hypot(x1 - T[FAR_X], y1 - T[FAR_Y])
    nearer_way = abs(wrap(th - T[TH])) > 0.5 * math.pi
    if abs(math.sin(T[TH] - th)) < PARALLEL:
        return nearer_way
    t_c = crossing(th, d, T[TH], T[D])  # along the new line
    if math.isnan(t_c):
        return nearer_way
    t_near, t_far = along(th, x2, y_near), along(th, x1, y1)
    if t_near - point_sd < t_c < t_far + point_sd:  # on the piece: no corner
        if mode == CONTRADICTED:
            return nearer_way
        return x2 * x2 + y_near * y_near > x1 * x1 + y1 * y1  # from the end nearer the vehicle
    return t_c > 0.5 * (t_near + t_far)


@njit(cache=True)
def _crossed(T, x1, y1, x2, y_near, border, behind, frame):
    """Whether a detection with its near end ``(x2, y_near)`` on the line and ``(x1, y1)`` off it is no bend.

    The end off the line lies within ``border`` (m, ``TrackParams.cross_border``) of the view's
    near border and more than ``behind`` (m) behind the other along the line's way, and no bend is
    being followed (no far end beyond one carried): the vehicle crosses the pipe where the line
    grazes the view's side and enters it there, and the pipe comes from under the vehicle, off the
    line; a hook's far end beyond its corner, which may also lie behind, leaves by the sides
    (docs/decisions.md, "The way of a piece the vehicle crosses").

    In a frame too murky to search (``UNSEARCHED_FRAME``: the measurement is the sonar's) the end
    off the line on the near border is where the pipe comes from also when the line runs back
    towards the vehicle (its way more than 90° from ahead): a sonar that looks ahead (the imaging
    sonar's map) sees a hook's next leg before the corner reaches the footprint, the tracker can
    hold that leg while the vehicle is still on the first, and the first then joins it from under
    the vehicle (docs/decisions.md, "A hook's next leg seen early").
    """
    if T[HAS_FAR] != 0.0 or y1 >= border:
        return False
    if frame == UNSEARCHED_FRAME and math.cos(T[TH]) < 0.0:
        return True
    return along(T[TH], x1, y1) < along(T[TH], x2, y_near) - behind


@njit(cache=True)
def _leaves_on_line(T, x1, y1, x2, y_near, a, b, hw, depth, tp):
    """Whether a piece with an end ``(x2, y_near)`` on the line, ``(x1, y1)`` off it, runs from the off end.

    ``[a, b]`` is the line's part in the footprint along it (:func:`in_footprint`; ``a > b``: none),
    ``tp`` the settings (:func:`pack_params`).

    A bend's near end is where the pipe enters the view along the line. An end on the line at a side
    or the far border (within ``TrackParams.border``), within ``TrackParams.exit_reach`` of where
    the line leaves the view and in the half of the line's piece in view nearer that exit, is where
    the pipe leaves the view. If the end off the line lies inside the view (more than
    ``TrackParams.cross_border`` from a side and the far border; a pipe that left by the line's exit
    may come back in there), the pipe comes from it: a corner the vehicle is over, whose first leg
    the detector did not follow under the vehicle (a half-buried hook), or a hook's first leg
    joining its next leg, which the tracker took before the corner (docs/decisions.md, "A corner
    the vehicle is over").
    """
    if a > b or min(hw - abs(x2), depth - y_near) > tp[_BORDER]:
        return False
    if min(hw - abs(x1), depth - y1) <= tp[_CROSS_BORDER]:
        return False
    t = along(T[TH], x2, y_near)
    return t > 0.5 * (a + b) and abs(t - b) < tp[_EXIT_REACH]


@njit(cache=True)
def _start_line(T, x1, y1, x2, y_near, point_sd, hw, depth, border, mode):
    """The line through a detection, its direction chosen by ``mode`` (:func:`_reversed`)."""
    th, d, r_tt, r_td, r_dd = measured_line(x2, y_near, x1, y1, point_sd)
    if _reversed(T, x1, y1, x2, y_near, th, d, mode, point_sd):
        x1, y1, x2, y_near = x2, y_near, x1, y1
        th, d, r_td = wrap(th + math.pi), -d, -r_td
    _start(T, TH, th, d, r_tt, r_td, r_dd)
    T[ACTIVE], T[MISS], T[C_ACTIVE], T[C_HITS], T[HAD_LINE] = 1.0, 0.0, 0.0, 0.0, 1.0
    T[HAS_FAR], T[HAS_END] = 0.0, 0.0
    _take_end(T, x1, y1, hw, depth, border)
    T[NEAR_X], T[NEAR_Y], T[HAS_NEAR] = x2, y_near, 1.0


@njit(cache=True)
def track_step(T, found, det, motion, nav_var, tp, hw, depth, out, frame=CLEAR_FRAME):
    """One frame: predict the line by ``motion``, take the detection, write the observation.

    Args:
        T: the track's state (:data:`STATE_SIZE` slots), updated in place.
        found: whether the detector found the pipe in this frame.
        det: the detection ``(x1, y1, x2, y_near)`` (camera metres; far end first).
        motion: the navigation's ``(Δl, Δf, Δψ)`` since the last frame (m, m, rad; in the last
            frame's axes, Δψ positive to starboard).
        nav_var: the variances of ``motion``'s three parts.
        tp: :func:`pack_params` of a :class:`TrackParams`.
        hw: the footprint's lateral half-width (m).
        depth: the footprint's forward extent (m).
        out: the observation (:data:`OUT_SIZE` slots): in view, x1, y1, x2, y_near, side.
        frame: :data:`CLEAR_FRAME`, :data:`MURKY_FRAME` (searched, but a short piece is carried
            no longer than any) or :data:`UNSEARCHED_FRAME` (the measurement another sensor's: the
            line is carried ``unsearched_misses`` frames, short pieces too).
    """
    point_sd, bend_sd, shift_sd = tp[_POINT_SD], tp[_BEND_SD], tp[_SHIFT_SD]
    gate, point_gate = tp[_GATE], tp[_POINT_GATE]
    max_misses, max_offset_sd, confirm = tp[_MAX_MISSES], tp[_MAX_OFFSET_SD], tp[_CONFIRM]
    border, far_match = tp[_BORDER], tp[_FAR_MATCH]
    near_reach, edge_misses = tp[_NEAR_REACH], tp[_EDGE_MISSES]
    if frame == UNSEARCHED_FRAME:
        max_misses = edge_misses = tp[_UNSEARCHED_MISSES]
    elif frame == MURKY_FRAME:
        edge_misses = max_misses
    dl, df, dpsi = motion[0], motion[1], motion[2]
    travelled = math.sqrt(dl * dl + df * df)
    q_theta, q_d = bend_sd * bend_sd * travelled, shift_sd * shift_sd * travelled
    if T[HAD_LINE] != 0.0:  # a lost line too: where the pipe was orders the ends of the next
        predict(T, TH, dl, df, dpsi, nav_var, q_theta, q_d)
    if T[C_ACTIVE] != 0.0:
        predict(T, C_TH, dl, df, dpsi, nav_var, q_theta, q_d)
    c, s = math.cos(dpsi), math.sin(dpsi)
    if T[HAS_FAR] != 0.0:  # the ends seen are points fixed in the world
        T[FAR_X], T[FAR_Y] = moved(T[FAR_X], T[FAR_Y], dl, df, c, s)
        T[FAR_AGE] += 1.0
    if T[HAS_END] != 0.0:
        T[END_X], T[END_Y] = moved(T[END_X], T[END_Y], dl, df, c, s)
    T[MISS] += 1.0
    T[EVENT] = NO_DETECTION
    T[HAS_NEAR] = 0.0
    if found:
        x1, y1, x2, y_near = det[0], det[1], det[2], det[3]
        taken = False
        if T[ACTIVE] != 0.0:
            nu_a, j_a, s_a, m_a = point_innovation(T, TH, x2, y_near, point_sd)
            nu_b, j_b, s_b, m_b = point_innovation(T, TH, x1, y1, point_sd)
            ok_a, ok_b = m_a <= point_gate, m_b <= point_gate
            if ok_a and not ok_b or ok_b and not ok_a:
                # one end on the line, the other off it: the pipe bends in view, if the end on the
                # line is the near one: nearer than the other to where the line enters the view
                # (else it is a line beside the pipe that crosses it far ahead, which is no bend)
                if ok_b:
                    x1, y1, x2, y_near = x2, y_near, x1, y1
                    nu_a, j_a, s_a = nu_b, j_b, s_b
                t_in, t_out = in_footprint(T[TH], T[D], -REACH, REACH, hw, depth)
                ex, ey = on_line(T[TH], T[D], t_in)
                if math.hypot(x2 - ex, y_near - ey) < math.hypot(x1 - ex, y1 - ey):
                    taken = True
                    if _crossed(
                        T, x1, y1, x2, y_near, tp[_CROSS_BORDER], tp[_BEND_BEHIND], frame
                    ) or _leaves_on_line(T, x1, y1, x2, y_near, t_in, t_out, hw, depth, tp):
                        # the pipe comes from the end off the line: the end on it is the far one
                        x1, y1, x2, y_near = x2, y_near, x1, y1
                        if min(hw - abs(x1), depth - y1) <= border:
                            # ... and the pipe leaves the view there, by a side or the far border: the
                            # piece seen is the pipe in view, and the line starts again from it (only
                            # corrected through the end on it, the line kept a corner's chord while
                            # the vehicle turned onto the next leg)
                            _start_line(T, x1, y1, x2, y_near, point_sd, hw, depth, border, AS_GIVEN)
                        else:
                            point_correct(T, TH, nu_a, j_a, s_a)
                            _take_end(T, x1, y1, hw, depth, border)
                        T[EVENT] = ACCEPTED
                    else:
                        point_correct(T, TH, nu_a, j_a, s_a)
                        T[EVENT] = BEND
                        T[HAS_FAR], T[FAR_X], T[FAR_Y], T[FAR_AGE] = 1.0, x1, y1, 0.0
                        # the line ends at the corner, about where the far end lies along it (its
                        # extension beyond is no pipe: shown once the far end is out of view, it led
                        # the vehicle back along the first leg)
                        t_c = max(along(T[TH], x1, y1), along(T[TH], x2, y_near))
                        T[HAS_END] = 1.0
                        T[END_X], T[END_Y] = on_line(T[TH], T[D], t_c)
            elif ok_a and ok_b:
                # both ends on the line: ordered along it (the detector's order is a guess)
                if along(T[TH], x2, y_near) > along(T[TH], x1, y1):
                    x1, y1, x2, y_near = x2, y_near, x1, y1
                th_m, d_m, r_tt, r_td, r_dd = measured_line(x2, y_near, x1, y1, point_sd)
                nu_t, nu_d, s_tt, s_td, s_dd, m2 = innovation(T, TH, th_m, d_m, r_tt, r_td, r_dd)
                if m2 <= gate:
                    correct(T, TH, nu_t, nu_d, s_tt, s_td, s_dd, r_tt, r_td, r_dd)
                else:
                    nu_a, j_a, s_a, m_a = point_innovation(T, TH, x2, y_near, point_sd)
                    point_correct(T, TH, nu_a, j_a, s_a)
                T[EVENT] = ACCEPTED
                _take_end(T, x1, y1, hw, depth, border)
                taken = True
            if taken:
                T[MISS] = 0.0
                T[C_ACTIVE], T[C_HITS] = 0.0, 0.0
                T[NEAR_X], T[NEAR_Y], T[HAS_NEAR] = x2, y_near, 1.0
        if not taken:
            a, b = _line_end(T, hw, depth)
            line_in_view = T[ACTIVE] != 0.0 and a <= b
            beyond = (
                T[HAS_FAR] != 0.0
                and min(
                    math.hypot(x1 - T[FAR_X], y1 - T[FAR_Y]), math.hypot(x2 - T[FAR_X], y_near - T[FAR_Y])
                )
                < far_match
            )
            near_end = False
            if line_in_view:
                ex, ey = on_line(T[TH], T[D], a)  # where the tracked pipe enters the view
                da, db = math.hypot(x2 - ex, y_near - ey), math.hypot(x1 - ex, y1 - ey)
                near_end = min(da, db) < near_reach
                if near_end and db < da:
                    x1, y1, x2, y_near = x2, y_near, x1, y1
            if near_end:
                # it starts where the tracked pipe enters the view: the same pipe, curving away
                # from the line (an arc the line cannot follow); the line starts again from it
                _start_line(T, x1, y1, x2, y_near, point_sd, hw, depth, border, AS_GIVEN)
                T[EVENT] = REPLACED
            elif beyond:
                # the leg after the bend, where the far end beyond it was seen: the pipe goes on there
                _start_line(T, x1, y1, x2, y_near, point_sd, hw, depth, border, TOWARDS_FAR)
                T[EVENT] = REPLACED
            elif not line_in_view:
                # nothing tracked in view: the detection is the pipe
                _start_line(T, x1, y1, x2, y_near, point_sd, hw, depth, border, AFTER_LINE)
                T[EVENT] = STARTED
            else:
                th_m, d_m, r_tt, r_td, r_dd = measured_line(x2, y_near, x1, y1, point_sd)
                hit = False
                if T[C_ACTIVE] != 0.0:
                    th_o, d_o, r_o = oriented(th_m, d_m, r_td, T[C_TH])
                    nu_t, nu_d, s_tt, s_td, s_dd, m2 = innovation(T, C_TH, th_o, d_o, r_tt, r_o, r_dd)
                    if m2 <= gate:
                        correct(T, C_TH, nu_t, nu_d, s_tt, s_td, s_dd, r_tt, r_o, r_dd)
                        T[C_HITS] += 1.0
                        hit = True
                if not hit:
                    _start(T, C_TH, th_m, d_m, r_tt, r_td, r_dd)
                    T[C_ACTIVE], T[C_HITS] = 1.0, 1.0
                T[EVENT] = REJECTED
                if T[C_HITS] >= confirm:
                    # seen again where the tracked line is not: that line was wrong, or left behind
                    _start_line(T, x1, y1, x2, y_near, point_sd, hw, depth, border, CONTRADICTED)
                    T[EVENT] = REPLACED
    if T[ACTIVE] != 0.0:
        limit = max_misses
        if T[MISS] > max_misses and edge_misses > max_misses:
            a, b = _line_end(T, hw, depth)
            # a short piece at the view's edge: the detector misses those
            if a <= b and b - a < tp[_EDGE_PIECE]:
                limit = edge_misses
        if T[MISS] > limit or T[P + 2] > max_offset_sd * max_offset_sd:
            T[ACTIVE] = 0.0
    if T[HAS_FAR] != 0.0 and (T[FAR_AGE] > max_misses or T[ACTIVE] == 0.0):
        T[HAS_FAR] = 0.0
    if T[ACTIVE] == 0.0:
        T[HAS_END] = 0.0
    observe_track(T, tp, hw, depth, out)


@njit(cache=True)
def observe_track(T, tp, hw, depth, out):
    """The track's observation (see :func:`track_step`'s ``out``); sets the track's side and confidence.

    The near end is this frame's accepted detection's, or where the line enters the view; the far
    end the far end seen beyond a bend while it is in view, else where the line leaves the view or
    was seen to end.
    """
    out[OUT_IN_VIEW] = 0.0
    if T[ACTIVE] == 0.0:
        T[CONFIDENCE] = 0.0
        out[OUT_SIDE] = T[SIDE]
        return
    th, d = T[TH], T[D]
    a, b = _line_end(T, hw, depth)
    seen_line = a <= b
    far_beyond = T[HAS_FAR] != 0.0 and inside(T[FAR_X], T[FAR_Y], hw, depth, tp[_FAR_MARGIN])
    if far_beyond:
        out[OUT_X1], out[OUT_Y1] = T[FAR_X], T[FAR_Y]
    elif seen_line:
        out[OUT_X1], out[OUT_Y1] = on_line(th, d, b)
    if T[HAS_NEAR] != 0.0:
        out[OUT_X2], out[OUT_Y_NEAR] = T[NEAR_X], T[NEAR_Y]
    elif seen_line:
        out[OUT_X2], out[OUT_Y_NEAR] = on_line(th, d, a)
    elif far_beyond:
        out[OUT_X2], out[OUT_Y_NEAR] = T[FAR_X], T[FAR_Y]
    # how well the offset is known: 1 at a fresh detection's, falling as the prediction's grows
    floor = 0.5 * tp[_POINT_SD] * tp[_POINT_SD]
    T[CONFIDENCE] = min(1.0, math.sqrt(floor / max(T[P + 2], floor)))
    if seen_line or far_beyond:
        out[OUT_IN_VIEW] = 1.0
        out[OUT_X1] = min(max(out[OUT_X1], -hw), hw)
        out[OUT_X2] = min(max(out[OUT_X2], -hw), hw)
        out[OUT_Y1] = min(max(out[OUT_Y1], 0.0), depth)
        out[OUT_Y_NEAR] = min(max(out[OUT_Y_NEAR], 0.0), depth)
        T[SIDE] = 1.0 if out[OUT_X1] >= 0.0 else -1.0
    elif T[HAS_FAR] != 0.0:
        T[SIDE] = 1.0 if T[FAR_X] >= 0.0 else -1.0  # out of view after a bend: towards where it went
    out[OUT_SIDE] = T[SIDE]


def new_track() -> np.ndarray:
    """An empty track's state."""
    T = np.zeros(STATE_SIZE)
    T[SIDE] = 1.0
    return T
