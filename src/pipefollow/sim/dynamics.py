"""The AUV's 3-DOF model (paper §3, eq. 16) and its kinematics (the RK4 steps are in ``sim.decision``).

Frames follow Fossen: earth x north, y east, heading ψ clockwise from north; body x forward,
y starboard. ``eta = (x, y, psi)`` is the pose, ``nu = (u, v, r)`` the body velocities and
``tau = (X, Y, N)`` the body forces (N, N, N m).

The inner functions work on float scalars and return tuples, so that numba compiles them to
allocation-free code; the array functions at the bottom are the public, checked interface.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit


class AUVParams(NamedTuple):
    """Coefficients of eq. 16 exactly as printed in the paper (SI units)."""

    rho: float = 1.025  # density of seawater, as printed (paper §3)
    mass: float = 80.0  # rigid-body mass (kg), M11 and M22
    inertia: float = 10.0  # yaw moment of inertia (kg m^2), M33
    added_u: float = 0.026  # added mass in surge, multiplies rho (M11)
    added_v: float = 0.04  # added mass in sway, multiplies rho (M22)
    added_vr: float = 0.0135  # sway-yaw added-mass coupling, multiplies rho (M23 = M32)
    added_r: float = 0.0107  # added inertia in yaw, multiplies rho (M33)
    d_u: float = 0.72  # linear surge damping D11
    d_vv: float = 0.8896  # linear sway damping D22
    d_vr: float = 7.25  # linear damping D23
    d_rv: float = 0.0313  # linear damping D32
    d_rr: float = 1.90  # linear yaw damping D33
    dn_u_absu: float = 1.33  # Dn11 = 1.33|u| + 5.87u^2
    dn_u_uu: float = 5.87
    dn_vv_absv: float = 36.5  # Dn22 = 36.5|v| + 0.805|r|
    dn_vv_absr: float = 0.805
    dn_vr_absv: float = 0.845  # Dn23 = 0.845|v| + 3.45|r|
    dn_vr_absr: float = 3.45
    dn_rv_absv: float = 3.96  # Dn32 = 3.96|v| - 0.130|r|
    dn_rv_absr: float = -0.130
    dn_rr_absv: float = -0.080  # Dn33 = -0.080|v| + 0.75|r|
    dn_rr_absr: float = 0.75


PAPER_AUV = AUVParams()


@njit(cache=True)
def _mass_terms(p):
    m11 = p.mass + p.added_u * p.rho
    m22 = p.mass + p.added_v * p.rho
    m23 = p.added_vr * p.rho
    m33 = p.inertia + p.added_r * p.rho
    return m11, m22, m23, m33


@njit(cache=True)
def acceleration(u, v, r, tx, ty, tn, p):
    """ν̇ = M⁻¹ (τ − C(ν)ν − D(ν)ν) of eq. 16, on scalars."""
    m11, m22, m23, m33 = _mass_terms(p)
    rho = p.rho
    # C(nu) nu, with C as printed (skew-symmetric).
    c13 = (p.added_v * rho - p.mass) * v + p.added_vr * rho * r
    c23 = (p.mass - p.added_u * rho) * u
    cnu_x = c13 * r
    cnu_y = c23 * r
    cnu_n = -c13 * u - c23 * v
    # D(nu) nu = (D + Dn(nu)) nu.
    au, av, ar = abs(u), abs(v), abs(r)
    d11 = p.d_u + p.dn_u_absu * au + p.dn_u_uu * u * u
    d22 = p.d_vv + p.dn_vv_absv * av + p.dn_vv_absr * ar
    d23 = p.d_vr + p.dn_vr_absv * av + p.dn_vr_absr * ar
    d32 = p.d_rv + p.dn_rv_absv * av + p.dn_rv_absr * ar
    d33 = p.d_rr + p.dn_rr_absv * av + p.dn_rr_absr * ar
    f1 = tx - cnu_x - d11 * u
    f2 = ty - cnu_y - d22 * v - d23 * r
    f3 = tn - cnu_n - d32 * v - d33 * r
    # M is diagonal in surge and a 2x2 block in sway-yaw: invert analytically.
    det = m22 * m33 - m23 * m23
    return f1 / m11, (m33 * f2 - m23 * f3) / det, (m22 * f3 - m23 * f2) / det


@njit(cache=True)
def kinematics(psi, u, v, r):
    """η̇ = R(ψ) ν: earth-frame rates of (x north, y east, ψ)."""
    c, s = np.cos(psi), np.sin(psi)
    return c * u - s * v, s * u + c * v, r


def mass_matrix(params: AUVParams = PAPER_AUV) -> np.ndarray:
    """M of eq. 16 (3×3)."""
    m11, m22, m23, m33 = _mass_terms(params)
    return np.array([[m11, 0.0, 0.0], [0.0, m22, m23], [0.0, m23, m33]])


def coriolis_matrix(nu: np.ndarray, params: AUVParams = PAPER_AUV) -> np.ndarray:
    """C(ν) of eq. 16 (3×3), as printed."""
    u, v, r = (float(x) for x in nu)
    p = params
    c13 = (p.added_v * p.rho - p.mass) * v + p.added_vr * p.rho * r
    c23 = (p.mass - p.added_u * p.rho) * u
    return np.array([[0.0, 0.0, c13], [0.0, 0.0, c23], [-c13, -c23, 0.0]])


def damping_matrix(nu: np.ndarray, params: AUVParams = PAPER_AUV) -> np.ndarray:
    """D(ν) = D + D_n(ν) of eq. 16 (3×3)."""
    u, v, r = (abs(float(x)) for x in nu)
    p = params
    linear = np.array([[p.d_u, 0.0, 0.0], [0.0, p.d_vv, p.d_vr], [0.0, p.d_rv, p.d_rr]])
    nonlinear = np.array(
        [
            [p.dn_u_absu * u + p.dn_u_uu * u * u, 0.0, 0.0],
            [0.0, p.dn_vv_absv * v + p.dn_vv_absr * r, p.dn_vr_absv * v + p.dn_vr_absr * r],
            [0.0, p.dn_rv_absv * v + p.dn_rv_absr * r, p.dn_rr_absv * v + p.dn_rr_absr * r],
        ]
    )
    return linear + nonlinear


def body_acceleration(nu, tau, params: AUVParams = PAPER_AUV) -> np.ndarray:
    """Return ν̇ of eq. 16 for body velocities ``nu`` and forces ``tau`` (arrays of shape (3,))."""
    nu = np.asarray(nu, dtype=np.float64)
    tau = np.asarray(tau, dtype=np.float64)
    if nu.shape != (3,) or tau.shape != (3,):
        raise ValueError(f"nu and tau must have shape (3,), got {nu.shape} and {tau.shape}")
    return np.array(acceleration(nu[0], nu[1], nu[2], tau[0], tau[1], tau[2], params))
