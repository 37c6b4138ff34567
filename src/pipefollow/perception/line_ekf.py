"""The tracked line's extended Kalman filter and its geometry in the camera frame (compiled, no ``fastmath``).

A line ``(θ, d)`` runs along ``u = (sin θ, cos θ)`` at the signed offset ``d`` along
``n = (cos θ, −sin θ)``: ``p(t) = d·n + t·u`` (:mod:`pipefollow.perception.tracker` describes the
state). A line and its covariance ``(Pθθ, Pθd, Pdd)`` sit in five consecutive slots of a track's
state array from offset ``o``: the functions here take the array and the offset.
"""

from __future__ import annotations

import math

from numba import njit

from pipefollow.sim.camera import clip_segment
from pipefollow.sim.controller import wrap_angle as wrap

CHI2_2DOF_99 = 9.2103  # Mahalanobis gate of a line: 99 % of a correct detection's innovations fall inside
CHI2_1DOF_99 = 6.6349  # ... of a second sensor's point on the line: 99 % (a chi-squared table)
CHI2_1DOF_90 = 2.7055  # ... of a detected end on the line: 90 % (a wider gate kept wrong lines; decisions.md)


@njit(cache=True)
def predict(T, o, dl, df, dpsi, nav_var, q_theta, q_d):
    """Move line ``o`` (its first slot) by the vehicle's motion; grow its covariance.

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
