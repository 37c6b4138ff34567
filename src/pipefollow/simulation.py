"""One decision of the closed loop, composed from the pure stages (docs/design.md, data flow).

A decision lasts ``substeps * dt`` seconds (1 s = 20 RK4 steps of 0.05 s). It places the
waypoint (or, with the pipe lost, runs the search behaviour), integrates controller and vehicle
with RK4, updates the progress along the pipe, reads the camera and computes the reward.

The simulation state is one float64 array with the named slots below, so that the Gymnasium
environment and the compiled training loop hold exactly the same thing.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.camera import PAPER_CAMERA, CameraParams, observe, tracking_errors
from pipefollow.controller import PAPER_CONTROLLER, ControllerParams, pd_force, place_waypoint
from pipefollow.dynamics import PAPER_AUV, AUVParams, acceleration, kinematics
from pipefollow.pipeline import project
from pipefollow.reward import LOST_REWARD, reward


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
    start_speed: float = 0.0  # surge speed u at the start (m/s): at rest (docs/design.md, "start")


PAPER_SIM = SimParams()

# Slots of the state array. The first four are the observation (x1, y1, x2, v_x).
X1, Y1, X2, VX = 0, 1, 2, 3
E_DIST, E_ANGL, IN_VIEW, Y_NEAR = 4, 5, 6, 7
X, Y, PSI, U, V, R = 8, 9, 10, 11, 12, 13
PROGRESS, PROGRESS_MAX, LAST_SIDE, A_PREV = 14, 15, 16, 17
TIME, WP_X, WP_Y, OVERRIDDEN = 18, 19, 20, 21
STATE_SIZE = 22


@njit(cache=True)
def closed_loop_rk4(s, wp_x, wp_y, psi_ref, track_bearing, dt, p):
    """One RK4 step of controller + vehicle with the waypoint held; updates ``s`` in place."""
    ap, cp = p.auv, p.controller
    x0, y0, h0, u0, v0, r0 = s[X], s[Y], s[PSI], s[U], s[V], s[R]
    # k1
    tx, ty, tn = pd_force(x0, y0, h0, u0, v0, r0, wp_x, wp_y, psi_ref, track_bearing, cp)
    k1x, k1y, k1h = kinematics(h0, u0, v0, r0)
    k1u, k1v, k1r = acceleration(u0, v0, r0, tx, ty, tn, ap)
    # k2
    h = 0.5 * dt
    x, y, ps, u, v, r = x0 + h * k1x, y0 + h * k1y, h0 + h * k1h, u0 + h * k1u, v0 + h * k1v, r0 + h * k1r
    tx, ty, tn = pd_force(x, y, ps, u, v, r, wp_x, wp_y, psi_ref, track_bearing, cp)
    k2x, k2y, k2h = kinematics(ps, u, v, r)
    k2u, k2v, k2r = acceleration(u, v, r, tx, ty, tn, ap)
    # k3
    x, y, ps, u, v, r = x0 + h * k2x, y0 + h * k2y, h0 + h * k2h, u0 + h * k2u, v0 + h * k2v, r0 + h * k2r
    tx, ty, tn = pd_force(x, y, ps, u, v, r, wp_x, wp_y, psi_ref, track_bearing, cp)
    k3x, k3y, k3h = kinematics(ps, u, v, r)
    k3u, k3v, k3r = acceleration(u, v, r, tx, ty, tn, ap)
    # k4
    x, y, ps, u, v, r = (
        x0 + dt * k3x,
        y0 + dt * k3y,
        h0 + dt * k3h,
        u0 + dt * k3u,
        v0 + dt * k3v,
        r0 + dt * k3r,
    )
    tx, ty, tn = pd_force(x, y, ps, u, v, r, wp_x, wp_y, psi_ref, track_bearing, cp)
    k4x, k4y, k4h = kinematics(ps, u, v, r)
    k4u, k4v, k4r = acceleration(u, v, r, tx, ty, tn, ap)
    w = dt / 6.0
    s[X] = x0 + w * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
    s[Y] = y0 + w * (k1y + 2.0 * k2y + 2.0 * k3y + k4y)
    s[PSI] = h0 + w * (k1h + 2.0 * k2h + 2.0 * k3h + k4h)
    s[U] = u0 + w * (k1u + 2.0 * k2u + 2.0 * k3u + k4u)
    s[V] = v0 + w * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
    s[R] = r0 + w * (k1r + 2.0 * k2r + 2.0 * k3r + k4r)


@njit(cache=True)
def read_camera(s, points, cum, p):
    """Update the observation slots of ``s`` from the camera at the current pose."""
    seen, x1, y1, x2, y_near, _, _ = observe(points, cum, s[X], s[Y], s[PSI], s[PROGRESS], p.camera)
    s[VX] = s[U]
    s[IN_VIEW] = 1.0 if seen else 0.0
    if seen:
        # Clipping puts the ends on the footprint's edges; clamp away floating-point dust there.
        w, depth = p.camera.half_width, p.camera.depth
        x1, x2 = min(max(x1, -w), w), min(max(x2, -w), w)
        y1, y_near = min(max(y1, 0.0), depth), min(max(y_near, 0.0), depth)
        s[X1], s[Y1], s[X2], s[Y_NEAR] = x1, y1, x2, y_near
        s[E_DIST], s[E_ANGL] = tracking_errors(x1, y1, x2, y_near)
        s[LAST_SIDE] = 1.0 if x1 >= 0.0 else -1.0
    # While the pipe is lost the observation holds the last sighting (and the current speed).


@njit(cache=True)
def init_state(s, points, cum, x, y, psi, p):
    """Fill ``s`` for an AUV at pose (x, y, ψ) next to the pipeline, surging at ``p.start_speed``."""
    s[:] = 0.0
    s[X], s[Y], s[PSI] = x, y, psi
    s[U] = p.start_speed
    s[PROGRESS] = project(points, cum, x, y, -np.inf, np.inf)
    s[PROGRESS_MAX] = s[PROGRESS]
    s[LAST_SIDE] = 1.0
    s[WP_X], s[WP_Y] = x, y
    read_camera(s, points, cum, p)


@njit(cache=True)
def decide(s, action, points, cum, p):
    """Run one decision from state ``s`` (updated in place) and return its reward.

    With the pipe in view, ``action`` in [-1, 1] places the waypoint at bearing ψ + a·90°. With
    the pipe lost, the search behaviour overrides it: the waypoint is held at the current
    position and the AUV turns towards the side where the pipe was last seen; the executed
    action is recorded as that side (±1) and the reward is the lost penalty.
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
    for _ in range(p.substeps):
        closed_loop_rk4(s, wp_x, wp_y, psi_ref, track, p.dt, p)
    s[PSI] = (s[PSI] + math.pi) % (2.0 * math.pi) - math.pi
    s[TIME] += p.dt * p.substeps
    s[WP_X], s[WP_Y] = wp_x, wp_y
    s[OVERRIDDEN] = 1.0 if overridden else 0.0
    s[PROGRESS] = project(
        points, cum, s[X], s[Y], s[PROGRESS] - p.progress_back, s[PROGRESS] + p.progress_ahead
    )
    s[PROGRESS_MAX] = max(s[PROGRESS_MAX], s[PROGRESS])
    read_camera(s, points, cum, p)
    if overridden or s[IN_VIEW] == 0.0:
        r = p.lost_reward
    else:
        r = reward(s[VX], s[E_DIST], s[E_ANGL], executed, s[A_PREV])
    s[A_PREV] = executed
    return r


def pack_params(p: SimParams) -> np.ndarray:
    """Flatten ``p`` into a float64 array, the cheap way to hand parameters to compiled code.

    Passing a nested NamedTuple from Python into a numba function costs ≈7 µs of argument
    checking per call; an array costs a fraction of a microsecond. :func:`unpack_params`
    rebuilds the record inside compiled code.
    """
    return np.array(
        [
            *p.auv,
            *p.controller,
            *p.camera,
            p.dt,
            p.substeps,
            p.lost_reward,
            p.progress_back,
            p.progress_ahead,
            p.start_speed,
        ],
        dtype=np.float64,
    )


@njit(cache=True)
def unpack_params(a):
    """Inverse of :func:`pack_params`, inside compiled code."""
    auv = AUVParams(
        a[0],
        a[1],
        a[2],
        a[3],
        a[4],
        a[5],
        a[6],
        a[7],
        a[8],
        a[9],
        a[10],
        a[11],
        a[12],
        a[13],
        a[14],
        a[15],
        a[16],
        a[17],
        a[18],
        a[19],
        a[20],
        a[21],
    )
    ctrl = ControllerParams(a[22], a[23], a[24], a[25], a[26], a[27], a[28], a[29])
    cam = CameraParams(a[30], a[31])
    return SimParams(auv, ctrl, cam, a[32], int(a[33]), a[34], a[35], a[36], a[37])


@njit(cache=True)
def decide_packed(s, action, points, cum, packed):
    """:func:`decide` with packed parameters: the entry point for Python callers."""
    return decide(s, action, points, cum, unpack_params(packed))


@njit(cache=True)
def init_state_packed(s, points, cum, x, y, psi, packed):
    """:func:`init_state` with packed parameters."""
    init_state(s, points, cum, x, y, psi, unpack_params(packed))
