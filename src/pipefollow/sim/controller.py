"""The PD waypoint controller of paper §3 and the lost-pipe search reference.

A decision places a waypoint on the circle of radius ``R`` around the AUV at bearing
``psi + a * 90°`` (``a`` in [-1, 1], positive to starboard). Between decisions the waypoint is
held fixed in the earth frame and the PD law

    tau = Kp ⊙ e − Kd ⊙ nu,   e = (waypoint error in body axes, wrapped heading error)

acts continuously on the closed loop. The heading error is measured to the bearing of the
waypoint, or, while searching for a lost pipe, to a fixed heading reference.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit


class ControllerParams(NamedTuple):
    """PD waypoint-controller gains (paper §3) and waypoint geometry (docs/design.md)."""

    kp_u: float = 1.5  # surge gain on the body-x waypoint error (N/m)
    kp_v: float = 0.3  # sway gain on the body-y waypoint error (N/m)
    kp_r: float = 1.0  # yaw gain on the heading error (N m/rad)
    kd_u: float = 6.0  # surge damping gain (N s/m)
    kd_v: float = 4.0  # sway damping gain (N s/m)
    kd_r: float = 2.0  # yaw damping gain (N m s/rad)
    radius: float = 3.0  # waypoint circle radius R (m), docs/design.md
    max_bearing: float = math.pi / 2  # bearing of a = ±1 (rad): the paper's ±90° limit


PAPER_CONTROLLER = ControllerParams()


@njit(cache=True)
def wrap_angle(angle):
    """Wrap an angle to [-π, π)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True)
def place_waypoint(x, y, psi, action, c):
    """Waypoint (north, east) for a normalized action: on the R-circle at ψ + a·90°."""
    bearing = psi + action * c.max_bearing
    return x + c.radius * math.cos(bearing), y + c.radius * math.sin(bearing)


@njit(cache=True)
def pd_force(x, y, psi, u, v, r, wp_x, wp_y, psi_ref, track_bearing, c):
    """τ = Kp ⊙ e − Kd ⊙ ν for a waypoint held in the earth frame.

    With ``track_bearing`` the heading reference is the bearing from the AUV to the waypoint;
    otherwise it is the fixed ``psi_ref`` (used by the search behaviour).
    """
    dx, dy = wp_x - x, wp_y - y
    cs, sn = math.cos(psi), math.sin(psi)
    ex = cs * dx + sn * dy  # body-x (forward) error
    ey = -sn * dx + cs * dy  # body-y (starboard) error
    if track_bearing:
        psi_ref = math.atan2(dy, dx)
    epsi = wrap_angle(psi_ref - psi)
    return (
        c.kp_u * ex - c.kd_u * u,
        c.kp_v * ey - c.kd_v * v,
        c.kp_r * epsi - c.kd_r * r,
    )


def control_force(eta, nu, waypoint, params: ControllerParams = PAPER_CONTROLLER) -> np.ndarray:
    """Array form of :func:`pd_force` in waypoint-tracking mode: τ for pose ``eta``, velocity ``nu``."""
    eta = np.asarray(eta, dtype=np.float64)
    nu = np.asarray(nu, dtype=np.float64)
    return np.array(pd_force(*eta, *nu, float(waypoint[0]), float(waypoint[1]), 0.0, True, params))
