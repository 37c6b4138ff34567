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
end beyond the bend. Otherwise the detection is rejected: it starts (or feeds) a candidate line
that replaces the line when seen :attr:`TrackParams.confirm` times, and at once if it starts
where the line enters the view (an arc the line cannot follow), ends where the far end beyond a
bend was seen (the next leg), or if the line is out of view. A new line keeps the pipe's way
(:func:`_reversed`): the last line's when the two are near parallel, else away from the corner
where they meet, towards the far end beyond the bend for the next leg; never the detector's order
of the ends, which swaps. Through missed detections the
prediction goes on and its uncertainty grows; beyond :attr:`TrackParams.max_misses` frames, or an
offset uncertain by more than :attr:`TrackParams.max_offset_sd`, the pipe is lost.

**Observation.** In the exact camera's format (:mod:`pipefollow.sim.camera`): the near end is
the accepted detection's (else where the line enters the view), the far end the far end beyond a
bend while that is in view (also in frames where the detector stops at the corner), else where
the line leaves the view or was seen to end; the in-view flag; the side to search on when it is
out of view (towards the far end beyond a bend).

All of it is compiled (:func:`track_step`, one call per frame; no ``fastmath``);
:class:`PipeTracker` holds the arrays and the navigation.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.sim.camera import clip_segment
from pipefollow.sim.controller import wrap_angle as wrap

CHI2_2DOF_99 = 9.2103  # Mahalanobis gate of a line: 99 % of a correct detection's innovations fall inside
CHI2_1DOF_99 = 6.6349  # ... of a second sensor's point on the line: 99 % (a chi-squared table)
CHI2_1DOF_90 = 2.7055  # ... of a detected end on the line: 90 % (a wider gate kept wrong lines; decisions.md)


class NavParams(NamedTuple):
    """The navigation's sensors (docs/decisions.md "pipe tracker" cites the datasheet figures).

    A DVL measures the velocity over the seabed in the body frame; a gyro (or AHRS) the heading's
    change. Between two frames their integration gives the vehicle's motion with these errors.
    """

    dvl_sd: float = 0.01  # one ping's velocity noise per axis (m/s)
    dvl_rate: float = 5.0  # pings per second
    dvl_scale_sd: float = 0.002  # scale-factor error (share of the velocity), drawn once per episode
    gyro_arw: float = 0.05  # angle random walk (deg/√s; 3 °/√h)
    gyro_bias_sd: float = 10.0 / 3600.0  # the gyro's bias at the start (deg/s; 10 °/h), per episode
    gyro_bias_walk: float = 1.0 / 3600.0  # the bias's random walk (deg/s per √s)


NAV = NavParams()


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


TRACK = TrackParams()

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
    """The settings as the compiled code takes them."""
    return np.array([float(v) for v in p], dtype=np.float64)


@njit(cache=True)
def predict(T, o, dl, df, dpsi, nav_var, q_theta, q_d):
    """Move leg ``o`` (slot offset: :data:`TH1` or :data:`TH2`) by the vehicle's motion; grow its covariance.

    ``nav_var`` holds the variances of ``(Δl, Δf, Δψ)``; ``q_theta``, ``q_d`` the pipe's own
    process variances for this step.
    """
    th, d = T[o], T[o + 1]
    c, s = math.cos(th), math.sin(th)
    T[o] = wrap(th - dpsi)
    T[o + 1] = d - dl * c + df * s
    # F = [[1, 0], [f, 1]], f = ∂d'/∂θ
    f = dl * s + df * c
    ptt, ptd, pdd = T[o + 2], T[o + 3], T[o + 4]
    ntt = ptt
    ntd = f * ptt + ptd
    ndd = f * f * ptt + 2.0 * f * ptd + pdd
    # G = ∂(θ', d')/∂(Δl, Δf, Δψ) = [[0, 0, −1], [−c, s, 0]]
    ntt += nav_var[2] + q_theta
    ndd += c * c * nav_var[0] + s * s * nav_var[1] + q_d
    T[o + 2], T[o + 3], T[o + 4] = ntt, ntd, ndd


@njit(cache=True)
def measured_line(ax, ay, bx, by, point_sd):
    """The line through a detection's ends a → b: ``(θ, d, Rθθ, Rθd, Rdd)``.

    Each end is off by ``point_sd`` per axis, independently: across the line the piece's midpoint
    is off by σ/√2 and its direction by σ·√2/L; ``d`` is the offset at the vehicle's foot on the
    line, ``t_m`` along from the midpoint, so ``δd = δo − t_m·δθ``.
    """
    ux, uy = bx - ax, by - ay
    length = math.sqrt(ux * ux + uy * uy)
    th = math.atan2(ux, uy)
    c, s = math.cos(th), math.sin(th)
    mx, my = 0.5 * (ax + bx), 0.5 * (ay + by)
    d = mx * c - my * s
    t_m = mx * s + my * c  # the midpoint's position along u
    var_o = 0.5 * point_sd * point_sd
    var_th = 2.0 * point_sd * point_sd / max(length * length, 1e-6)
    return th, d, var_th, -t_m * var_th, var_o + t_m * t_m * var_th


@njit(cache=True)
def oriented(th_m, d_m, r_td, th_ref):
    """A measured line taken the way nearer direction ``th_ref``: ``(θ, d, Rθd)``.

    The same line read the other way round is ``(θ + π, −d)``; its covariance keeps ``Rθθ`` and
    ``Rdd`` and changes the sign of ``Rθd``.
    """
    if abs(wrap(th_m - th_ref)) > 0.5 * math.pi:
        return wrap(th_m + math.pi), -d_m, -r_td
    return th_m, d_m, r_td


@njit(cache=True)
def innovation(T, o, th_m, d_m, r_tt, r_td, r_dd):
    """The measured line (already :func:`oriented`) against leg ``o``: ``(νθ, νd, Sθθ, Sθd, Sdd, m²)``.

    ``m²`` is the squared Mahalanobis distance ``νᵀ S⁻¹ ν`` with ``S = P + R``.
    """
    nu_t = wrap(th_m - T[o])
    nu_d = d_m - T[o + 1]
    s_tt = T[o + 2] + r_tt
    s_td = T[o + 3] + r_td
    s_dd = T[o + 4] + r_dd
    det = s_tt * s_dd - s_td * s_td
    m2 = (s_dd * nu_t * nu_t - 2.0 * s_td * nu_t * nu_d + s_tt * nu_d * nu_d) / det
    return nu_t, nu_d, s_tt, s_td, s_dd, m2


@njit(cache=True)
def correct(T, o, nu_t, nu_d, s_tt, s_td, s_dd, r_tt, r_td, r_dd):
    """Kalman update of leg ``o`` with the innovation ``ν`` and its covariance ``S`` (Joseph form)."""
    ptt, ptd, pdd = T[o + 2], T[o + 3], T[o + 4]
    det = s_tt * s_dd - s_td * s_td
    i_tt, i_td, i_dd = s_dd / det, -s_td / det, s_tt / det
    # K = P S⁻¹ (H = I)
    k00 = ptt * i_tt + ptd * i_td
    k01 = ptt * i_td + ptd * i_dd
    k10 = ptd * i_tt + pdd * i_td
    k11 = ptd * i_td + pdd * i_dd
    T[o] = wrap(T[o] + k00 * nu_t + k01 * nu_d)
    T[o + 1] = T[o + 1] + k10 * nu_t + k11 * nu_d
    # Joseph form: (I − K) P (I − K)ᵀ + K R Kᵀ
    a00, a01, a10, a11 = 1.0 - k00, -k01, -k10, 1.0 - k11
    b00 = a00 * ptt + a01 * ptd
    b01 = a00 * ptd + a01 * pdd
    b10 = a10 * ptt + a11 * ptd
    b11 = a10 * ptd + a11 * pdd
    n_tt = b00 * a00 + b01 * a01
    n_td = b00 * a10 + b01 * a11
    n_dd = b10 * a10 + b11 * a11
    c00 = k00 * r_tt + k01 * r_td
    c01 = k00 * r_td + k01 * r_dd
    c10 = k10 * r_tt + k11 * r_td
    c11 = k10 * r_td + k11 * r_dd
    n_tt += c00 * k00 + c01 * k01
    n_td += c00 * k10 + c01 * k11
    n_dd += c10 * k10 + c11 * k11
    T[o + 2], T[o + 3], T[o + 4] = n_tt, n_td, n_dd


@njit(cache=True)
def point_innovation(T, o, px, py, point_sd):
    """A detected end ``p`` against line ``o``: ``(ν, jθ, S, m²)``.

    The end lies on the line if ``r = n(θ)·p − d`` is 0; linearized, ``r ≈ r₀ + jθ·δθ − δd +
    n·δp`` with ``jθ = −u·p``, so ``S = J P Jᵀ + σ²`` (J = (jθ, −1)) and ``ν = −r₀``.
    """
    th, d = T[o], T[o + 1]
    c, s = math.cos(th), math.sin(th)
    nu = d - (px * c - py * s)
    j = -(px * s + py * c)
    ptt, ptd, pdd = T[o + 2], T[o + 3], T[o + 4]
    S = j * j * ptt - 2.0 * j * ptd + pdd + point_sd * point_sd
    return nu, j, S, nu * nu / S


@njit(cache=True)
def point_correct(T, o, nu, j, S):
    """Kalman update of line ``o`` with a detected end's innovation (:func:`point_innovation`).

    The state moves by ``−K·r₀ = K·ν`` with ``K = P Jᵀ / S``, and the covariance becomes
    ``P − K S Kᵀ`` (symmetric by construction).
    """
    ptt, ptd, pdd = T[o + 2], T[o + 3], T[o + 4]
    # P Jᵀ with J = (j, −1)
    g0 = ptt * j - ptd
    g1 = ptd * j - pdd
    k0, k1 = g0 / S, g1 / S
    T[o] = wrap(T[o] + k0 * nu)  # x⁺ = x − K·r₀ = x + K·ν
    T[o + 1] = T[o + 1] + k1 * nu
    T[o + 2] = ptt - k0 * g0
    T[o + 3] = ptd - k0 * g1
    T[o + 4] = pdd - k1 * g1


@njit(cache=True)
def _start(T, o, th, d, r_tt, r_td, r_dd):
    T[o], T[o + 1] = th, d
    T[o + 2], T[o + 3], T[o + 4] = r_tt, r_td, r_dd


PARALLEL = math.sin(math.radians(25.0))  # lines closer in direction than this have no corner worth the name


@njit(cache=True)
def crossing(th1, d1, th2, d2):
    """Where line 1 meets line 2, as line 1's parameter ``t`` (nan if they are parallel)."""
    sn = math.sin(th1 - th2)  # u1·n2
    if abs(sn) < 1e-9:
        return math.nan
    return (d2 - d1 * math.cos(th1 - th2)) / sn


@njit(cache=True)
def on_line(th, d, t):
    """The point ``d·n + t·u`` of line (θ, d)."""
    c, s = math.cos(th), math.sin(th)
    return d * c + t * s, -d * s + t * c


@njit(cache=True)
def along(th, x, y):
    """A point's position along a line of direction θ (from the vehicle's foot on it)."""
    return x * math.sin(th) + y * math.cos(th)


@njit(cache=True)
def in_footprint(th, d, t_from, t_to, hw, depth):
    """The part ``[t0, t1]`` of line (θ, d) from ``t_from`` to ``t_to`` in the footprint (t0 > t1: none)."""
    ax, ay = on_line(th, d, t_from)
    bx, by = on_line(th, d, t_to)
    a, b = clip_segment(ax, ay, bx, by, -hw, hw, 0.0, depth)
    if a > b:
        return 1.0, 0.0
    return t_from + a * (t_to - t_from), t_from + b * (t_to - t_from)


@njit(cache=True)
def inside(x, y, hw, depth, margin):
    """Whether a point lies in the footprint grown by ``margin``."""
    return abs(x) <= hw + margin and -margin <= y <= depth + margin


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
    between them. Near parallel (within :data:`PARALLEL`): the last line's way. Otherwise the last
    line meets the new one at a corner, from which the pipe runs on: towards the far end seen beyond
    the bend (``TOWARDS_FAR``), else away from the crossing. A crossing *on* the piece seen is no
    corner (the pipe runs on both sides of it): the last line was wrong. Contradicted in view
    (``CONTRADICTED``) it was seen a frame or two before, and the new line takes its nearer way;
    lost or out of view (``AFTER_LINE``) it was carried blind, and the pipe comes from the piece's
    end nearer the vehicle.
    """
    if mode == AS_GIVEN or T[HAD_LINE] == 0.0:
        return False
    nearer_way = abs(wrap(th - T[TH])) > 0.5 * math.pi
    if abs(math.sin(T[TH] - th)) < PARALLEL:
        return nearer_way
    if mode == TOWARDS_FAR and T[HAS_FAR] != 0.0:
        # the pipe goes on towards the far end seen beyond the bend: the end nearer it is the far one
        return math.hypot(x2 - T[FAR_X], y_near - T[FAR_Y]) < math.hypot(x1 - T[FAR_X], y1 - T[FAR_Y])
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
def track_step(T, found, det, motion, nav_var, tp, hw, depth, out):
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
    """
    point_sd, bend_sd, shift_sd, gate, point_gate = tp[0], tp[1], tp[2], tp[3], tp[4]
    max_misses, max_offset_sd, confirm, border, far_match = tp[5], tp[6], tp[7], tp[8], tp[10]
    near_reach = tp[11]
    dl, df, dpsi = motion[0], motion[1], motion[2]
    travelled = math.sqrt(dl * dl + df * df)
    q_theta, q_d = bend_sd * bend_sd * travelled, shift_sd * shift_sd * travelled
    if T[HAD_LINE] != 0.0:  # a lost line too: where the pipe was orders the ends of the next
        predict(T, TH, dl, df, dpsi, nav_var, q_theta, q_d)
    if T[C_ACTIVE] != 0.0:
        predict(T, C_TH, dl, df, dpsi, nav_var, q_theta, q_d)
    c, s = math.cos(dpsi), math.sin(dpsi)
    if T[HAS_FAR] != 0.0:  # the ends seen are points fixed in the world
        ex, ey = T[FAR_X] - dl, T[FAR_Y] - df
        T[FAR_X], T[FAR_Y] = c * ex - s * ey, s * ex + c * ey
        T[FAR_AGE] += 1.0
    if T[HAS_END] != 0.0:
        ex, ey = T[END_X] - dl, T[END_Y] - df
        T[END_X], T[END_Y] = c * ex - s * ey, s * ex + c * ey
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
                t_in, _ = in_footprint(T[TH], T[D], -REACH, REACH, hw, depth)
                ex, ey = on_line(T[TH], T[D], t_in)
                if math.hypot(x2 - ex, y_near - ey) < math.hypot(x1 - ex, y1 - ey):
                    point_correct(T, TH, nu_a, j_a, s_a)
                    T[EVENT] = BEND
                    T[HAS_FAR], T[FAR_X], T[FAR_Y], T[FAR_AGE] = 1.0, x1, y1, 0.0
                    taken = True
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
    if T[ACTIVE] != 0.0 and (T[MISS] > max_misses or T[P + 2] > max_offset_sd * max_offset_sd):
        T[ACTIVE] = 0.0
    if T[HAS_FAR] != 0.0 and (T[FAR_AGE] > max_misses or T[ACTIVE] == 0.0):
        T[HAS_FAR] = 0.0
    if T[ACTIVE] == 0.0:
        T[HAS_END] = 0.0
    observe_track(T, tp, hw, depth, out)


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
    far_beyond = T[HAS_FAR] != 0.0 and inside(T[FAR_X], T[FAR_Y], hw, depth, tp[9])
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
    floor = 0.5 * tp[0] * tp[0]
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


NORMALS_BLOCK = 256  # steps of navigation noise drawn at a time


class Navigation:
    """Dead reckoning between frames: a DVL's velocity and a gyro's heading, with their errors.

    :meth:`motion` turns the vehicle's true poses at two frames into what its navigation reports:
    the displacement in the earlier frame's axes (the DVL's velocity integrated, off by the
    episode's scale error and the pings' noise) and the heading's change (the gyro's, off by its
    drifting bias and its angle random walk). The errors draw from the generator given to
    :meth:`reset`. :attr:`variances` are the motion's error variances as the filter assumes them
    for a step of ``dt`` seconds (the bias's share: its 1σ over the step).
    """

    def __init__(self, params: NavParams = NAV, dt: float = 1.0) -> None:
        self.params, self.dt = params, dt
        p = params
        disp_sd = p.dvl_sd * math.sqrt(dt / p.dvl_rate)  # the mean of dt·rate pings, times dt
        turn_var = math.radians(p.gyro_arw) ** 2 * dt + (math.radians(p.gyro_bias_sd) * dt) ** 2
        self.disp_sd = disp_sd
        self.variances = np.array([disp_sd**2, disp_sd**2, turn_var])
        self.rng = np.random.default_rng(0)
        self.scale, self.bias = 1.0, 0.0
        self._z = np.empty((0, 4))  # the steps' normals, drawn from the generator a block at a time
        self._k = 0
        self._out = np.zeros(3)

    def reset(self, rng: np.random.Generator) -> None:
        """A new episode: the scale error and the gyro's bias drawn from ``rng``, which later steps use."""
        p = self.params
        self.rng = rng
        self.scale = 1.0 + p.dvl_scale_sd * float(rng.standard_normal())
        self.bias = math.radians(p.gyro_bias_sd) * float(rng.standard_normal())
        self._z, self._k = np.empty((0, 4)), 0

    def motion(self, before: tuple[float, float, float], after: tuple[float, float, float]) -> np.ndarray:
        """The navigation's ``(Δl, Δf, Δψ)`` between two true poses (x north, y east, ψ).

        Returns an array the next call overwrites. The step's four normals come from blocks of
        :data:`NORMALS_BLOCK` rows drawn from the generator (a draw per step cost more than the filter).
        """
        p, dt = self.params, self.dt
        x0, y0, psi0 = before
        dx, dy = after[0] - x0, after[1] - y0
        cs, sn = math.cos(psi0), math.sin(psi0)
        if self._k >= len(self._z):
            self._z, self._k = self.rng.standard_normal((NORMALS_BLOCK, 4)), 0
        z = self._z[self._k]
        self._k += 1
        d_f = self.scale * (cs * dx + sn * dy) + self.disp_sd * z[0]
        d_l = self.scale * (-sn * dx + cs * dy) + self.disp_sd * z[1]
        d_psi = math.remainder(after[2] - psi0, 2.0 * math.pi)
        d_psi += self.bias * dt + math.radians(p.gyro_arw) * math.sqrt(dt) * z[2]
        self.bias += math.radians(p.gyro_bias_walk) * math.sqrt(dt) * z[3]
        out = self._out
        out[0], out[1], out[2] = d_l, d_f, d_psi
        return out


class PipeTracker:
    """One camera's track of the pipe (see the module docstring), fed one detection per frame."""

    def __init__(
        self,
        half_width: float = 1.0,
        depth: float = 3.0,
        params: TrackParams = TRACK,
        nav: NavParams = NAV,
        dt: float = 1.0,
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

    def reset(self, rng: np.random.Generator, pose: tuple[float, float, float]) -> None:
        """A new episode at the true ``pose``: an empty track; the navigation's errors from ``rng``."""
        self.navigation.reset(rng)
        self.start()
        self._pose = pose

    def start(self) -> None:
        """An empty track; the next frame is the first (no motion before it), the navigation as it is."""
        self.state[:] = new_track()
        self._pose = None

    def step(
        self, pose: tuple[float, float, float], found: bool, det: tuple[float, float, float, float]
    ) -> np.ndarray:
        """A frame from the true ``pose`` with the detection ``det`` = (x1, y1, x2, y_near): the observation.

        Returns the output array (in view, x1, y1, x2, y_near, side), reused frame after frame.
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
            self.half_width, self.depth, self.out,
        )  # fmt: skip
        return self.out

    def point(self, x: float, y: float, point_sd: float, gate: float = CHI2_1DOF_99) -> np.ndarray:
        """After :meth:`step`: a second sensor's point on the pipe (:func:`track_point`).

        Returns the observation: the output array of :meth:`step`, rewritten if the point was taken.
        """
        if track_point(self.state, float(x), float(y), float(point_sd), float(gate)):
            observe_track(self.state, self._tp, self.half_width, self.depth, self.out)
        return self.out

    def carry(self, max_misses: int) -> None:
        """From the next frame on, carry the line this many frames without a sighting (not ``params``')."""
        self._tp[TrackParams._fields.index("max_misses")] = float(max_misses)

    def search_towards(self, x: float) -> np.ndarray:
        """While no pipe is in view: search on the side of ``x`` (a second sensor's sighting off the view).

        Returns the observation: the output array of :meth:`step` with its side set.
        """
        if self.out[OUT_IN_VIEW] == 0.0:
            side = 1.0 if x >= 0.0 else -1.0
            self.state[SIDE] = side
            self.out[OUT_SIDE] = side
        return self.out

    @property
    def confidence(self) -> float:
        """How well the tracked offset is known, in [0, 1] (0 without a track)."""
        return float(self.state[CONFIDENCE])

    @property
    def event(self) -> float:
        """What the last detection did: :data:`ACCEPTED`, :data:`SECOND_LEG`, :data:`REJECTED`, ..."""
        return float(self.state[EVENT])
