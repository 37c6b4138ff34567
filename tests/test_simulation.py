"""One decision of the closed loop: RK4 accuracy, rest, the lost-pipe override, eq. 19, params."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal
from scipy.integrate import solve_ivp

from pipefollow.sim import decision as sim
from pipefollow.sim.camera import CameraParams
from pipefollow.sim.controller import PAPER_CONTROLLER, ControllerParams, pd_force
from pipefollow.sim.disturbance import PACKED_SIZE, Disturbance
from pipefollow.sim.dynamics import PAPER_AUV, AUVParams, acceleration, kinematics
from pipefollow.sim.pipeline import Pipeline

P = sim.PAPER_SIM
POSE = [sim.X, sim.Y, sim.PSI, sim.U, sim.V, sim.R]

# A turning manoeuvre: waypoint 3 m away at 60° to starboard, AUV already moving. The start is
# chosen so that u > 0, v < 0, r > 0 throughout: eq. 16 has |v|, |r| terms that are not smooth
# at zero, and a sign change would (correctly) cost RK4 its fourth order.
START_NU = (0.3, -0.02, 0.05)
WAYPOINT = (3.0 * math.cos(math.radians(60.0)), 3.0 * math.sin(math.radians(60.0)))
T_END = 4.0


def start_state():
    s = np.zeros(sim.STATE_SIZE)
    s[sim.U], s[sim.V], s[sim.R] = START_NU
    return s


def rk4_run(dt, history=False):
    s = start_state()
    rows = []
    for _ in range(round(T_END / dt)):
        sim.closed_loop_rk4(s, WAYPOINT[0], WAYPOINT[1], 0.0, True, dt, P)
        rows.append(s[POSE].copy())
    return np.array(rows) if history else s[POSE].copy()


def closed_loop_rhs(t, z):
    x, y, psi, u, v, r = z
    tau = pd_force(x, y, psi, u, v, r, WAYPOINT[0], WAYPOINT[1], 0.0, True, PAPER_CONTROLLER)
    return [*kinematics(psi, u, v, r), *acceleration(u, v, r, *tau, PAPER_AUV)]


@pytest.fixture(scope="module")
def fine():
    return rk4_run(0.005, history=True)


def test_manoeuvre_keeps_the_signs_of_the_velocities(fine):
    u, v, r = fine[:, 3], fine[:, 4], fine[:, 5]
    assert np.all(u > 0) and np.all(v < 0) and np.all(r > 0)
    assert fine[-1, 2] > 0.5  # it really turns: more than 28° in 4 s


def test_rk4_against_a_ten_times_finer_step(fine):
    coarse = rk4_run(0.05)
    err = np.max(np.abs(coarse - fine[-1]))
    assert err < 1e-8
    # the fine step is itself accurate: closer to the coarse one than the coarse one's own error
    assert np.max(np.abs(rk4_run(0.01) - fine[-1])) < err / 100


def test_rk4_is_fourth_order(fine):
    errors = [np.max(np.abs(rk4_run(dt) - fine[-1])) for dt in (0.1, 0.05, 0.025)]
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    # halving dt divides the error by 2⁴ = 16
    assert np.all((ratios > 12.0) & (ratios < 20.0)), ratios


def test_rk4_against_solve_ivp():
    sol = solve_ivp(
        closed_loop_rhs,
        (0.0, T_END),
        [0.0, 0.0, 0.0, *START_NU],
        method="DOP853",
        rtol=1e-10,
        atol=1e-12,
        dense_output=True,
    )
    assert sol.success
    coarse = rk4_run(0.05, history=True)
    times = 0.05 * np.arange(1, len(coarse) + 1)
    assert_allclose(coarse, sol.sol(times).T, rtol=0, atol=1e-8)


def test_rest_stays_at_rest_exactly():
    s = np.zeros(sim.STATE_SIZE)
    s[sim.X], s[sim.Y], s[sim.PSI] = 3.7, -1.2, 2.5
    before = s.copy()
    for _ in range(40):
        # waypoint on the AUV itself, heading reference = heading: no error, no force
        sim.closed_loop_rk4(s, 3.7, -1.2, 2.5, False, 0.05, P)
    assert_array_equal(s, before)


def straight_pipe():
    return Pipeline(np.array([[0.0, 0.0], [60.0, 0.0]]), "straight")


def fresh_state(pipe, x, y, psi):
    s = np.zeros(sim.STATE_SIZE)
    sim.init_state(s, pipe.points, pipe.cumulative, x, y, psi, P)
    return s


def test_init_state():
    pipe = straight_pipe()
    s = fresh_state(pipe, 10.0, -0.5, 0.0)
    assert s[sim.IN_VIEW] == 1.0
    assert_allclose(s[[sim.X1, sim.Y1, sim.X2, sim.VX]], [0.5, 3.0, 0.5, 0.0], atol=1e-12)
    assert s[sim.PROGRESS] == pytest.approx(10.0) and s[sim.PROGRESS_MAX] == pytest.approx(10.0)
    assert s[sim.TIME] == 0.0 and s[sim.U] == 0.0 and s[sim.V] == 0.0 and s[sim.R] == 0.0
    assert s[sim.LAST_SIDE] == 1.0  # pipe at x = +0.5: starboard


@pytest.mark.parametrize("side", [-1.0, 1.0])
def test_decide_with_the_pipe_lost(side):
    pipe = straight_pipe()
    s = fresh_state(pipe, 10.0, 5.0, 0.0)  # 5 m east of the pipe: out of view
    assert s[sim.IN_VIEW] == 0.0
    s[sim.LAST_SIDE] = side
    s[sim.A_PREV] = 0.4
    r = sim.decide(s, -0.7 * side, pipe.points, pipe.cumulative, P)  # the action is ignored
    assert r == -10.0
    assert s[sim.OVERRIDDEN] == 1.0
    assert s[sim.A_PREV] == side  # the executed action is the search side
    assert (s[sim.WP_X], s[sim.WP_Y]) == (10.0, 5.0)  # waypoint held where the search began
    assert np.sign(s[sim.PSI]) == side and np.sign(s[sim.R]) == side  # rotates towards that side
    # in place, up to the sway that the yaw couples into (M23, D23) against the held waypoint
    assert math.hypot(s[sim.X] - 10.0, s[sim.Y] - 5.0) < 0.01
    assert s[sim.TIME] == pytest.approx(1.0)


def test_decide_reward_is_eq19_of_the_resulting_state():
    pipe = straight_pipe()
    s = fresh_state(pipe, 10.0, -0.2, 0.1)
    s[sim.A_PREV] = 0.3
    action = -0.2
    r = sim.decide(s, action, pipe.points, pipe.cumulative, P)
    assert s[sim.IN_VIEW] == 1.0 and s[sim.OVERRIDDEN] == 0.0
    # the camera slots, by hand for a north-going pipe at y = 0: in the camera it is the line
    # through (-y / cos ψ, 0) along (-sin ψ, cos ψ)
    y, psi = s[sim.Y], s[sim.PSI]
    x2 = -y / math.cos(psi)
    x1 = x2 - 3.0 * math.tan(psi)
    assert abs(x1) < 1.0 and abs(x2) < 1.0
    assert_allclose(s[[sim.X1, sim.Y1, sim.X2, sim.Y_NEAR]], [x1, 3.0, x2, 0.0], atol=1e-12)
    assert s[sim.VX] == s[sim.U]
    e_dist = (s[sim.X1] + s[sim.X2]) / 2
    e_angl = math.atan2(s[sim.X1] - s[sim.X2], s[sim.Y1] - s[sim.Y_NEAR])
    assert e_angl == pytest.approx(-psi)
    assert (s[sim.E_DIST], s[sim.E_ANGL]) == pytest.approx((e_dist, e_angl), abs=1e-14)
    expected = s[sim.VX] - e_dist**2 - e_angl**2 - (action - 0.3) ** 2
    assert r == pytest.approx(expected, abs=1e-14)
    assert s[sim.A_PREV] == action


def test_decide_places_the_waypoint_and_advances_time():
    pipe = straight_pipe()
    s = fresh_state(pipe, 10.0, 0.0, 0.0)
    sim.decide(s, 0.5, pipe.points, pipe.cumulative, P)
    # heading north, a = 0.5: 45° to starboard, 3 m away
    assert_allclose((s[sim.WP_X], s[sim.WP_Y]), (10.0 + 3 / math.sqrt(2), 3 / math.sqrt(2)), atol=1e-12)
    assert s[sim.TIME] == pytest.approx(1.0)
    sim.decide(s, 0.5, pipe.points, pipe.cumulative, P)
    assert s[sim.TIME] == pytest.approx(2.0)
    # progress along the pipe is the north coordinate of the AUV
    assert s[sim.PROGRESS] == pytest.approx(s[sim.X], abs=1e-12)


def test_decide_is_20_rk4_steps():
    pipe = straight_pipe()
    s = fresh_state(pipe, 10.0, 0.0, 0.0)
    by_hand = s.copy()
    sim.decide(s, 0.8, pipe.points, pipe.cumulative, P)
    wx = 10.0 + 3.0 * math.cos(0.8 * math.pi / 2)
    wy = 3.0 * math.sin(0.8 * math.pi / 2)
    for _ in range(20):
        sim.closed_loop_rk4(by_hand, wx, wy, 0.0, True, 0.05, P)
    # equal but for the heading wrap to [-π, π), which may round the last bit
    assert_allclose(s[POSE], by_hand[POSE], rtol=1e-14, atol=1e-15)


def test_decide_wraps_the_heading():
    pipe = Pipeline(np.array([[0.0, 0.0], [-60.0, 0.0]]), "south")
    s = fresh_state(pipe, -10.0, 0.0, math.pi - 0.01)  # heading just short of south
    for _ in range(3):
        sim.decide(s, 1.0, pipe.points, pipe.cumulative, P)  # turn to starboard, past south
    assert -math.pi <= s[sim.PSI] < 0.0


def non_default_params():
    auv = AUVParams(*(1.0 + 0.37 * i for i in range(len(AUVParams._fields))))
    ctrl = ControllerParams(*(20.0 + 0.11 * i for i in range(len(ControllerParams._fields))))
    cam = CameraParams(1.7, 4.2)
    dist = Disturbance(
        0.2, 1.1, 30.0, 0.05, 0.25, 0.03, 0.1, 0.02, 0.004, (1.0, 3.0, 5.0, 7.0), (2.0, 4.0, 6.0, 8.0)
    )
    return sim.SimParams(
        auv,
        ctrl,
        cam,
        dt=0.02,
        substeps=13,
        lost_reward=-7.5,
        progress_back=1.25,
        progress_ahead=4.5,
        disturbance=dist,
        start_speed=0.3,
        end_at_pipe_end=False,
    )


def test_pack_unpack_round_trip():
    p = non_default_params()
    defaults = sim.PAPER_SIM
    # every field really differs from its default, so a swapped or dropped slot shows
    for group, default in zip(p[:3], defaults[:3], strict=True):
        assert all(a != b for a, b in zip(group, default, strict=True))
    assert all(a != b for a, b in zip(p[3:8], defaults[3:8], strict=True))
    assert all(a != b for a, b in zip(p.disturbance, defaults.disturbance, strict=True))
    start = sim.OFFSETS["disturbance"]
    slots = sim.pack_params(p)[start : start + PACKED_SIZE]
    assert len(set(slots)) == PACKED_SIZE == 17  # no two disturbance slots alike
    assert p.start_speed != defaults.start_speed and p.end_at_pipe_end != defaults.end_at_pipe_end
    packed = sim.pack_params(p)
    assert packed.dtype == np.float64 and packed.shape == (sim.OFFSETS["end_at_pipe_end"] + 1,)
    for name in ("dt", "substeps", "lost_reward", "progress_back", "progress_ahead", "start_speed"):
        assert packed[sim.OFFSETS[name]] == getattr(p, name)  # each scalar where its name says
    back = sim.unpack_params(packed)
    assert back == p
    assert isinstance(back.substeps, int) and back.end_at_pipe_end is False
    assert tuple(back.auv) == tuple(p.auv) and tuple(back.controller) == tuple(p.controller)


def test_decide_packed_matches_decide():
    pipe = straight_pipe()
    a = fresh_state(pipe, 10.0, 0.3, -0.2)
    b = a.copy()
    packed = sim.pack_params(P)
    for action in (0.4, -0.1, 0.0):
        ra = sim.decide(a, action, pipe.points, pipe.cumulative, P)
        rb = sim.decide_packed(b, action, pipe.points, pipe.cumulative, packed)
        assert ra == rb
    assert_array_equal(a, b)
