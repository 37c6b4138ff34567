"""One decision of the closed loop, composed from the pure stages (docs/design.md, data flow).

A decision lasts ``substeps * dt`` seconds (1 s = 20 RK4 steps of 0.05 s). It places the
waypoint (or, with the pipe lost, runs the search behaviour), integrates controller and vehicle
with RK4, updates the progress along the pipe, reads the camera and computes the reward.

With an ocean current (:mod:`pipefollow.sim.disturbance`) the RK4 integrates the pose η and the
velocity relative to the water ν_r (slots ``U, V, R``): eq. 16 in ν_r,
``M ν̇_r + C(ν_r) ν_r + D(ν_r) ν_r = τ``, and ``η̇ = R(ψ) ν_r + [V_c cos β_c, V_c sin β_c, 0]``.
The PD controller damps the velocity over ground ν = ν_r + ν_c, and ``v_x`` (observation and
reward) is the surge speed over ground. Without a current ν = ν_r and nothing changes.

The simulation state is one float64 array with the named slots below, so that the Gymnasium
environment and the compiled training loop hold exactly the same thing.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit
from numba.extending import register_jitable
from numba.np.unsafe.ndarray import to_fixed_tuple

from pipefollow.sim import records
from pipefollow.sim.camera import PAPER_CAMERA, CameraParams, observe, tracking_errors
from pipefollow.sim.controller import PAPER_CONTROLLER, ControllerParams, pd_force, place_waypoint, wrap_angle
from pipefollow.sim.disturbance import (
    NO_DISTURBANCE,
    Disturbance,
    missed,
    noise_layout,
    sensor_offsets,
    vary_current,
)
from pipefollow.sim.disturbance import unpack as unpack_disturbance
from pipefollow.sim.dynamics import PAPER_AUV, AUVParams, acceleration, kinematics
from pipefollow.sim.pipeline import project
from pipefollow.sim.reward import LOST_REWARD, reward


class SimParams(NamedTuple):
    """Everything that fixes the simulated system."""

    auv: AUVParams = PAPER_AUV
    controller: ControllerParams = PAPER_CONTROLLER
    camera: CameraParams = PAPER_CAMERA
    dt: float = 0.05  # RK4 step (s), docs/design.md
    substeps: int = 20  # RK4 steps per decision: decisions every 1 s (paper §4.1)
    lost_reward: float = LOST_REWARD  # reward per decision while the pipe is lost (paper §4)
    progress_back: float = 1.5  # progress search window behind the last progress (m)
    progress_ahead: float = 1.5  # and ahead of it (m): ≥ 1 s of travel plus a corner cut (√2 × 1 m)
    disturbance: Disturbance = NO_DISTURBANCE  # current and camera faults; none by default
    start_speed: float = 0.0  # surge speed u (through the water) at the start (m/s): at rest (docs/design.md)
    end_at_pipe_end: bool = True  # reaching the pipe's far end ends the episode (reading pipe_end)


PAPER_SIM = SimParams()

# Slots of the state array. The first four are the observation (x1, y1, x2, v_x).
X1, Y1, X2, VX = 0, 1, 2, 3
E_DIST, E_ANGL, IN_VIEW, Y_NEAR = 4, 5, 6, 7
X, Y, PSI, U, V, R = 8, 9, 10, 11, 12, 13
PROGRESS, PROGRESS_MAX, LAST_SIDE, A_PREV = 14, 15, 16, 17
TIME, WP_X, WP_Y, OVERRIDDEN = 18, 19, 20, 21
CURRENT_SPEED, CURRENT_DIR, MISSED = 22, 23, 24  # V_c (m/s), β_c (rad), last reading missed (0/1)
# What the vehicle's own motion sensors read at each camera reading (pipefollow.sim.observation):
# the DVL's sway velocity over ground (m/s, starboard positive) and the gyro's yaw rate (rad/s),
# each with its noise (Disturbance.dvl_noise, .gyro_noise); no learner sees them under the paper's state.
DVL_SWAY, GYRO_R = 25, 26
STATE_SIZE = 27


@register_jitable
def decision_seconds(p):
    """The length of one decision (s): ``substeps`` RK4 steps of ``dt`` (1 s = 20 × 0.05 s)."""
    return p.dt * p.substeps


@register_jitable
def decisions_in(seconds, p):
    """The number of decisions in ``seconds`` (an episode's length in decisions)."""
    return int(round(seconds / decision_seconds(p)))


@njit(cache=True)
def _rates(x, y, ps, u, v, r, vn, ve, wp_x, wp_y, psi_ref, track_bearing, p):
    """η̇ and ν̇_r of the closed loop at pose (x, y, ψ), relative velocity ν_r = (u, v, r).

    The current's earth velocity (vn, ve) gives ν_c = R(ψ)ᵀ (vn, ve, 0); the PD law acts on
    ν = ν_r + ν_c, eq. 16 on ν_r, and η̇ = R(ψ) ν_r + (vn, ve, 0).
    """
    cs, sn = math.cos(ps), math.sin(ps)
    u_g = u + (cs * vn + sn * ve)  # surge over ground (m/s)
    v_g = v + (cs * ve - sn * vn)  # sway over ground (m/s)
    tx, ty, tn = pd_force(x, y, ps, u_g, v_g, r, wp_x, wp_y, psi_ref, track_bearing, p.controller)
    kx, ky, kh = kinematics(ps, u, v, r)
    ku, kv, kr = acceleration(u, v, r, tx, ty, tn, p.auv)
    return kx + vn, ky + ve, kh, ku, kv, kr


@njit(cache=True)
def closed_loop_rk4(s, wp_x, wp_y, psi_ref, track_bearing, dt, p, vn=0.0, ve=0.0):
    """One RK4 step of controller + vehicle with the waypoint held; updates ``s`` in place.

    ``vn, ve`` is the current's earth velocity (m/s, north and east); ``s[U:R+1]`` holds ν_r.
    """
    x0, y0, h0, u0, v0, r0 = s[X], s[Y], s[PSI], s[U], s[V], s[R]
    # k1
    k1x, k1y, k1h, k1u, k1v, k1r = _rates(
        x0, y0, h0, u0, v0, r0, vn, ve, wp_x, wp_y, psi_ref, track_bearing, p
    )
    # k2
    h = 0.5 * dt
    x, y, ps, u, v, r = x0 + h * k1x, y0 + h * k1y, h0 + h * k1h, u0 + h * k1u, v0 + h * k1v, r0 + h * k1r
    k2x, k2y, k2h, k2u, k2v, k2r = _rates(x, y, ps, u, v, r, vn, ve, wp_x, wp_y, psi_ref, track_bearing, p)
    # k3
    x, y, ps, u, v, r = x0 + h * k2x, y0 + h * k2y, h0 + h * k2h, u0 + h * k2u, v0 + h * k2v, r0 + h * k2r
    k3x, k3y, k3h, k3u, k3v, k3r = _rates(x, y, ps, u, v, r, vn, ve, wp_x, wp_y, psi_ref, track_bearing, p)
    # k4
    x, y, ps, u, v, r = (
        x0 + dt * k3x,
        y0 + dt * k3y,
        h0 + dt * k3h,
        u0 + dt * k3u,
        v0 + dt * k3v,
        r0 + dt * k3r,
    )
    k4x, k4y, k4h, k4u, k4v, k4r = _rates(x, y, ps, u, v, r, vn, ve, wp_x, wp_y, psi_ref, track_bearing, p)
    w = dt / 6.0
    s[X] = x0 + w * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
    s[Y] = y0 + w * (k1y + 2.0 * k2y + 2.0 * k3y + k4y)
    s[PSI] = h0 + w * (k1h + 2.0 * k2h + 2.0 * k3h + k4h)
    s[U] = u0 + w * (k1u + 2.0 * k2u + 2.0 * k3u + k4u)
    s[V] = v0 + w * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
    s[R] = r0 + w * (k1r + 2.0 * k2r + 2.0 * k3r + k4r)


@njit(cache=True)
def read_camera(s, points, cum, p, z=None):
    """Update the observation slots of ``s`` from the camera at the current pose.

    ``z`` holds the reading's standard normals (see :mod:`pipefollow.sim.disturbance`); without it
    (``None``) the camera is exact and never misses.
    """
    d = p.disturbance
    seen, x1, y1, x2, y_near, _, _ = observe(
        points, cum, s[X], s[Y], s[PSI], s[PROGRESS], p.camera, d.buried_from, d.buried_to
    )
    # v_x: surge speed over ground, u = u_r + u_c (the camera looks at the seabed)
    psi, vc, bc = s[PSI], s[CURRENT_SPEED], s[CURRENT_DIR]
    s[VX] = s[U] + (math.cos(psi) * (vc * math.cos(bc)) + math.sin(psi) * (vc * math.sin(bc)))
    s[MISSED] = 0.0
    if z is not None:
        i_cam, i_miss, n = noise_layout(d)
        if seen and i_miss > i_cam:
            sd = d.camera_noise
            x1, y1 = x1 + sd * z[i_cam], y1 + sd * z[i_cam + 1]
            x2, y_near = x2 + sd * z[i_cam + 2], y_near + sd * z[i_cam + 3]
        if d.miss_prob > 0.0 and missed(d, z[i_miss]):
            s[MISSED] = 1.0
            seen = False
    s[IN_VIEW] = 1.0 if seen else 0.0
    read_motion_sensors(s, d, z)
    if seen:
        # Clipping puts the ends on the footprint's edges; clamp away floating-point dust there
        # (and noise beyond them).
        w, depth = p.camera.half_width, p.camera.depth
        x1, x2 = min(max(x1, -w), w), min(max(x2, -w), w)
        y1, y_near = min(max(y1, 0.0), depth), min(max(y_near, 0.0), depth)
        s[X1], s[Y1], s[X2], s[Y_NEAR] = x1, y1, x2, y_near
        s[E_DIST], s[E_ANGL] = tracking_errors(x1, y1, x2, y_near)
        s[LAST_SIDE] = 1.0 if x1 >= 0.0 else -1.0
    # While the pipe is lost the observation holds the last sighting (and the current speed).


@njit(cache=True)
def read_motion_sensors(s, d, z=None):
    """The DVL's sway velocity over ground and the gyro's yaw rate into ``s[DVL_SWAY]``, ``s[GYRO_R]``.

    The DVL tracks the seabed: it reads the velocity over ground, whose sway part is the sway
    through the water plus the current's, ``v + (−sin ψ V_n + cos ψ V_e)``; the gyro reads ``r``.
    Each adds Gaussian noise of s.d. ``d.dvl_noise`` (m/s), ``d.gyro_noise`` (rad/s) from the
    reading's normals ``z`` (:func:`~pipefollow.sim.disturbance.sensor_offsets`); exact without.
    """
    psi, vc, bc = s[PSI], s[CURRENT_SPEED], s[CURRENT_DIR]
    vn, ve = vc * math.cos(bc), vc * math.sin(bc)
    sway = s[V] + (math.cos(psi) * ve - math.sin(psi) * vn)
    rate = s[R]
    if z is not None:
        i_dvl, i_gyro = sensor_offsets(d)
        if d.dvl_noise > 0.0:
            sway += d.dvl_noise * z[i_dvl]
        if d.gyro_noise > 0.0:
            rate += d.gyro_noise * z[i_gyro]
    s[DVL_SWAY], s[GYRO_R] = sway, rate


@njit(cache=True)
def init_state(s, points, cum, x, y, psi, p, z=None):
    """Fill ``s`` for an AUV at pose (x, y, ψ) next to the pipeline, surging at ``p.start_speed``.

    ``z``: the first camera reading's standard normals (see :func:`read_camera`).
    """
    s[:] = 0.0
    s[X], s[Y], s[PSI] = x, y, psi
    s[U] = p.start_speed
    s[PROGRESS] = project(points, cum, x, y, -np.inf, np.inf)
    s[PROGRESS_MAX] = s[PROGRESS]
    s[LAST_SIDE] = 1.0
    s[WP_X], s[WP_Y] = x, y
    s[CURRENT_SPEED], s[CURRENT_DIR] = p.disturbance.current_speed, p.disturbance.current_direction
    read_camera(s, points, cum, p, z)


@njit(cache=True)
def decide(s, action, points, cum, p, z=None):
    """Run one decision from state ``s`` (updated in place) and return its reward.

    With the pipe in view, ``action`` in [-1, 1] places the waypoint at bearing ψ + a·90°. With
    the pipe lost, the search behaviour overrides it: the waypoint is held at the current
    position and the AUV turns towards the side where the pipe was last seen; the executed
    action is recorded as that side (±1) and the reward is the lost penalty.

    ``z``: the decision's standard normals for the random disturbances (see
    :mod:`pipefollow.sim.disturbance`); with ``None`` the current keeps its speed and direction
    and the camera is exact and never misses.
    """
    overridden = s[IN_VIEW] == 0.0
    if overridden:
        executed = s[LAST_SIDE]
        wp_x, wp_y = s[X], s[Y]
        psi_ref = s[PSI] + executed * p.controller.max_bearing
        track = False
    else:
        executed = action
        wp_x, wp_y = place_waypoint(s[X], s[Y], s[PSI], action, p.controller)
        psi_ref = 0.0
        track = True
    d = p.disturbance
    seconds = decision_seconds(p)
    if z is not None:
        if noise_layout(d)[0] == 2:
            s[CURRENT_SPEED], s[CURRENT_DIR] = vary_current(
                s[CURRENT_SPEED], s[CURRENT_DIR], d, seconds, z[0], z[1]
            )
    vn = s[CURRENT_SPEED] * math.cos(s[CURRENT_DIR])  # current, north (m/s)
    ve = s[CURRENT_SPEED] * math.sin(s[CURRENT_DIR])  # current, east (m/s)
    for _ in range(p.substeps):
        closed_loop_rk4(s, wp_x, wp_y, psi_ref, track, p.dt, p, vn, ve)
    s[PSI] = wrap_angle(s[PSI])
    s[TIME] += seconds
    s[WP_X], s[WP_Y] = wp_x, wp_y
    s[OVERRIDDEN] = 1.0 if overridden else 0.0
    s[PROGRESS] = project(
        points, cum, s[X], s[Y], s[PROGRESS] - p.progress_back, s[PROGRESS] + p.progress_ahead
    )
    s[PROGRESS_MAX] = max(s[PROGRESS_MAX], s[PROGRESS])
    read_camera(s, points, cum, p, z)
    if overridden or s[IN_VIEW] == 0.0:
        r = p.lost_reward
    else:
        r = reward(s[VX], s[E_DIST], s[E_ANGL], executed, s[A_PREV])
    s[A_PREV] = executed
    return r


# Where each field of SimParams starts in pack_params' array, from the field names.
OFFSETS = records.offsets(PAPER_SIM)
_AUV, _N_AUV = OFFSETS["auv"], len(AUVParams._fields)
_CONTROLLER, _N_CONTROLLER = OFFSETS["controller"], len(ControllerParams._fields)
_CAMERA, _N_CAMERA = OFFSETS["camera"], len(CameraParams._fields)
_DT, _SUBSTEPS, _LOST_REWARD = OFFSETS["dt"], OFFSETS["substeps"], OFFSETS["lost_reward"]
_BACK, _AHEAD = OFFSETS["progress_back"], OFFSETS["progress_ahead"]
_DISTURBANCE, _START_SPEED = OFFSETS["disturbance"], OFFSETS["start_speed"]
_END_AT_PIPE_END = OFFSETS["end_at_pipe_end"]


def pack_params(p: SimParams) -> np.ndarray:
    """Flatten ``p`` into a float64 array, the cheap way to hand parameters to compiled code.

    Passing a nested NamedTuple from Python into a numba function costs microseconds of argument
    checking per call, an array far less (figures in benchmarks/README.md). :func:`unpack_params`
    rebuilds the record inside compiled code; :data:`OFFSETS` says where each field starts.
    """
    return records.pack(p)


@njit(cache=True)
def unpack_params(a):
    """Inverse of :func:`pack_params`, inside compiled code."""
    auv = AUVParams(*to_fixed_tuple(a[_AUV : _AUV + _N_AUV], _N_AUV))
    ctrl = ControllerParams(*to_fixed_tuple(a[_CONTROLLER : _CONTROLLER + _N_CONTROLLER], _N_CONTROLLER))
    cam = CameraParams(*to_fixed_tuple(a[_CAMERA : _CAMERA + _N_CAMERA], _N_CAMERA))
    dist = unpack_disturbance(a, _DISTURBANCE)
    return SimParams(
        auv,
        ctrl,
        cam,
        a[_DT],
        int(a[_SUBSTEPS]),
        a[_LOST_REWARD],
        a[_BACK],
        a[_AHEAD],
        dist,
        a[_START_SPEED],
        a[_END_AT_PIPE_END] != 0.0,
    )


@njit(cache=True)
def decide_packed(s, action, points, cum, packed, z=None):
    """:func:`decide` with packed parameters: the entry point for Python callers."""
    return decide(s, action, points, cum, unpack_params(packed), z)


@njit(cache=True)
def init_state_packed(s, points, cum, x, y, psi, packed, z=None):
    """:func:`init_state` with packed parameters."""
    init_state(s, points, cum, x, y, psi, unpack_params(packed), z)


@njit(cache=True)
def draw_normals(rng, z):
    """Fill ``z`` with standard normals from ``rng``, as ``rng.standard_normal(out=z)`` does."""
    for i in range(z.shape[0]):
        z[i] = rng.standard_normal()
