"""The perception page's figures: their geometry against hand-computed values, and what they show."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pipefollow.evaluation import perception_figures as pf
from pipefollow.sim.camera import to_camera


def test_camera_and_world_frames_are_inverse_and_oriented_as_the_simulator():
    # heading east (ψ = 90°): forward is east, starboard is south
    pose = (10.0, 5.0, math.pi / 2)
    north, east = pf.to_world(pose, [1.0, 0.0], [0.0, 2.0])
    np.testing.assert_allclose(north, [9.0, 10.0], atol=1e-12)  # 1 m to starboard: 1 m south
    np.testing.assert_allclose(east, [5.0, 7.0], atol=1e-12)  # 2 m ahead: 2 m east
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=5), rng.normal(size=5)
    pose = (1.0, -2.0, 0.7)
    back = to_camera(*pf.to_world(pose, x, y), *pose)  # the simulator's own transform
    np.testing.assert_allclose(back, (x, y), atol=1e-12)


def test_the_true_lateral_offset_of_a_straight_pipe():
    # a pipe running north along east = 0.3 m, the vehicle at the origin heading north: 0.3 m to starboard
    pts = np.array([[-10.0, 0.3], [10.0, 0.3]])
    assert pf.lateral_at(pts, (0.0, 0.0, 0.0)) == pytest.approx(0.3)
    # heading 10° to starboard of the pipe: 1.5 m ahead it lies 0.3/cos 10° − 1.5 tan 10° across the view
    psi = math.radians(10.0)
    expected = 0.3 / math.cos(psi) - 1.5 * math.tan(psi)
    assert pf.lateral_at(pts, (0.0, 0.0, psi)) == pytest.approx(expected, abs=1e-12)
    # a pipe behind the vehicle only: nowhere ahead
    assert math.isnan(pf.lateral_at(np.array([[-10.0, 0.0], [-5.0, 0.0]]), (0.0, 0.0, 0.0)))


def test_a_tracked_lines_lateral_offset_and_its_sd():
    # θ = 0: the line x = d, its s.d. that of d
    cov = np.array([[0.01, 0.0], [0.0, 0.04]])
    x, sd = pf.line_lateral(0.0, 0.25, cov)
    assert x == pytest.approx(0.25) and sd == pytest.approx(math.sqrt(0.04 + pf.Y_REF**2 * 0.01))
    # the line through (d cos θ, −d sin θ) along (sin θ, cos θ) meets y = Y_REF at the returned x
    th, d = 0.3, -0.4
    x, _ = pf.line_lateral(th, d, cov)
    t = (pf.Y_REF + d * math.sin(th)) / math.cos(th)
    assert x == pytest.approx(d * math.cos(th) + t * math.sin(th), abs=1e-12)
    # the s.d. against a finite-difference propagation of the covariance
    eps = 1e-6
    j = np.array([
        (pf.line_lateral(th + eps, d, cov)[0] - pf.line_lateral(th - eps, d, cov)[0]) / (2 * eps),
        (pf.line_lateral(th, d + eps, cov)[0] - pf.line_lateral(th, d - eps, cov)[0]) / (2 * eps),
    ])  # fmt: skip
    assert pf.line_lateral(th, d, cov)[1] == pytest.approx(math.sqrt(j @ cov @ j), rel=1e-6)


def test_the_sonar_figure_finds_every_pipe_near_its_axis(tmp_path):
    path = tmp_path / "s.png"
    fixes = pf.sonar_profiles(path, lateral=0.4, angle=0.3)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(fixes) == len(pf.SONAR_CASES) and all(f.found for f in fixes)
    # the axis's lateral position at the detection's forward position (the tilted fan meets it short of
    # its seabed line): within 6 cm, the half buried pipe's SNR below the proud pipe's on the same seabed
    from pipefollow.perception.sonar import fan_line
    from pipefollow.perception.sonar_track import SonarSensor

    line = fan_line(SonarSensor().sonar)
    for f in fixes:
        assert abs(f.lateral - (0.4 + (f.forward - line) * math.tan(0.3))) < 0.06
    assert fixes[1].snr < fixes[0].snr and fixes[3].snr < fixes[2].snr


def test_the_tracker_episode_follows_a_straight_start(tmp_path):
    pytest.importorskip("cv2")
    run = pf.tracker_episode("heldout-sharp", 7, "clear", seconds=8.0)
    assert len(run.poses) == 8 and run.detection.shape == (8, 4) and run.cov.shape == (8, 2, 2)
    stats = pf.tracker_figure(run, tmp_path / "t.png")
    assert (tmp_path / "t.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # heldout-sharp-007 runs straight ahead for 3 m: the tracked offset is the true one within centimetres
    assert stats["compared"] >= 6 and stats["rms_error_m"] < 0.05
