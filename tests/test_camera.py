"""The camera footprint (docs/design.md): clipping, the visible piece, and the tracking errors.

Footprint: lateral x ∈ [-1, 1] m (positive to starboard), forward y ∈ [0, 3] m. The earth frame
is x north, y east, so an AUV heading north (ψ = 0) sees east as +x and north as +y.
"""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from pipefollow.sim.camera import (
    PAPER_CAMERA,
    CameraParams,
    clip_segment,
    observe,
    to_camera,
    tracking_errors,
)
from pipefollow.sim.pipeline import Pipeline


def view(points, x, y, psi, progress=None, cam=PAPER_CAMERA):
    pipe = Pipeline(np.array(points, dtype=float))
    if progress is None:
        progress = pipe.project(x, y)[0]
    in_view, x1, y1, x2, y_near, s_near, s_far = observe(
        pipe.points, pipe.cumulative, x, y, psi, progress, cam
    )
    return in_view, np.array([x1, y1, x2, y_near]), (s_near, s_far)


def test_paper_footprint():
    assert PAPER_CAMERA == CameraParams(1.0, 3.0)


@pytest.mark.parametrize(
    ("point", "pose", "expected"),
    [
        ((2.0, 0.0), (0.0, 0.0, 0.0), (0.0, 2.0)),  # ahead
        ((0.0, 1.0), (0.0, 0.0, 0.0), (1.0, 0.0)),  # east is starboard when heading north
        ((0.0, 1.0), (0.0, 0.0, math.pi / 2), (0.0, 1.0)),  # heading east: east is ahead
        ((1.0, 0.0), (0.0, 0.0, math.pi / 2), (-1.0, 0.0)),  # heading east: north is port
        ((3.0, 3.0), (1.0, 1.0, math.pi / 4), (0.0, 2 * math.sqrt(2))),
    ],
)
def test_to_camera(point, pose, expected):
    assert_allclose(to_camera(*point, *pose), expected, atol=1e-12)


BOX = (-1.0, 1.0, 0.0, 3.0)


@pytest.mark.parametrize(
    ("seg", "expected"),
    [
        ((-0.5, 0.5, 0.5, 2.5), (0.0, 1.0)),  # fully inside
        ((-2.0, 1.0, 2.0, 1.0), (0.25, 0.75)),  # crossing left to right
        ((0.0, -1.0, 0.0, 4.0), (0.2, 0.8)),  # crossing bottom to top
        ((0.0, 1.0, 0.0, 5.0), (0.0, 0.5)),  # leaving through the top
        ((2.0, 1.0, 0.0, 1.0), (0.5, 1.0)),  # entering through the right side
        ((-3.0, 0.0, 1.0, 4.0), (0.5, 0.75)),  # in through the left side at (-1, 2), out the top at (0, 3)
        ((-2.0, 1.0, 0.0, -1.0), (0.5, 0.5)),  # touches the corner (-1, 0) only
    ],
)
def test_clip_segment_visible(seg, expected):
    t0, t1 = clip_segment(*seg, *BOX)
    assert t0 <= t1
    assert_allclose((t0, t1), expected, atol=1e-12)


@pytest.mark.parametrize(
    "seg",
    [
        (2.0, 0.0, 3.0, 3.0),  # off to starboard
        (2.0, 0.0, 2.0, 3.0),  # parallel to the side, outside
        (-0.5, -2.0, 0.5, -0.1),  # behind
        (-0.5, 3.5, 0.5, 5.0),  # beyond the far edge
        (0.5, -1.0, 2.0, 0.5),  # passes outside the corner (1, 0): at y = 0 it is at x = 1.5
    ],
)
def test_clip_segment_outside(seg):
    t0, t1 = clip_segment(*seg, *BOX)
    assert t0 > t1


def test_straight_pipe_centred():
    # AUV on a north-going pipe, heading along it
    in_view, obs, (s_near, s_far) = view([[-10.0, 0.0], [10.0, 0.0]], 0.0, 0.0, 0.0)
    assert in_view
    assert_allclose(obs, [0.0, 3.0, 0.0, 0.0], atol=1e-12)
    assert_allclose((s_near, s_far), (10.0, 13.0), atol=1e-12)
    assert_allclose(tracking_errors(*obs), (0.0, 0.0), atol=1e-12)


def test_straight_pipe_offset_to_port():
    # AUV 0.5 m west (to port) of the pipe: the pipe appears 0.5 m to starboard
    in_view, obs, _ = view([[-10.0, 0.0], [10.0, 0.0]], 0.0, -0.5, 0.0)
    assert in_view
    assert_allclose(obs, [0.5, 3.0, 0.5, 0.0], atol=1e-12)
    assert_allclose(tracking_errors(*obs), (0.5, 0.0), atol=1e-12)


def test_straight_pipe_heading_south():
    # heading south, port is east: an AUV 0.3 m west of a south-going pipe sees it at x = -0.3
    in_view, obs, _ = view([[10.0, 0.0], [-10.0, 0.0]], 0.0, -0.3, math.pi)
    assert in_view
    assert_allclose(obs, [-0.3, 3.0, -0.3, 0.0], atol=1e-12)


def test_angled_pipe_leaves_through_the_top():
    # heading 10° to starboard of a north-going pipe through the AUV: in the camera the pipe
    # runs along (-sin 10°, cos 10°) and meets the far edge y = 3 at x = -3 tan 10°
    theta = math.radians(10.0)
    in_view, obs, _ = view([[-10.0, 0.0], [10.0, 0.0]], 0.0, 0.0, theta)
    assert in_view
    assert_allclose(obs, [-3.0 * math.tan(theta), 3.0, 0.0, 0.0], atol=1e-12)
    e_dist, e_angl = tracking_errors(*obs)
    assert e_dist == pytest.approx(-1.5 * math.tan(theta))
    assert e_angl == pytest.approx(-theta)


def test_angled_pipe_leaves_through_the_side():
    # at 20° the line x = -y tan 20° reaches x = -1 before y = 3: exit at (-1, cot 20°) = (-1, 2.7475)
    theta = math.radians(20.0)
    in_view, obs, _ = view([[-10.0, 0.0], [10.0, 0.0]], 0.0, 0.0, theta)
    assert in_view
    assert_allclose(obs, [-1.0, 1.0 / math.tan(theta), 0.0, 0.0], atol=1e-12)
    assert obs[1] == pytest.approx(2.7474774)
    assert tracking_errors(*obs)[1] == pytest.approx(-theta)


@pytest.mark.parametrize(("side", "x1"), [(-1.0, -1.0), (1.0, 1.0)])
def test_corner_inside_the_view(side, x1):
    # pipe north to (1.5, 0), then a 90° turn (west for side -1, east for +1): in the camera it
    # runs up the centre to y = 1.5, then sideways to the footprint's side edge
    points = [[-5.0, 0.0], [1.5, 0.0], [1.5, side * 10.0]]
    in_view, obs, (s_near, s_far) = view(points, 0.0, 0.0, 0.0)
    assert in_view
    assert_allclose(obs, [x1, 1.5, 0.0, 0.0], atol=1e-12)
    assert_allclose((s_near, s_far), (5.0, 7.5), atol=1e-12)  # one piece across the corner
    e_dist, e_angl = tracking_errors(*obs)
    assert e_dist == pytest.approx(x1 / 2)
    assert e_angl == pytest.approx(math.atan2(x1, 1.5))


def test_angled_pipe_at_45_degrees():
    # heading north-east over a north-going pipe: in the camera the pipe runs along
    # (-sin 45°, cos 45°) and leaves through the port side at (-1, 1)
    in_view, obs, _ = view([[-10.0, 0.0], [10.0, 0.0]], 0.0, 0.0, math.pi / 4)
    assert in_view
    assert_allclose(obs, [-1.0, 1.0, 0.0, 0.0], atol=1e-12)


def test_pipe_entering_through_a_side_edge():
    # the pipe comes from the west 1 m ahead of the AUV and turns north at (1, 0): in the camera
    # it enters through the port edge at (-1, 1), runs to (0, 1), then straight up to (0, 3)
    points = [[1.0, -5.0], [1.0, 0.0], [10.0, 0.0]]
    in_view, obs, (s_near, s_far) = view(points, 0.0, 0.0, 0.0)
    assert in_view
    assert_allclose(obs, [0.0, 3.0, -1.0, 1.0], atol=1e-12)
    assert_allclose((s_near, s_far), (4.0, 7.0), atol=1e-12)
    e_dist, e_angl = tracking_errors(*obs)
    assert e_dist == pytest.approx(-0.5)
    assert e_angl == pytest.approx(math.atan2(1.0, 2.0))


U_PIPE = [[-5.0, 0.0], [5.0, 0.0], [5.0, 0.8], [-5.0, 0.8]]  # up at y = 0, back down at y = 0.8


def test_u_pipe_on_the_outbound_leg_sees_the_outbound_piece():
    # both legs cross the view; the return leg (x = 0.8, s ∈ [12.8, 15.8]) is further along the
    # pipe than the AUV's progress (s = 5), so the outbound piece (s ∈ [5, 8]) is chosen
    in_view, obs, (s_near, s_far) = view(U_PIPE, 0.0, 0.0, 0.0, progress=5.0)
    assert in_view
    assert_allclose(obs, [0.0, 3.0, 0.0, 0.0], atol=1e-12)
    assert_allclose((s_near, s_far), (5.0, 8.0), atol=1e-12)


def test_u_pipe_on_the_return_leg_sees_the_return_piece():
    # now on the return leg heading south: the outbound leg appears at x = +0.8 (west is
    # starboard) but lies behind the progress (s = 15.8); the return piece continues from it
    in_view, obs, (s_near, s_far) = view(U_PIPE, 0.0, 0.8, math.pi, progress=15.8)
    assert in_view
    assert_allclose(obs, [0.0, 3.0, 0.0, 0.0], atol=1e-12)
    assert_allclose((s_near, s_far), (15.8, 18.8), atol=1e-12)


def test_u_pipe_near_the_turn_sees_one_piece_round_the_turn():
    # AUV 1 m short of the turn (progress 9): the outbound leg to s = 10, the 0.8-m connector and
    # the return leg down to the footprint's bottom edge (s = 11.8) form one piece
    in_view, obs, (s_near, s_far) = view(U_PIPE, 4.0, 0.0, 0.0, progress=9.0)
    assert in_view
    assert_allclose(obs, [0.8, 0.0, 0.0, 0.0], atol=1e-12)  # far end on the bottom edge
    assert_allclose((s_near, s_far), (9.0, 11.8), atol=1e-12)


def test_pipe_out_of_view():
    in_view, obs, (s_near, s_far) = view([[-10.0, 0.0], [10.0, 0.0]], 0.0, 5.0, 0.0)
    assert not in_view
    assert_allclose(obs, 0.0)
    # behind the AUV only
    in_view, _, _ = view([[-10.0, 0.0], [-1.0, 0.0]], 0.0, 0.0, 0.0, progress=9.0)
    assert not in_view
    # beside it, just outside the half-width
    in_view, _, _ = view([[-10.0, 0.0], [10.0, 0.0]], 0.0, -1.01, 0.0)
    assert not in_view


def test_tracking_errors_formula():
    # e_dist = (x1 + x2)/2, e_angl = atan2(x1 - x2, y1 - y_near)
    assert_allclose(tracking_errors(0.6, 2.0, -0.2, 0.5), (0.2, math.atan2(0.8, 1.5)), atol=1e-15)
    assert_allclose(tracking_errors(0.6, 2.0, -0.2, 0.5), (0.2, 0.4899573263), atol=1e-9)
    assert_allclose(tracking_errors(-1.0, 0.0, 1.0, 0.0), (0.0, -math.pi / 2), atol=1e-15)
    assert_allclose(tracking_errors(0.4, 3.0, 0.4, 0.0), (0.4, 0.0), atol=1e-15)


def test_angle_error_is_a_line_angle_whichever_way_the_pipe_runs():
    # a pipe running backwards through the frame, tilted 30° from vertical: the line deviates by 30°
    dx, dy = math.sin(math.radians(30.0)), math.cos(math.radians(30.0))
    _, forward = tracking_errors(dx, 2.0 + dy, 0.0, 2.0)
    _, backward = tracking_errors(-dx, 2.0 - dy, 0.0, 2.0)
    assert forward == pytest.approx(math.radians(30.0))
    assert backward == pytest.approx(math.radians(30.0))
    _, flipped = tracking_errors(dx, 2.0 - dy, 0.0, 2.0)
    assert flipped == pytest.approx(-math.radians(30.0))
    # the worst in-view reward of eq. 19 then stays above the lost-pipe penalty (paper §4)
    assert -(1.0 + (math.pi / 2) ** 2 + 4.0 + 0.5) > -10.0
