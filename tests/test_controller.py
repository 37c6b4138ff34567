"""The PD waypoint controller (paper §3, docs/design.md): forces, waypoints, and the closed loop."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.optimize import brentq

from pipefollow.sim import decision as sim
from pipefollow.sim.controller import (
    PAPER_CONTROLLER,
    ControllerParams,
    control_force,
    pd_force,
    place_waypoint,
    wrap_angle,
)
from pipefollow.sim.pipeline import Pipeline


def test_paper_gains():
    c = PAPER_CONTROLLER
    assert (c.kp_u, c.kp_v, c.kp_r) == (1.5, 0.3, 1.0)
    assert (c.kd_u, c.kd_v, c.kd_r) == (6.0, 4.0, 2.0)
    assert c.radius == 3.0
    assert c.max_bearing == pytest.approx(math.pi / 2)


@pytest.mark.parametrize(
    ("angle", "expected"),
    [
        (0.0, 0.0),
        (1.0, 1.0),
        (-1.0, -1.0),
        (1.5 * math.pi, -0.5 * math.pi),
        (-1.5 * math.pi, 0.5 * math.pi),
        (math.pi, -math.pi),  # the interval is [-π, π)
        (-math.pi, -math.pi),
        (0.1 + 4 * math.pi, 0.1),
        (-0.1 - 6 * math.pi, -0.1),
        (math.radians(350.0), math.radians(-10.0)),
    ],
)
def test_wrap_angle(angle, expected):
    assert wrap_angle(angle) == pytest.approx(expected, abs=1e-12)


def test_wrap_angle_random_keeps_direction_and_range():
    rng = np.random.default_rng(3)
    for a in rng.uniform(-50.0, 50.0, 200):
        w = wrap_angle(a)
        assert -math.pi <= w < math.pi
        assert math.cos(w) == pytest.approx(math.cos(a), abs=1e-12)
        assert math.sin(w) == pytest.approx(math.sin(a), abs=1e-12)


@pytest.mark.parametrize(
    ("psi", "action", "expected"),
    [
        (0.0, 0.0, (3.0, 0.0)),  # heading north, straight ahead
        (0.0, 1.0, (0.0, 3.0)),  # a = +1: 90° to starboard = east
        (0.0, -1.0, (0.0, -3.0)),  # a = -1: 90° to port = west
        (0.0, 0.5, (3 / math.sqrt(2), 3 / math.sqrt(2))),  # 45° to starboard: north-east
        (math.pi / 2, 0.0, (0.0, 3.0)),  # heading east
        (math.pi / 2, 1.0, (-3.0, 0.0)),  # heading east, starboard is south
    ],
)
def test_place_waypoint(psi, action, expected):
    x, y = 1.0, -2.0
    wx, wy = place_waypoint(x, y, psi, action, PAPER_CONTROLLER)
    assert_allclose((wx - x, wy - y), expected, atol=1e-12)


def test_pd_force_hand_computed_tracking_bearing():
    # AUV at (1, 2) heading 30°, waypoint at (4, 6): 5 m away at bearing atan2(4, 3) ≈ 53.13°.
    x, y, psi = 1.0, 2.0, math.radians(30.0)
    u, v, r = 0.2, -0.1, 0.05
    bearing = math.atan2(4.0, 3.0)
    rel = bearing - psi  # waypoint direction seen from the bow
    ex, ey = 5.0 * math.cos(rel), 5.0 * math.sin(rel)  # 4.5981, 1.9641
    expected = (1.5 * ex - 6.0 * u, 0.3 * ey - 4.0 * v, 1.0 * rel - 2.0 * r)
    got = pd_force(x, y, psi, u, v, r, 4.0, 6.0, 0.0, True, PAPER_CONTROLLER)
    assert_allclose(got, expected, rtol=1e-12)
    # and the numbers written out: ex = 3 cos30° + 4 sin30°, ey = -3 sin30° + 4 cos30°
    assert_allclose(got, (1.5 * 4.598076211 - 1.2, 0.3 * 1.964101615 + 0.4, 0.403696442 - 0.1), atol=1e-6)
    assert_allclose(control_force([x, y, psi], [u, v, r], [4.0, 6.0]), expected, rtol=1e-12)


def test_pd_force_fixed_heading_reference_wraps_the_error():
    # Heading 170°, reference -170°: the short way is +20° (to starboard), not -340°.
    psi, psi_ref = math.radians(170.0), math.radians(-170.0)
    tau = pd_force(0.0, 0.0, psi, 0.0, 0.0, 0.3, 0.0, 0.0, psi_ref, False, PAPER_CONTROLLER)
    assert_allclose(tau, (0.0, 0.0, math.radians(20.0) - 2.0 * 0.3), atol=1e-12)


def test_pd_force_uses_all_six_gains():
    c = ControllerParams(kp_u=2.0, kp_v=3.0, kp_r=5.0, kd_u=7.0, kd_v=11.0, kd_r=13.0)
    # heading north, waypoint 1 m north and 2 m east, heading reference 0.1 rad (fixed)
    tau = pd_force(0.0, 0.0, 0.0, 0.1, 0.2, 0.3, 1.0, 2.0, 0.1, False, c)
    assert_allclose(tau, (2.0 * 1.0 - 7.0 * 0.1, 3.0 * 2.0 - 11.0 * 0.2, 5.0 * 0.1 - 13.0 * 0.3), atol=1e-12)


def _straight_pipe():
    return Pipeline(np.array([[0.0, 0.0], [200.0, 0.0]]), "straight")


def test_cruise_speed_on_a_straight_line():
    pipe = _straight_pipe()
    p = sim.PAPER_SIM
    s = np.zeros(sim.STATE_SIZE)
    sim.init_state(s, pipe.points, pipe.cumulative, 0.0, 0.0, 0.0, p)
    speeds = []
    for _ in range(90):
        sim.decide(s, 0.0, pipe.points, pipe.cumulative, p)
        speeds.append(s[sim.U])
        # straight ahead on the pipe: no reason to sway or yaw
        assert abs(s[sim.V]) < 1e-12 and abs(s[sim.R]) < 1e-12 and abs(s[sim.PSI]) < 1e-12
        assert abs(s[sim.Y]) < 1e-12
    speeds = np.array(speeds)
    u_end = speeds[-1]
    assert 0.35 < u_end < 0.55
    # settled: the last ten decisions agree to 0.1 mm/s, and speed rose monotonically
    assert np.ptp(speeds[-10:]) < 1e-4
    assert np.all(np.diff(speeds) > -1e-12)
    # Within a 1-s decision the waypoint (R = 3 m ahead) is held while the AUV moves ≈ u·1 s,
    # so the mean surge error is ≈ R − u/2 and the periodic steady state balances
    # Kp·(R − u/2) = Kd·u + 0.72u + 1.33u|u| + 5.87u³ (eq. 16 surge row, v = r = 0).
    u_avg = brentq(
        lambda u: 1.5 * (3.0 - u / 2) - 6.0 * u - (0.72 * u + 1.33 * u * abs(u) + 5.87 * u**3), 0.0, 2.0
    )
    assert u_end == pytest.approx(u_avg, rel=0.01)


def _after_one_decision(action, psi0=0.0):
    pipe = _straight_pipe()
    p = sim.PAPER_SIM
    s = np.zeros(sim.STATE_SIZE)
    sim.init_state(s, pipe.points, pipe.cumulative, 10.0, 0.0, psi0, p)
    assert s[sim.IN_VIEW] == 1.0
    sim.decide(s, action, pipe.points, pipe.cumulative, p)
    return s


@pytest.mark.parametrize("action", [0.3, 1.0])
def test_positive_action_turns_to_starboard(action):
    s = _after_one_decision(action)
    assert s[sim.PSI] > 0.0  # heading north → clockwise: towards east
    assert s[sim.R] > 0.0
    assert s[sim.Y] > 0.0  # drifted east
    assert s[sim.X] > 10.0  # and moved forward


@pytest.mark.parametrize("action", [-0.3, -1.0])
def test_negative_action_turns_to_port(action):
    s = _after_one_decision(action)
    assert s[sim.PSI] < 0.0
    assert s[sim.R] < 0.0
    assert s[sim.Y] < 0.0
    assert s[sim.X] > 10.0


def test_turns_are_mirror_images():
    right, left = _after_one_decision(0.6), _after_one_decision(-0.6)
    assert_allclose(
        [right[sim.X], right[sim.Y], right[sim.PSI], right[sim.U], right[sim.V], right[sim.R]],
        [left[sim.X], -left[sim.Y], -left[sim.PSI], left[sim.U], -left[sim.V], -left[sim.R]],
        rtol=1e-12,
        atol=1e-14,
    )
