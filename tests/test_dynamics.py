"""Eq. 16 (paper §3): M, C(ν), D(ν), ν̇ and the kinematics, against the printed numbers."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from pipefollow.sim import dynamics
from pipefollow.sim.dynamics import (
    PAPER_AUV,
    body_acceleration,
    coriolis_matrix,
    damping_matrix,
    kinematics,
    mass_matrix,
)

RHO = 1.025  # as printed under eq. 16


def printed_matrices(u, v, r):
    """M, C(ν), D(ν) typed in from the paper's eq. 16, independent of the package."""
    rho = RHO
    m = np.array(
        [
            [80 + 0.026 * rho, 0, 0],
            [0, 80 + 0.04 * rho, 0.0135 * rho],
            [0, 0.0135 * rho, 10 + 0.0107 * rho],
        ]
    )
    c = np.array(
        [
            [0, 0, (0.04 * rho - 80) * v + 0.0135 * rho * r],
            [0, 0, (80 - 0.026 * rho) * u],
            [(80 - 0.04 * rho) * v - 0.0135 * rho * r, (0.026 * rho - 80) * u, 0],
        ]
    )
    d = np.array([[0.72, 0, 0], [0, 0.8896, 7.25], [0, 0.0313, 1.90]])
    dn = np.array(
        [
            [1.33 * abs(u) + 5.87 * u**2, 0, 0],
            [0, 36.5 * abs(v) + 0.805 * abs(r), 0.845 * abs(v) + 3.45 * abs(r)],
            [0, 3.96 * abs(v) - 0.130 * abs(r), -0.080 * abs(v) + 0.75 * abs(r)],
        ]
    )
    return m, c, d + dn


def test_mass_matrix_entries_as_printed():
    m = mass_matrix()
    # 80 + 0.026*1.025 = 80.02665, 80 + 0.04*1.025 = 80.041, 0.0135*1.025 = 0.0138375,
    # 10 + 0.0107*1.025 = 10.0109675
    expected = np.array([[80.02665, 0.0, 0.0], [0.0, 80.041, 0.0138375], [0.0, 0.0138375, 10.0109675]])
    assert_allclose(m, expected, rtol=0, atol=1e-12)
    assert_allclose(m, m.T, rtol=0, atol=0)
    assert np.all(np.linalg.eigvalsh(m) > 0)


def test_coriolis_entries_at_hand_picked_nu():
    u, v, r = 0.4, -0.2, 0.3
    c = coriolis_matrix(np.array([u, v, r]))
    # C13 = (0.041 - 80)(-0.2) + 0.0138375*0.3 = 15.9918 + 0.00415125 = 15.99595125
    # C23 = (80 - 0.02665)(0.4) = 31.98934
    c13 = 15.99595125
    c23 = 31.98934
    expected = np.array([[0, 0, c13], [0, 0, c23], [-c13, -c23, 0]])
    assert_allclose(c, expected, rtol=0, atol=1e-10)
    assert_allclose(c, printed_matrices(u, v, r)[1], rtol=0, atol=1e-12)


def test_damping_entries_at_hand_picked_nu():
    u, v, r = -0.5, 0.2, -0.4
    d = damping_matrix(np.array([u, v, r]))
    # D11 = 0.72 + 1.33*0.5 + 5.87*0.25 = 2.8525
    # D22 = 0.8896 + 36.5*0.2 + 0.805*0.4 = 8.5116
    # D23 = 7.25 + 0.845*0.2 + 3.45*0.4 = 8.799
    # D32 = 0.0313 + 3.96*0.2 - 0.130*0.4 = 0.7713
    # D33 = 1.90 - 0.080*0.2 + 0.75*0.4 = 2.184
    expected = np.array([[2.8525, 0, 0], [0, 8.5116, 8.799], [0, 0.7713, 2.184]])
    assert_allclose(d, expected, rtol=0, atol=1e-12)
    assert_allclose(d, printed_matrices(u, v, r)[2], rtol=0, atol=1e-12)


def test_damping_at_rest_is_the_linear_matrix():
    assert_allclose(damping_matrix(np.zeros(3)), [[0.72, 0, 0], [0, 0.8896, 7.25], [0, 0.0313, 1.90]])


def test_coriolis_is_skew_symmetric_for_random_nu():
    rng = np.random.default_rng(20100601)
    for nu in rng.normal(scale=0.7, size=(50, 3)):
        c = coriolis_matrix(nu)
        assert_allclose(c, -c.T, rtol=0, atol=0)
        # skew symmetry means C(ν) does no work: νᵀ C(ν) ν = 0
        assert abs(nu @ c @ nu) < 1e-12


def test_body_acceleration_matches_printed_model_and_matrix_functions():
    rng = np.random.default_rng(7)
    for _ in range(50):
        nu = rng.normal(scale=0.5, size=3)
        tau = rng.normal(scale=3.0, size=3)
        m, c, d = printed_matrices(*nu)
        expected = np.linalg.solve(m, tau - c @ nu - d @ nu)
        from_functions = np.linalg.solve(
            mass_matrix(), tau - coriolis_matrix(nu) @ nu - damping_matrix(nu) @ nu
        )
        got = body_acceleration(nu, tau)
        assert got.shape == (3,)
        assert_allclose(got, expected, rtol=1e-10, atol=1e-13)
        assert_allclose(got, from_functions, rtol=1e-10, atol=1e-13)


def test_body_acceleration_from_rest_is_inverse_mass_times_force():
    tau = np.array([1.0, 0.0, 0.0])
    # pure surge force on a vehicle at rest: u̇ = X / (80 + 0.026ρ)
    assert_allclose(body_acceleration(np.zeros(3), tau), [1.0 / 80.02665, 0.0, 0.0], rtol=1e-12)
    assert_allclose(body_acceleration(np.zeros(3), np.zeros(3)), np.zeros(3), atol=0)


def surge_damping(u):
    return 0.72 * u + 1.33 * u * abs(u) + 5.87 * u**3


@pytest.mark.parametrize("force", [2.0, 0.5, -1.5])
def test_steady_surge_under_constant_force(force):
    u_star = brentq(lambda u: surge_damping(u) - force, -5.0, 5.0, xtol=1e-14)
    assert_allclose(body_acceleration([u_star, 0.0, 0.0], [force, 0.0, 0.0]), 0.0, atol=1e-12)

    sol = solve_ivp(
        lambda t, nu: body_acceleration(nu, [force, 0.0, 0.0]),
        (0.0, 500.0),  # slowest time constant here is M11 / D'(u*) ≈ 26 s
        np.zeros(3),
        rtol=1e-9,
        atol=1e-12,
    )
    assert sol.success
    u_end, v_end, r_end = sol.y[:, -1]
    assert_allclose(u_end, u_star, rtol=1e-6)
    assert abs(v_end) < 1e-12 and abs(r_end) < 1e-12
    # monotone approach from rest: never overshoots the steady speed
    assert np.all(np.sign(force) * sol.y[0] <= abs(u_star) * (1 + 1e-9))


@pytest.mark.parametrize(
    ("nu", "tau"),
    [
        (np.zeros(2), np.zeros(3)),
        (np.zeros(3), np.zeros(4)),
        (np.zeros((3, 1)), np.zeros(3)),
        (np.zeros(3), np.zeros((1, 3))),
        (0.0, np.zeros(3)),
    ],
)
def test_body_acceleration_rejects_bad_shapes(nu, tau):
    with pytest.raises(ValueError, match="shape"):
        body_acceleration(nu, tau)


def test_default_parameters_are_the_printed_ones():
    assert PAPER_AUV.rho == RHO
    assert dynamics.AUVParams() == PAPER_AUV


@pytest.mark.parametrize(
    ("psi", "u", "v", "r", "expected"),
    [
        (0.0, 1.0, 0.0, 0.2, (1.0, 0.0, 0.2)),  # heading north, surge → north
        (math.pi / 2, 1.0, 0.0, 0.0, (0.0, 1.0, 0.0)),  # heading east, surge → east
        (0.0, 0.0, 1.0, 0.0, (0.0, 1.0, 0.0)),  # heading north, sway to starboard → east
        (math.pi / 2, 0.0, 1.0, 0.0, (-1.0, 0.0, 0.0)),  # heading east, starboard is south
        (math.pi / 6, 2.0, 0.0, -0.1, (math.sqrt(3), 1.0, -0.1)),
    ],
)
def test_kinematics_rotation(psi, u, v, r, expected):
    assert_allclose(kinematics(psi, u, v, r), expected, atol=1e-15)
