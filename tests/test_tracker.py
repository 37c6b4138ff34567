"""The pipe tracker: its Kalman steps against textbook and numerical answers, its gate, its misses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pipefollow.perception import line_ekf as ekf
from pipefollow.perception import track_step as ts
from pipefollow.perception.navigation import Navigation, NavParams
from pipefollow.perception.tracker import PipeTracker


def moved(px, py, dl, df, dpsi):
    """A world point's camera coordinates after the vehicle moved (Δl, Δf) and turned Δψ (to starboard)."""
    qx, qy = px - dl, py - df
    return math.cos(dpsi) * qx - math.sin(dpsi) * qy, math.sin(dpsi) * qx + math.cos(dpsi) * qy


def line_through(ax, ay, bx, by):
    """(θ, d) of the line a → b: θ from forward to starboard, d the offset along n = (cos θ, −sin θ)."""
    th = math.atan2(bx - ax, by - ay)
    return th, ax * math.cos(th) - ay * math.sin(th)


def test_prediction_moves_the_line_as_the_world_fixed_points_on_it_move():
    th, d = 0.3, 0.2
    T = ts.new_track()
    T[ts.TH], T[ts.D] = th, d
    dl, df, dpsi = 0.1, 0.5, 0.05
    ekf.predict(T, ts.TH, dl, df, dpsi, np.zeros(3), 0.0, 0.0)
    a = moved(*ekf.on_line(th, d, -1.0), dl, df, dpsi)
    b = moved(*ekf.on_line(th, d, 2.0), dl, df, dpsi)
    assert (T[ts.TH], T[ts.D]) == pytest.approx(line_through(*a, *b), abs=1e-12)


def test_prediction_covariance_is_the_jacobians_sandwich():
    # F P Fᵀ + G Σ Gᵀ + Q with F and G by central differences of the geometric motion
    th, d = -0.4, 0.35
    P = np.array([[0.01, 0.002], [0.002, 0.004]])
    motion = np.array([0.07, 0.45, -0.03])
    nav_var = np.array([1e-4, 2e-4, 3e-5])
    q_t, q_d = 0.002, 0.0005

    def f(x, m):
        a = moved(*ekf.on_line(x[0], x[1], -1.0), *m)
        b = moved(*ekf.on_line(x[0], x[1], 2.0), *m)
        return np.array(line_through(*a, *b))

    h = 1e-6
    x0 = np.array([th, d])
    F = np.column_stack([(f(x0 + h * e, motion) - f(x0 - h * e, motion)) / (2 * h) for e in np.eye(2)])
    G = np.column_stack([(f(x0, motion + h * e) - f(x0, motion - h * e)) / (2 * h) for e in np.eye(3)])
    expected = F @ P @ F.T + G @ np.diag(nav_var) @ G.T + np.diag([q_t, q_d])
    T = ts.new_track()
    T[ts.TH], T[ts.D], T[ts.P], T[ts.P + 1], T[ts.P + 2] = th, d, P[0, 0], P[0, 1], P[1, 1]
    ekf.predict(T, ts.TH, *motion, nav_var, q_t, q_d)
    got = np.array([[T[ts.P], T[ts.P + 1]], [T[ts.P + 1], T[ts.P + 2]]])
    np.testing.assert_allclose(got, expected, rtol=1e-6, atol=1e-12)


def test_line_update_is_the_textbook_kalman_step():
    T = ts.new_track()
    x = np.array([0.1, -0.05])
    P = np.array([[0.02, -0.003], [-0.003, 0.01]])
    T[ts.TH], T[ts.D], T[ts.P], T[ts.P + 1], T[ts.P + 2] = x[0], x[1], P[0, 0], P[0, 1], P[1, 1]
    z = np.array([0.16, 0.02])
    R = np.array([[0.004, -0.001], [-0.001, 0.003]])
    nu_t, nu_d, s_tt, s_td, s_dd, m2 = ekf.innovation(T, ts.TH, z[0], z[1], R[0, 0], R[0, 1], R[1, 1])
    S = P + R
    assert m2 == pytest.approx((z - x) @ np.linalg.solve(S, z - x), rel=1e-12)
    ekf.correct(T, ts.TH, nu_t, nu_d, s_tt, s_td, s_dd, R[0, 0], R[0, 1], R[1, 1])
    K = P @ np.linalg.inv(S)
    np.testing.assert_allclose([T[ts.TH], T[ts.D]], x + K @ (z - x), rtol=1e-12)
    P_post = (np.eye(2) - K) @ P
    np.testing.assert_allclose(
        [T[ts.P], T[ts.P + 1], T[ts.P + 2]], [P_post[0, 0], P_post[0, 1], P_post[1, 1]], rtol=1e-10
    )


def test_point_update_is_the_extended_kalman_step_of_a_point_on_the_line():
    th, d = 0.25, 0.1
    P = np.array([[0.01, 0.001], [0.001, 0.02]])
    p = np.array([0.3, 1.2])  # a detected end, off the line by a little
    sd = 0.05

    def r(x):  # the point's offset from the line
        return p[0] * math.cos(x[0]) - p[1] * math.sin(x[0]) - x[1]

    h = 1e-7
    x0 = np.array([th, d])
    J = np.array([(r(x0 + h * e) - r(x0 - h * e)) / (2 * h) for e in np.eye(2)])
    S = J @ P @ J + sd * sd
    K = P @ J / S
    T = ts.new_track()
    T[ts.TH], T[ts.D], T[ts.P], T[ts.P + 1], T[ts.P + 2] = th, d, P[0, 0], P[0, 1], P[1, 1]
    nu, j, s, m2 = ekf.point_innovation(T, ts.TH, p[0], p[1], sd)
    assert s == pytest.approx(S, rel=1e-6) and m2 == pytest.approx(r(x0) ** 2 / S, rel=1e-6)
    ekf.point_correct(T, ts.TH, nu, j, s)
    np.testing.assert_allclose([T[ts.TH], T[ts.D]], x0 - K * r(x0), rtol=1e-6)
    P_post = P - np.outer(K, K) * S
    np.testing.assert_allclose(
        [T[ts.P], T[ts.P + 1], T[ts.P + 2]], [P_post[0, 0], P_post[0, 1], P_post[1, 1]], rtol=1e-6
    )


def test_measured_line_covariance_matches_the_ends_noise():
    rng = np.random.default_rng(3)
    a, b, sd = np.array([0.2, 0.3]), np.array([-0.4, 2.8]), 0.05
    th0, d0, r_tt, r_td, r_dd = ekf.measured_line(*a, *b, sd)
    assert (th0, d0) == pytest.approx(line_through(*a, *b), abs=1e-12)
    n = 40_000
    ea, eb = a + sd * rng.standard_normal((n, 2)), b + sd * rng.standard_normal((n, 2))
    th = np.arctan2(eb[:, 0] - ea[:, 0], eb[:, 1] - ea[:, 1])
    d = ea[:, 0] * np.cos(th) - ea[:, 1] * np.sin(th)
    cov = np.cov(np.vstack([th, d]))
    np.testing.assert_allclose([cov[0, 0], cov[0, 1], cov[1, 1]], [r_tt, r_td, r_dd], rtol=0.05)


def straight_detections(tracker, frames, offset=0.1, step=0.5):
    """Frames of a straight pipe along the vehicle's axis ``offset`` m to starboard; the vehicle surges."""
    out = None
    for k in range(frames):
        pose = (k * step, 0.0, 0.0)  # heading north; camera x is east
        out = tracker.step(pose, True, (offset, 3.0, offset, 0.0)).copy()
    return out, (frames * step, 0.0, 0.0)


def quiet_tracker():
    nav = NavParams(dvl_sd=0.0, dvl_scale_sd=0.0, gyro_arw=0.0, gyro_bias_sd=0.0, gyro_bias_walk=0.0)
    t = PipeTracker(nav=nav, memory=None)  # the line alone (its memory: tests/test_piece_memory.py)
    t.reset(np.random.default_rng(0), (0.0, 0.0, 0.0))
    t.start()
    return t


def test_the_gate_rejects_a_detection_off_the_pipe_and_keeps_the_line():
    t = quiet_tracker()
    out, pose = straight_detections(t, 6)
    assert out[ts.OUT_IN_VIEW] == 1.0 and out[ts.OUT_X1] == pytest.approx(0.1, abs=1e-3)
    before = t.state[[ts.TH, ts.D]].copy()
    # a texture line parallel to the pipe, 0.6 m to port: rejected, the observation stays on the pipe
    out = t.step(pose, True, (-0.5, 3.0, -0.5, 0.0))
    assert t.event == ts.REJECTED
    np.testing.assert_allclose(t.state[[ts.TH, ts.D]], before, atol=1e-12)
    assert out[ts.OUT_IN_VIEW] == 1.0 and out[ts.OUT_X1] == pytest.approx(0.1, abs=1e-3)


def test_swapped_ends_are_put_back_in_the_pipes_direction():
    t = quiet_tracker()
    _, pose = straight_detections(t, 6, offset=0.0)
    # the pipe turns slightly to starboard ahead; the detector gives its ends the wrong way round
    out = t.step(pose, True, (0.0, 0.0, 0.15, 3.0))
    assert t.event == ts.ACCEPTED
    assert out[ts.OUT_Y1] == pytest.approx(3.0, abs=1e-6) and out[ts.OUT_X1] > 0.05
    assert out[ts.OUT_Y_NEAR] == pytest.approx(0.0, abs=1e-6)


def test_uncertainty_grows_through_misses_until_the_pipe_is_lost():
    t = quiet_tracker()
    _, pose = straight_detections(t, 6)
    variances, confidences, seen = [], [], []
    for k in range(1, 7):
        out = t.step((pose[0] + 0.5 * k, 0.0, 0.0), False, (0.0, 0.0, 0.0, 0.0))
        variances.append(t.state[ts.P + 2])
        confidences.append(t.confidence)
        seen.append(out[ts.OUT_IN_VIEW])
    m = int(t.params.max_misses)
    assert all(b > a for a, b in zip(variances[:m], variances[1 : m + 1], strict=True))
    assert all(b <= a for a, b in zip(confidences[:-1], confidences[1:], strict=True))
    assert confidences[m - 1] < confidences[0]
    assert seen[:m] == [1.0] * m and seen[m:] == [0.0] * (6 - m)  # carried max_misses frames, then lost
    # while carried, the prediction stays on the pipe (straight, the vehicle on it)
    assert t.state[ts.ACTIVE] == 0.0


def test_a_corner_seen_ahead_is_shown_by_its_far_end_beyond_the_bend():
    t = quiet_tracker()
    _, pose = straight_detections(t, 6, offset=0.0)
    # the pipe runs ahead to a corner at 1.5 m and turns 135° to port, out of view at the left border
    out = t.step(pose, True, (-1.0, 0.5, 0.0, 0.0))
    assert t.event == ts.BEND
    assert (out[ts.OUT_X1], out[ts.OUT_Y1]) == pytest.approx((-1.0, 0.5))
    # a frame in which the detector stops at the corner keeps the far end beyond it
    out = t.step(pose, True, (0.0, 1.5, 0.0, 0.0))
    assert (out[ts.OUT_X1], out[ts.OUT_Y1]) == pytest.approx((-1.0, 0.5))


def test_a_bend_ends_the_line_at_its_corner_and_the_search_turns_towards_the_far_end():
    t = quiet_tracker()
    _, (x0, y0, psi) = straight_detections(t, 6, offset=0.0)
    # the pipe runs ahead to a corner at 1.5 m and turns 90° to starboard, out of view at the right border
    out = t.step((x0, y0, psi), True, (1.0, 1.5, 0.0, 0.0))
    assert t.event == ts.BEND
    # a right-angle corner is the far end's foot on the line
    assert t.state[ts.HAS_END] == 1.0
    assert (t.state[ts.END_X], t.state[ts.END_Y]) == pytest.approx((0.0, 1.5), abs=1e-9)
    # 1 m on, the corner 0.5 m ahead: the far end beyond it still shows
    out = t.step((x0 + 1.0, y0, psi), False, (0.0, 0.0, 0.0, 0.0))
    assert out[ts.OUT_IN_VIEW] == 1.0 and (out[ts.OUT_X1], out[ts.OUT_Y1]) == pytest.approx((1.0, 0.5))
    # 2 m on, the corner 0.5 m behind the view and the far end out of it: the first leg's extension
    # ahead is no pipe, so nothing is in view, and the search turns to starboard, where the pipe went
    out = t.step((x0 + 2.0, y0, psi), False, (0.0, 0.0, 0.0, 0.0))
    assert out[ts.OUT_IN_VIEW] == 0.0 and out[ts.OUT_SIDE] == 1.0


@pytest.mark.parametrize("edge_misses", [2, 5])
def test_a_short_piece_at_the_views_corner_is_carried_through_edge_misses_frames(edge_misses):
    nav = NavParams(dvl_sd=0.0, dvl_scale_sd=0.0, gyro_arw=0.0, gyro_bias_sd=0.0, gyro_bias_walk=0.0)
    t = PipeTracker(nav=nav, params=ts.TRACK._replace(edge_misses=edge_misses), memory=None)
    t.reset(np.random.default_rng(0), (0.0, 0.0, 0.0))
    pose = (0.0, 0.0, 0.0)  # the vehicle holds still: the piece stays where it is
    # the pipe crosses the footprint's lower right corner: 0.5 m of it in view, from (0.6, 0) to (1, 0.3)
    for _ in range(3):
        out = t.step(pose, True, (1.0, 0.3, 0.6, 0.0))
    assert out[ts.OUT_IN_VIEW] == 1.0
    seen = [t.step(pose, False, (0.0, 0.0, 0.0, 0.0))[ts.OUT_IN_VIEW] for _ in range(7)]
    assert seen == [1.0] * edge_misses + [0.0] * (7 - edge_misses)
    # with its memory the tracker goes on showing the piece it took, still in view, once the line is lost
    t = PipeTracker(nav=nav, params=ts.TRACK._replace(edge_misses=edge_misses))
    t.reset(np.random.default_rng(0), pose)
    for _ in range(3):
        t.step(pose, True, (1.0, 0.3, 0.6, 0.0))
    shown = [t.step(pose, False, (0.0, 0.0, 0.0, 0.0))[:5].copy() for _ in range(7)]
    np.testing.assert_allclose(shown[-1], [1.0, 1.0, 0.3, 0.6, 0.0], atol=0.02)
    # a long piece (the pipe straight ahead, 3 m in view) is lost after max_misses frames whatever edge_misses
    t = PipeTracker(nav=nav, params=ts.TRACK._replace(edge_misses=edge_misses), memory=None)
    t.reset(np.random.default_rng(0), pose)
    for _ in range(3):
        t.step(pose, True, (0.0, 3.0, 0.0, 0.0))
    seen = [t.step(pose, False, (0.0, 0.0, 0.0, 0.0))[ts.OUT_IN_VIEW] for _ in range(4)]
    assert seen == [1.0] * ts.TRACK.max_misses + [0.0] * (4 - ts.TRACK.max_misses)


def test_navigation_without_errors_reports_the_true_motion():
    nav = Navigation(
        NavParams(dvl_sd=0.0, dvl_scale_sd=0.0, gyro_arw=0.0, gyro_bias_sd=0.0, gyro_bias_walk=0.0)
    )
    nav.reset(np.random.default_rng(1))
    psi = math.radians(30.0)
    before, after = (1.0, 2.0, psi), (1.0 + 0.4, 2.0 + 0.3, psi + 0.1)
    dl, df, dpsi = nav.motion(before, after)
    # forward along (cos ψ, sin ψ), starboard along (−sin ψ, cos ψ)
    assert df == pytest.approx(0.4 * math.cos(psi) + 0.3 * math.sin(psi))
    assert dl == pytest.approx(-0.4 * math.sin(psi) + 0.3 * math.cos(psi))
    assert dpsi == pytest.approx(0.1)


def test_navigation_errors_come_from_the_seeded_generator_and_have_their_spread():
    def run(seed):
        nav = Navigation()
        nav.reset(np.random.default_rng(seed))
        return np.array([nav.motion((0.0, 0.0, 0.0), (0.5, 0.0, 0.0)).copy() for _ in range(4000)])

    a, b = run(7), run(7)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, run(8))
    nav = Navigation()
    # the lateral error of a 0.5 m surge: the pings' noise only (no heading error within a step)
    assert np.std(a[:, 0]) == pytest.approx(nav.disp_sd, rel=0.1)


def direction_of(out):
    """The observation's direction from its near end to its far end (rad from forward to starboard)."""
    return math.atan2(out[ts.OUT_X1] - out[ts.OUT_X2], out[ts.OUT_Y1] - out[ts.OUT_Y_NEAR])


@pytest.mark.parametrize("swapped", [False, True])
def test_a_line_that_replaces_a_contradicted_one_keeps_the_pipes_way(swapped):
    # the tracked line runs straight ahead; the detector sees the pipe elsewhere, crossing that line
    # on the piece it sees (two thirds of the way along): no corner, so the new line keeps the
    # forward way, whichever way round the detector gives the ends
    t = quiet_tracker()
    _, pose = straight_detections(t, 6, offset=0.0)
    near, far = (-0.9, 0.3), (0.6, 2.3)
    det = (*near, *far) if swapped else (*far, *near)  # (x1, y1, x2, y_near): far end first
    t.step(pose, True, det)
    assert t.event == ts.REJECTED
    out = t.step(pose, True, det)
    assert t.event == ts.REPLACED
    assert direction_of(out) == pytest.approx(math.atan2(1.5, 2.0), abs=1e-9)
    assert t.state[ts.TH] == pytest.approx(math.atan2(1.5, 2.0), abs=1e-9)
    assert (out[ts.OUT_X2], out[ts.OUT_Y_NEAR]) == pytest.approx(near)


def test_the_leg_after_a_hook_runs_away_from_its_corner():
    # the pipe turns 135° to port at a corner 2 m ahead, out of the piece seen: after the line is
    # lost, the next leg (its ends given the wrong way round) runs from the corner, back to port
    t = quiet_tracker()
    _, pose = straight_detections(t, 6, offset=0.0)
    for _ in range(int(t.params.max_misses) + 1):
        t.step(pose, False, (0.0, 0.0, 0.0, 0.0))
    assert t.state[ts.ACTIVE] == 0.0
    out = t.step(pose, True, (-0.3, 1.7, -1.0, 1.0))
    assert t.event == ts.STARTED
    assert direction_of(out) == pytest.approx(math.radians(-135.0), abs=1e-9)
    assert (out[ts.OUT_X2], out[ts.OUT_Y_NEAR]) == pytest.approx((-0.3, 1.7))


def test_a_far_end_beyond_a_bend_does_not_turn_a_parallel_line_back():
    # a corner seen ahead leaves a far end beyond the bend at the left border; the next line, the
    # pipe 0.6 m to port and parallel to the tracked one, does not run through that far end, so it
    # takes the tracked line's way (ordered by the far end, it ran backwards)
    t = quiet_tracker()
    _, pose = straight_detections(t, 6, offset=0.0)
    t.step(pose, True, (-1.0, 0.5, 0.0, 0.0))
    assert t.event == ts.BEND
    det = (-0.6, 3.0, -0.6, 0.0)
    t.step(pose, True, det)
    assert t.event == ts.REJECTED
    out = t.step(pose, True, det)
    assert t.event == ts.REPLACED
    assert direction_of(out) == pytest.approx(0.0, abs=1e-9)
    assert out[ts.OUT_Y1] == pytest.approx(3.0) and out[ts.OUT_Y_NEAR] == pytest.approx(0.0)


@pytest.mark.parametrize("order", ["far first", "near first"])
def test_a_hooks_next_leg_running_back_beside_the_first_runs_towards_the_far_end_beyond_the_bend(order):
    # the tracked line runs straight ahead; a bend leaves the far end beyond it at (-1.0, 0.5). The
    # next leg seen alone runs from the corner (0.0, 3.0) back to that far end, 21.8 degrees from
    # the tracked line's way reversed: near parallel to the line, yet the pipe runs on towards the
    # far end beyond the bend (taking the line's way, the vehicle followed the hook's leg backwards)
    t = quiet_tracker()
    _, pose = straight_detections(t, 6, offset=0.0)
    t.step(pose, True, (-1.0, 0.5, 0.0, 0.0))
    assert t.event == ts.BEND
    corner, far = (0.0, 3.0), (-1.0, 0.5)
    out = t.step(pose, True, (*far, *corner) if order == "far first" else (*corner, *far))
    assert t.event == ts.REPLACED
    assert (out[ts.OUT_X1], out[ts.OUT_Y1]) == pytest.approx(far, abs=1e-6)
    assert (out[ts.OUT_X2], out[ts.OUT_Y_NEAR]) == pytest.approx(corner, abs=1e-6)
    assert direction_of(out) == pytest.approx(math.atan2(-1.0, -2.5), abs=1e-9)


@pytest.mark.parametrize("swapped", [False, True])
def test_after_a_lost_line_a_piece_it_crosses_runs_from_the_end_nearer_the_vehicle(swapped):
    # the line is lost; the pipe is seen again crossing the carried line halfway along the piece:
    # no corner there, so the pipe comes from the piece's end nearer the vehicle
    t = quiet_tracker()
    _, pose = straight_detections(t, 6, offset=0.0)
    for _ in range(int(t.params.max_misses) + 1):
        t.step(pose, False, (0.0, 0.0, 0.0, 0.0))
    assert t.state[ts.ACTIVE] == 0.0
    near, far = (0.8, 0.5), (-0.7, 2.5)
    out = t.step(pose, True, (*near, *far) if swapped else (*far, *near))
    assert t.event == ts.STARTED
    assert direction_of(out) == pytest.approx(math.atan2(-1.5, 2.0), abs=1e-9)
    assert (out[ts.OUT_X2], out[ts.OUT_Y_NEAR]) == pytest.approx(near)


def still_detections(tracker, det, frames=3, pose=(0.0, 0.0, 0.0)):
    """Frames of the same detection from a vehicle that does not move."""
    for _ in range(frames):
        tracker.step(pose, True, det)
    return pose


@pytest.mark.parametrize("swapped", [False, True])
def test_a_pipe_crossed_where_the_line_grazes_the_side_runs_from_the_near_border(swapped):
    # the tracked line grazes the starboard side: it enters the view there at (1.0, 1.0) and runs
    # ahead to (0.9, 3.0). The pipe seen now comes from under the vehicle at (0.7, 0.0), off the
    # line, and leaves the view where the line enters it: no bend ahead (the end off the line lies
    # 0.98 m behind the other along the line), so the piece runs from (0.7, 0.0), the line's way.
    # It leaves the view by the side, so the piece seen is the pipe in view: the line starts again
    # from it (its direction atan2(0.3, 1.0), not the old line's atan2(-0.1, 2.0))
    t = quiet_tracker()
    pose = still_detections(t, (0.9, 3.0, 1.0, 1.0))
    th = math.atan2(-0.1, 2.0)
    assert t.state[ts.TH] == pytest.approx(th, abs=1e-9)
    near, far = (0.7, 0.0), (1.0, 1.0)
    out = t.step(pose, True, (*near, *far) if swapped else (*far, *near))
    assert t.event == ts.ACCEPTED and t.state[ts.HAS_FAR] == 0.0
    assert (out[ts.OUT_X2], out[ts.OUT_Y_NEAR]) == pytest.approx(near)
    assert (out[ts.OUT_X1], out[ts.OUT_Y1]) == pytest.approx(far, abs=1e-6)
    assert t.state[ts.TH] == pytest.approx(math.atan2(0.3, 1.0), abs=1e-9)


@pytest.mark.parametrize("swapped", [False, True])
def test_a_crossed_piece_whose_end_on_the_line_lies_inside_the_view_keeps_the_line(swapped):
    # the tracked line enters the view by the port side at (-1.0, 1.0) and runs to (-0.5, 3.0). The
    # pipe seen comes from under the vehicle at (-0.3, 0.0), off the line, 1.2 m behind the other
    # end along it, and that end, (-0.9, 1.4), lies on the line 0.1 m inside the side: the pipe goes
    # on along the line past it, so the line is kept (corrected through that end), not started again
    # from the piece (whose direction would be atan2(-0.6, 1.4))
    t = quiet_tracker()
    pose = still_detections(t, (-0.5, 3.0, -1.0, 1.0))
    th = math.atan2(0.5, 2.0)
    assert t.state[ts.TH] == pytest.approx(th, abs=1e-9)
    near, far = (-0.3, 0.0), (-0.9, 1.4)
    out = t.step(pose, True, (*near, *far) if swapped else (*far, *near))
    assert t.event == ts.ACCEPTED and t.state[ts.HAS_FAR] == 0.0
    assert t.state[ts.TH] == pytest.approx(th, abs=1e-6)
    assert (out[ts.OUT_X2], out[ts.OUT_Y_NEAR]) == pytest.approx(near)
    assert (out[ts.OUT_X1], out[ts.OUT_Y1]) == pytest.approx(far, abs=1e-6)


@pytest.mark.parametrize("far", [(1.0, 0.15), (1.0, 0.08), (1.0, 0.0)])
def test_a_hooks_far_end_behind_the_near_end_is_a_bend_unless_it_lies_on_the_near_border(far):
    # the tracked line runs from (0, 0) ahead to port, to (-1.0, 1.5); the pipe seen now turns back
    # at the near end to the starboard side, 0.45–0.55 m behind it along the line. At the side
    # (0.15 m ahead of the near border) it is a hook's far end beyond the bend; on the near border it
    # is where the pipe comes from under the vehicle, the line's end its far one; 8 cm ahead of it
    # too: a half-buried pipe's visible half ends a quarter diameter (6 cm) beside its axis
    t = quiet_tracker()
    pose = still_detections(t, (-1.0, 1.5, 0.0, 0.0))
    out = t.step(pose, True, (*far, 0.0, 0.0))
    if far[1] > 0.12:
        assert t.event == ts.BEND
        assert (out[ts.OUT_X1], out[ts.OUT_Y1]) == pytest.approx(far)
        assert (out[ts.OUT_X2], out[ts.OUT_Y_NEAR]) == pytest.approx((0.0, 0.0))
    else:
        assert t.event == ts.ACCEPTED
        assert (out[ts.OUT_X2], out[ts.OUT_Y_NEAR]) == pytest.approx(far)
        assert (out[ts.OUT_X1], out[ts.OUT_Y1]) == pytest.approx((-1.0, 1.5), abs=1e-6)


@pytest.mark.parametrize("swapped", [False, True])
@pytest.mark.parametrize("frame", [ts.CLEAR_FRAME, ts.UNSEARCHED_FRAME])
def test_a_line_running_back_joined_from_the_near_border_is_where_the_pipe_comes_from(frame, swapped):
    # the tracked line runs back towards the vehicle, from (0.2, 3.0) to the starboard side at
    # (1.0, 1.0) (a hook's next leg, as a sonar looking ahead sees it before the corner). The piece
    # seen now joins it at the side from under the vehicle, (0.0, 0.0): the first leg, where the pipe
    # comes from. In a frame left to the sonar the end off the line on the near border says so
    # (_crossed); in a searched frame, as well, the end on the line where the line leaves the view
    # (_leaves_on_line; before it, a bend whose far end lay under the vehicle). The piece runs from
    # (0.0, 0.0) and, leaving the view by the side, starts the line again (direction 45°)
    t = quiet_tracker()
    pose = still_detections(t, (1.0, 1.0, 0.2, 3.0))
    assert t.state[ts.TH] == pytest.approx(math.atan2(0.8, -2.0), abs=1e-9)
    near, far = (0.0, 0.0), (1.0, 1.0)
    out = t.step(pose, True, (*near, *far) if swapped else (*far, *near), frame=frame)
    assert t.event == ts.ACCEPTED and t.state[ts.HAS_FAR] == 0.0
    assert (out[ts.OUT_X2], out[ts.OUT_Y_NEAR]) == pytest.approx(near)
    assert (out[ts.OUT_X1], out[ts.OUT_Y1]) == pytest.approx(far, abs=1e-6)
    assert t.state[ts.TH] == pytest.approx(math.radians(45.0), abs=1e-9)


@pytest.mark.parametrize("swapped", [False, True])
def test_a_corner_the_vehicle_is_over_runs_from_its_end_inside_the_view_to_where_the_line_leaves(swapped):
    # the tracked line (a hook's next leg) enters the view at (-0.5, 0.0) and leaves it by the port
    # side at (-1.0, 0.3). The piece seen runs from that exit to (0.6, 0.2), inside the view: the
    # corner the vehicle is over (its first leg, under the vehicle, not seen). Its end on the line
    # is nearer the line's entry (0.58 m) than the other (1.12 m), which made it a bend's near end
    # with its far end at the corner; but it lies where the line leaves the view, so the pipe
    # comes from the corner and the piece, leaving by the side, starts the line again
    t = quiet_tracker()
    pose = still_detections(t, (-1.0, 0.3, -0.5, 0.0))
    assert t.state[ts.TH] == pytest.approx(math.atan2(-0.5, 0.3), abs=1e-9)
    near, far = (0.6, 0.2), (-1.0, 0.3)
    out = t.step(pose, True, (*near, *far) if swapped else (*far, *near))
    assert t.event == ts.ACCEPTED and t.state[ts.HAS_FAR] == 0.0
    assert (out[ts.OUT_X2], out[ts.OUT_Y_NEAR]) == pytest.approx(near)
    assert (out[ts.OUT_X1], out[ts.OUT_Y1]) == pytest.approx(far, abs=1e-6)
    assert t.state[ts.TH] == pytest.approx(math.atan2(-1.6, 0.1), abs=1e-9)


@pytest.mark.parametrize("off", [(-0.2, 3.0), (0.95, 1.5)])
def test_a_piece_from_where_the_line_leaves_back_to_the_far_border_or_a_side_is_a_bend(off):
    # the same line; the piece runs from its exit to the far border or the starboard side, where a
    # pipe that left the view by the line's exit may come back in: a bend beyond the view, the end
    # on the line the near one and the other the far end beyond the bend, as before
    t = quiet_tracker()
    pose = still_detections(t, (-1.0, 0.3, -0.5, 0.0))
    out = t.step(pose, True, (*off, -1.0, 0.3))
    assert t.event == ts.BEND
    assert (out[ts.OUT_X1], out[ts.OUT_Y1]) == pytest.approx(off)
