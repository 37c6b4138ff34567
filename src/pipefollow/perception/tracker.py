"""A pipe tracker: the pipe as a line fixed in the world, carried by the vehicle's navigation.

The detector (:mod:`pipefollow.perception.detector`) judges every frame on its own: it swaps the
ends when the pipe crosses the view, loses the pipe in a frame without edges, and at a hook of more
than 120° reports only the leg before the corner. The tracker keeps what earlier frames showed.

**State.** The pipe's current leg is a straight line fixed in the world, held in the vehicle's
camera frame (x lateral to starboard, y forward, origin at the vehicle's centre) as its direction
``θ`` (rad from the forward axis towards starboard; the line runs along ``u = (sin θ, cos θ)``, the
pipe's own direction) and its signed offset ``d`` (m) along ``n = (cos θ, −sin θ)``: the line is
``p(t) = d·n + t·u``. The same line in earth coordinates would be badly conditioned far from the
origin; held in the vehicle's frame it is re-expressed at every frame by the vehicle's motion,
which is the world-fixed line seen from the new pose. A second leg (the pipe after a corner) is
held the same way; the two meet at the corner.

**Prediction** (an extended Kalman filter): the vehicle moves ``(Δl, Δf)`` (lateral, forward,
in the earlier frame) and turns ``Δψ`` (to starboard) as its *navigation* reports them
(:class:`Navigation`: a DVL's velocity and a gyro's heading change, with their noise, scale error
and bias drift from a seeded generator, not the simulator's truth)::

    θ' = θ − Δψ        d' = d − Δl·cos θ + Δf·sin θ

The process noise is the navigation's (through the Jacobian in ``(Δl, Δf, Δψ)``) plus the pipe's
own bending: a random walk of ``θ`` and ``d`` per metre travelled (:class:`TrackParams`).

**Correction.** A detection's near and far ends give a measured line (``θ_m`` from their
direction, ``d_m``) whose covariance follows from the ends' pixel noise and the piece's length.
Its direction is taken the way nearer the prediction (the ends' order is the detector's guess),
and it is accepted only inside a Mahalanobis gate (χ² with 2 degrees of freedom); a rejected
detection starts (or feeds) the second leg instead: a turn of the pipe if it meets the first
near where that was last seen to end, a new line otherwise. A second leg seen in
:attr:`TrackParams.confirm` frames takes over when the first is no longer seen. Through missed
detections the prediction goes on and its uncertainty grows; beyond :attr:`TrackParams.max_misses`
frames, or an offset uncertain by more than :attr:`TrackParams.max_offset_sd`, the pipe is lost.

**Observation.** The tracked piece inside the footprint, in the exact camera's format
(:mod:`pipefollow.sim.camera`): the near end where the first leg enters the view, the far end
where the pipe (after the corner, if one is tracked) leaves it or ends, the in-view flag, and the
side to search on when it is out of view.

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

CHI2_2DOF_99 = 9.2103  # the Mahalanobis gate: 99 % of a correct detection's innovations fall inside


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
    gate: float = CHI2_2DOF_99  # Mahalanobis gate (squared)
    max_misses: int = 3  # frames a leg is carried without a detection
    max_offset_sd: float = 0.4  # m: a leg whose offset is this uncertain is lost
    confirm: int = 2  # frames a second leg must be seen in to take over (or show without a seen end)
    corner_reach: float = 0.6  # m: a rejected detection turns the pipe if its corner is this near the seen end
    parallel_deg: float = 25.0  # a rejected detection this close in direction is a shifted line, not a turn
    border: float = 0.06  # m: a detected far end this near the footprint's border is where the pipe leaves it


TRACK = TrackParams()

# slots of a track's state array
TH1, D1, P1, ACTIVE1, MISS1, HAS_END, END_X, END_Y = 0, 1, 2, 5, 6, 7, 8, 9  # P1: Pθθ, Pθd, Pdd
TH2, D2, P2, ACTIVE2, MISS2, HITS2 = 10, 11, 12, 15, 16, 17
SIDE, CONFIDENCE, LAST_TH, EVENT = 18, 19, 20, 21
STATE_SIZE = 22
# EVENT: what the last frame's detection did
NO_DETECTION, ACCEPTED, SECOND_LEG, REJECTED, STARTED = 0.0, 1.0, 2.0, 3.0, 4.0
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
def _start(T, o, th, d, r_tt, r_td, r_dd):
    T[o], T[o + 1] = th, d
    T[o + 2], T[o + 3], T[o + 4] = r_tt, r_td, r_dd


@njit(cache=True)
def crossing(th1, d1, th2, d2):
    """Where line 1 meets line 2, as line 1's parameter ``t`` (nan if they are parallel)."""
    sn = math.sin(th1 - th2)  # u1·n2
    if abs(sn) < 1e-9:
        return math.nan
    cs = math.cos(th1 - th2)  # n1·n2
    return (d2 - d1 * cs) / sn


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
    """The part ``[t0, t1]`` of line (θ, d) from ``t_from`` to ``t_to`` inside the footprint; t0 > t1 if none."""
    ax, ay = on_line(th, d, t_from)
    bx, by = on_line(th, d, t_to)
    a, b = clip_segment(ax, ay, bx, by, -hw, hw, 0.0, depth)
    if a > b:
        return 1.0, 0.0
    return t_from + a * (t_to - t_from), t_from + b * (t_to - t_from)


@njit(cache=True)
def _corner(T):
    """The corner of leg 1 and leg 2 as leg 1's parameter (nan without a second leg or if parallel)."""
    if T[ACTIVE2] == 0.0:
        return math.nan
    return crossing(T[TH1], T[D1], T[TH2], T[D2])


@njit(cache=True)
def _shows_turn(T, tp):
    """Whether the second leg is a turn of the first that the observation shows."""
    t_c = _corner(T)
    if math.isnan(t_c) or T[ACTIVE1] == 0.0:
        return False
    if abs(math.sin(T[TH1] - T[TH2])) < math.sin(math.radians(tp[8])):
        return False  # a shifted line: it replaces the first leg once confirmed, it does not continue it
    if T[HITS2] >= tp[6]:
        return True
    if T[HAS_END] != 0.0:  # seen once: a turn where the first leg was seen to end
        cx, cy = on_line(T[TH1], T[D1], t_c)
        return math.hypot(cx - T[END_X], cy - T[END_Y]) < tp[7]
    return False


@njit(cache=True)
def _promote(T):
    """The second leg becomes the first."""
    for k in range(5):
        T[TH1 + k] = T[TH2 + k]
    T[ACTIVE1], T[MISS1], T[HAS_END] = 1.0, 0.0, 0.0
    T[ACTIVE2], T[MISS2], T[HITS2] = 0.0, 0.0, 0.0


@njit(cache=True)
def track_step(T, found, det, motion, nav_var, tp, hw, depth, out):
    """One frame: predict both legs by ``motion``, take the detection, write the observation.

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
    point_sd, bend_sd, shift_sd, gate = tp[0], tp[1], tp[2], tp[3]
    max_misses, max_offset_sd, confirm = tp[4], tp[5], tp[6]
    corner_reach, parallel, border = tp[7], math.sin(math.radians(tp[8])), tp[9]
    dl, df, dpsi = motion[0], motion[1], motion[2]
    travelled = math.sqrt(dl * dl + df * df)
    q_theta, q_d = bend_sd * bend_sd * travelled, shift_sd * shift_sd * travelled
    for o, active in ((TH1, ACTIVE1), (TH2, ACTIVE2)):
        if T[active] != 0.0:
            predict(T, o, dl, df, dpsi, nav_var, q_theta, q_d)
    if T[HAS_END] != 0.0:  # the seen end is a point fixed in the world
        ex, ey = T[END_X] - dl, T[END_Y] - df
        c, s = math.cos(dpsi), math.sin(dpsi)
        T[END_X], T[END_Y] = c * ex - s * ey, s * ex + c * ey
    if T[LAST_TH] == T[LAST_TH]:
        T[LAST_TH] = wrap(T[LAST_TH] - dpsi)
    T[MISS1] += 1.0
    T[MISS2] += 1.0
    T[EVENT] = NO_DETECTION
    if found:
        x1, y1, x2, y_near = det[0], det[1], det[2], det[3]
        th_m, d_m, r_tt, r_td, r_dd = measured_line(x2, y_near, x1, y1, point_sd)
        taken = False
        if T[ACTIVE1] != 0.0:
            th_o, d_o, r_o = oriented(th_m, d_m, r_td, T[TH1])
            nu_t, nu_d, s_tt, s_td, s_dd, m2 = innovation(T, TH1, th_o, d_o, r_tt, r_o, r_dd)
            if m2 <= gate:
                flip = th_o != th_m
                correct(T, TH1, nu_t, nu_d, s_tt, s_td, s_dd, r_tt, r_o, r_dd)
                T[MISS1] = 0.0
                T[EVENT] = ACCEPTED
                taken = True
                # the far end in the pipe's direction: where the pipe is seen to end (or leave the view)
                fx, fy = (x2, y_near) if flip else (x1, y1)
                if min(hw - abs(fx), fy, depth - fy) > border:
                    T[HAS_END], T[END_X], T[END_Y] = 1.0, fx, fy
                else:
                    T[HAS_END] = 0.0
        if not taken and T[ACTIVE2] != 0.0:
            th_o, d_o, r_o = oriented(th_m, d_m, r_td, T[TH2])
            nu_t, nu_d, s_tt, s_td, s_dd, m2 = innovation(T, TH2, th_o, d_o, r_tt, r_o, r_dd)
            if m2 <= gate:
                correct(T, TH2, nu_t, nu_d, s_tt, s_td, s_dd, r_tt, r_o, r_dd)
                T[MISS2] = 0.0
                T[HITS2] += 1.0
                T[EVENT] = SECOND_LEG
                taken = True
        if not taken and T[ACTIVE1] == 0.0:
            # a new track: the detector's order of the ends, unless the last track ran the other way
            if T[LAST_TH] == T[LAST_TH]:
                th_m, d_m, r_td = oriented(th_m, d_m, r_td, T[LAST_TH])
            _start(T, TH1, th_m, d_m, r_tt, r_td, r_dd)
            T[ACTIVE1], T[MISS1], T[HAS_END] = 1.0, 0.0, 0.0
            T[EVENT] = STARTED
            taken = True
        elif not taken:
            # a second leg: away from the corner if it turns the pipe, along the first if parallel
            t_c = crossing(T[TH1], T[D1], th_m, d_m)
            if abs(math.sin(T[TH1] - th_m)) < parallel or math.isnan(t_c):
                th_m, d_m, r_td = oriented(th_m, d_m, r_td, T[TH1])
            else:
                cx, cy = on_line(T[TH1], T[D1], t_c)
                mx, my = 0.5 * (x1 + x2), 0.5 * (y1 + y_near)
                if (mx - cx) * math.sin(th_m) + (my - cy) * math.cos(th_m) < 0.0:
                    th_m, d_m, r_td = wrap(th_m + math.pi), -d_m, -r_td
            _start(T, TH2, th_m, d_m, r_tt, r_td, r_dd)
            T[ACTIVE2], T[MISS2], T[HITS2] = 1.0, 0.0, 1.0
            T[EVENT] = REJECTED
    # legs no longer seen are dropped; a confirmed second leg takes over from a first no longer seen
    for active, miss, o in ((ACTIVE1, MISS1, TH1), (ACTIVE2, MISS2, TH2)):
        if T[active] != 0.0 and (T[miss] > max_misses or T[o + 4] > max_offset_sd * max_offset_sd):
            T[active] = 0.0
            if active == ACTIVE1:
                T[HAS_END] = 0.0
    if T[ACTIVE2] != 0.0 and T[HITS2] >= confirm and (T[ACTIVE1] == 0.0 or T[MISS1] >= 1.0):
        _promote(T)
    if T[ACTIVE1] == 0.0 and T[ACTIVE2] != 0.0 and T[HITS2] >= confirm:
        _promote(T)
    observe_track(T, tp, hw, depth, out)


@njit(cache=True)
def observe_track(T, tp, hw, depth, out):
    """The track's observation (see :func:`track_step`'s ``out``); sets the track's side and confidence."""
    out[OUT_IN_VIEW] = 0.0
    if T[ACTIVE1] == 0.0:
        T[CONFIDENCE] = 0.0
        out[OUT_SIDE] = T[SIDE]
        return
    T[LAST_TH] = T[TH1]
    th1, d1 = T[TH1], T[D1]
    turn = _shows_turn(T, tp)
    t_end = REACH
    if turn:
        t_end = _corner(T)
    elif T[HAS_END] != 0.0:
        t_end = along(th1, T[END_X], T[END_Y])
    a1, b1 = in_footprint(th1, d1, -REACH, REACH, hw, depth)
    b1 = min(b1, t_end)
    seen1 = a1 <= b1
    seen2 = False
    a2, b2 = 1.0, 0.0
    if turn:
        cx, cy = on_line(th1, d1, t_end)
        a2, b2 = in_footprint(T[TH2], T[D2], along(T[TH2], cx, cy), REACH, hw, depth)
        seen2 = a2 <= b2
    if seen1:
        out[OUT_X2], out[OUT_Y_NEAR] = on_line(th1, d1, a1)
    elif seen2:
        out[OUT_X2], out[OUT_Y_NEAR] = on_line(T[TH2], T[D2], a2)
    if seen2:
        out[OUT_X1], out[OUT_Y1] = on_line(T[TH2], T[D2], b2)
    elif seen1:
        out[OUT_X1], out[OUT_Y1] = on_line(th1, d1, b1)
    # how well the offset is known: 1 at a fresh detection's, falling as the prediction's grows
    floor = 0.5 * tp[0] * tp[0]
    T[CONFIDENCE] = min(1.0, math.sqrt(floor / max(T[P1 + 2], floor)))
    if seen1 or seen2:
        out[OUT_IN_VIEW] = 1.0
        out[OUT_X1] = min(max(out[OUT_X1], -hw), hw)
        out[OUT_X2] = min(max(out[OUT_X2], -hw), hw)
        out[OUT_Y1] = min(max(out[OUT_Y1], 0.0), depth)
        out[OUT_Y_NEAR] = min(max(out[OUT_Y_NEAR], 0.0), depth)
        T[SIDE] = 1.0 if out[OUT_X1] >= 0.0 else -1.0
    elif turn:
        # out of view after a turn: search towards where the second leg goes on
        cx, cy = on_line(th1, d1, t_end)
        T[SIDE] = 1.0 if cx + 2.0 * math.sin(T[TH2]) >= 0.0 else -1.0
    out[OUT_SIDE] = T[SIDE]


def new_track() -> np.ndarray:
    """An empty track's state."""
    T = np.zeros(STATE_SIZE)
    T[SIDE] = 1.0
    T[LAST_TH] = math.nan
    return T


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

    def reset(self, rng: np.random.Generator) -> None:
        """A new episode: the scale error and the gyro's bias drawn from ``rng``, which later steps use."""
        p = self.params
        self.rng = rng
        self.scale = 1.0 + p.dvl_scale_sd * float(rng.standard_normal())
        self.bias = math.radians(p.gyro_bias_sd) * float(rng.standard_normal())

    def motion(self, before: tuple[float, float, float], after: tuple[float, float, float]) -> np.ndarray:
        """The navigation's ``(Δl, Δf, Δψ)`` between two true poses (x north, y east, ψ)."""
        p, dt = self.params, self.dt
        x0, y0, psi0 = before
        dx, dy = after[0] - x0, after[1] - y0
        cs, sn = math.cos(psi0), math.sin(psi0)
        z = self.rng.standard_normal(4)
        d_f = self.scale * (cs * dx + sn * dy) + self.disp_sd * z[0]
        d_l = self.scale * (-sn * dx + cs * dy) + self.disp_sd * z[1]
        d_psi = math.remainder(after[2] - psi0, 2.0 * math.pi)
        d_psi += self.bias * dt + math.radians(p.gyro_arw) * math.sqrt(dt) * z[2]
        self.bias += math.radians(p.gyro_bias_walk) * math.sqrt(dt) * z[3]
        return np.array([d_l, d_f, d_psi])


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

    def step(self, pose: tuple[float, float, float], found: bool, det: tuple[float, float, float, float]) -> np.ndarray:
        """A frame from the true ``pose`` with the detection ``det`` = (x1, y1, x2, y_near): the observation.

        Returns the output array (in view, x1, y1, x2, y_near, side), reused frame after frame.
        """
        if self._pose is None:
            motion = np.zeros(3)
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

    @property
    def confidence(self) -> float:
        """How well the tracked offset is known, in [0, 1] (0 without a track)."""
        return float(self.state[CONFIDENCE])

    @property
    def event(self) -> float:
        """What the last detection did: :data:`ACCEPTED`, :data:`SECOND_LEG`, :data:`REJECTED`, ..."""
        return float(self.state[EVENT])
