"""The multibeam profiler against hand-computed geometry and scipy, and its pipe detector on noisy pings."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, stats

from pipefollow.perception.sonar import (
    DOWNWARD_SONAR,
    LOOK_AHEAD_SONAR,
    SonarError,
    beam_angles,
    fan_line,
    make_sonar,
    profile_points,
    render_ping,
)
from pipefollow.perception.sonar_detect import SonarFix, detect_profile
from pipefollow.perception.sonar_track import CARRY, NO_VIEW, SonarSensor, SonarTrack
from pipefollow.sim.camera import PAPER_CAMERA, observe

EMPTY = np.zeros((0, 2))
EXACT = make_sonar(range_noise=0.0, range_resolution=0.0, beam_width_deg=0.0, sub_rays=1)  # the bare geometry


def straight_pipe(x0: float, angle: float = 0.0, length: float = 40.0, north: float = 0.0):
    """A straight pipe through (``north``, east ``x0``): for an AUV at (0, 0, ψ = 0) and ``north``
    0 it crosses the camera frame's lateral axis at x0. ``angle`` turns it from north (the track)
    towards east (starboard).
    """
    d = np.array([math.cos(angle), math.sin(angle)])
    p0 = np.array([north, x0])
    return np.array([p0 - 0.5 * length * d, p0 + 0.5 * length * d]), np.array([0.0, length])


def ping(points, cum, sonar=DOWNWARD_SONAR, seed=0, pose=(0.0, 0.0, 0.0), **kw):
    return render_ping(points, cum, pose, np.random.default_rng(seed), sonar, **kw)


# --- the render's geometry ------------------------------------------------------------------


def test_a_flat_seabed_reads_altitude_over_cos_of_the_beam_angle():
    p = ping(EMPTY, EMPTY[:, 0], EXACT)
    assert np.array_equal(p.angles, beam_angles(EXACT)) and np.all(np.diff(p.angles) > 0)
    assert np.allclose(p.ranges, 2.0 / np.cos(p.angles), rtol=0, atol=1e-12)
    assert p.angles[0] == pytest.approx(-math.radians(60.0)) and p.angles[-1] == pytest.approx(
        math.radians(60.0)
    )
    # the swath at 2 m: 2·2·tan 60° = 6.93 m across, wider than the camera's 2 m footprint
    x, _ = profile_points(p.ranges, p.angles)
    assert x[-1] - x[0] == pytest.approx(4.0 * math.tan(math.radians(60.0)))


def test_a_beams_width_averages_its_rays_over_the_flat_seabed():
    sonar = EXACT._replace(beam_width_deg=2.0, sub_rays=4)
    p = ping(EMPTY, EMPTY[:, 0], sonar)
    w = math.radians(2.0)
    offsets = w * (np.arange(4) + 0.5) / 4 - 0.5 * w  # -0.75w, -0.25w, 0.25w, 0.75w
    expected = np.mean(2.0 / np.cos(p.angles[:, None] + offsets[None, :]), axis=1)
    assert np.allclose(p.ranges, expected, atol=1e-12)
    assert np.all(p.ranges >= 2.0 / np.cos(p.angles) - 1e-12)  # 1/cos is convex: the mean reads long


@pytest.mark.parametrize("pitch", [20.0, 45.0])
def test_a_tilted_fan_reads_the_flat_seabed_at_altitude_over_cos_phi_cos_pitch(pitch):
    sonar = EXACT._replace(pitch_deg=pitch)
    p = ping(EMPTY, EMPTY[:, 0], sonar)
    tau = math.radians(pitch)
    assert np.allclose(p.ranges, 2.0 / (np.cos(p.angles) * math.cos(tau)), atol=1e-12)
    assert p.pitch == pytest.approx(tau) and fan_line(sonar) == pytest.approx(2.0 * math.tan(tau))
    _, z = profile_points(p.ranges, p.angles, p.pitch)
    assert np.allclose(z, -2.0, atol=1e-12)  # heights in the vertical


def test_a_sloping_seabed_puts_every_point_on_its_plane():
    p = ping(EMPTY, EMPTY[:, 0], EXACT._replace(seabed_slope_deg=10.0))
    x, z = profile_points(p.ranges, p.angles)
    assert np.allclose(z + 2.0, x * math.tan(math.radians(10.0)), atol=1e-12)


@pytest.mark.parametrize("burial", [0.0, 0.5, 0.8])
def test_the_beam_below_reads_the_top_of_the_pipe(burial):
    sonar = EXACT._replace(n_beams=129)  # an odd count: beam 64 points straight down
    pts, cum = straight_pipe(0.0)
    p = ping(pts, cum, sonar, burial=burial)
    assert p.angles[64] == 0.0
    # the top stands 2R(1 − b) above the seabed: R = 0.125, altitude 2 m
    assert p.ranges[64] == pytest.approx(2.0 - 0.25 * (1.0 - burial), abs=1e-12)
    # a beam at angle φ meets the circle of centre depth d below the transducer at
    # r = d cos φ − √(R² − d² sin² φ), the near root of |r(sin φ, cos φ) − (0, d)| = R
    d, radius = 2.0 - 0.125 * (1.0 - 2.0 * burial), 0.125
    for i in (63, 62, 65):
        phi = p.angles[i]
        r = d * math.cos(phi) - math.sqrt(radius**2 - (d * math.sin(phi)) ** 2)
        if r * math.cos(phi) < 2.0:  # above the seabed
            assert p.ranges[i] == pytest.approx(r, abs=1e-12)


@pytest.mark.parametrize(
    "x0, angle, pitch", [(0.4, 0.0, 0.0), (-0.7, 0.5, 0.0), (1.2, -0.9, 0.0), (0.3, 0.4, 45.0)]
)
def test_a_pipe_crossing_the_fan_obliquely_matches_the_3d_cylinder(x0, angle, pitch):
    """Each beam's range against a root-finder on the distance to the cylinder's axis in 3-D."""
    tau = math.radians(pitch)
    ahead = 2.0 * math.tan(tau)  # the fan's seabed line; the pipe crosses it at lateral x0
    pts, cum = straight_pipe(x0, angle, north=ahead)
    p = ping(pts, cum, EXACT._replace(pitch_deg=pitch))
    assert p.pipe_x[0] == pytest.approx(x0, abs=1e-12)
    radius, altitude = 0.125, 2.0
    axis_point = np.array([x0, ahead, altitude - radius])  # (lateral, forward, depth) on the axis
    axis_dir = np.array([math.sin(angle), math.cos(angle), 0.0])  # camera frame: east → lateral

    def gap(r, phi):
        ray = np.array([math.sin(phi), math.cos(phi) * math.sin(tau), math.cos(phi) * math.cos(tau)])
        return np.linalg.norm(np.cross(r * ray - axis_point, axis_dir)) - radius

    hits = 0
    for phi, measured in zip(p.angles, p.ranges, strict=True):
        seabed = altitude / (math.cos(phi) * math.cos(tau))
        if abs(seabed * math.sin(phi) - x0) > 0.8:  # the ray passes ≥ 0.5 m from the pipe
            assert measured == pytest.approx(seabed, abs=1e-12)
            continue
        rs = np.linspace(0.5, seabed, 1000)
        g = np.array([gap(r, phi) for r in rs])
        k = int(np.argmin(g))  # the ray's closest approach to the axis, refined
        lo, hi = rs[max(k - 1, 0)], rs[min(k + 1, rs.size - 1)]
        closest = optimize.minimize_scalar(
            gap, bounds=(lo, hi), args=(phi,), method="bounded", options={"xatol": 1e-12}
        )
        if closest.fun >= 0.0:
            assert measured == pytest.approx(seabed, abs=1e-12)
            continue
        r = optimize.brentq(gap, 0.5, closest.x, args=(phi,), xtol=1e-13)
        assert measured == pytest.approx(min(r, seabed), abs=1e-9)
        hits += 1
    assert hits >= 3


def test_each_segment_is_a_cylinder_of_its_own_length():
    """A pipe that runs north to the fan's line, then turns east along it, ends there."""
    pts = np.array([[-20.0, 0.3], [0.0, 0.3], [0.0, 5.3]])
    cum = np.array([0.0, 20.0, 25.0])
    p = ping(pts, cum, EXACT)
    x, _ = profile_points(2.0 / np.cos(p.angles), p.angles)  # where each beam meets the seabed
    flat = 2.0 / np.cos(p.angles)
    west = x < 0.3 - 0.125 - 0.01  # beyond the pipe's western side
    assert np.allclose(p.ranges[west], flat[west], atol=1e-12)
    # over the eastward leg (lying in the fan's plane) a beam meets its top line, 1.75 m down
    on_leg = (x > 0.5) & (x < 5.0)
    assert on_leg.sum() >= 10 and np.allclose(p.ranges[on_leg], 1.75 / np.cos(p.angles[on_leg]), atol=1e-9)
    # a pipe that ends 1 m behind the fan leaves the seabed flat
    short = ping(np.array([[-20.0, 0.3], [-1.0, 0.3]]), np.array([0.0, 19.0]), EXACT)
    assert np.array_equal(short.ranges, flat) and short.pipe_x.size == 0


def test_a_fully_buried_pipe_and_a_buried_stretch_leave_a_flat_seabed():
    pts, cum = straight_pipe(0.3)
    flat = ping(EMPTY, EMPTY[:, 0], EXACT).ranges
    assert np.array_equal(ping(pts, cum, EXACT, burial=1.0).ranges, flat)
    # the fan crosses the pipe at arc length 20 m; a stretch over it buries it, one elsewhere not
    buried = ping(
        pts,
        cum,
        EXACT,
        buried_from=(19.0, 30.0, math.inf, math.inf),
        buried_to=(21.0, 31.0, math.inf, math.inf),
    )
    assert np.array_equal(buried.ranges, flat) and not buried.pipe_visible[0]
    elsewhere = ping(pts, cum, EXACT, buried_from=(25.0, math.inf, math.inf, math.inf))
    assert not np.array_equal(elsewhere.ranges, flat) and elsewhere.pipe_visible[0]
    assert buried.pipe_x[0] == pytest.approx(0.3)


def test_the_fan_moves_with_the_pose():
    """A pipe along north at east 0.3, seen from an AUV heading east: the fan crosses it at lateral 0."""
    pts = np.array([[-20.0, 0.3], [20.0, 0.3]])
    cum = np.array([0.0, 40.0])
    p = ping(pts, cum, EXACT, pose=(1.5, 0.0, 0.5 * math.pi))  # heading east, fan along north–south
    assert p.pipe_x.size == 0  # the fan (north–south line at east 0) is parallel to the pipe: no crossing
    p = ping(pts, cum, EXACT, pose=(2.0, 0.3, 0.0))
    assert p.pipe_x[0] == pytest.approx(0.0, abs=1e-12)


def test_ranges_are_quantised_to_the_resolution():
    sonar = make_sonar(range_noise=0.0, range_resolution=0.0125)
    p = ping(*straight_pipe(0.2), sonar)
    exact = ping(*straight_pipe(0.2), sonar._replace(range_resolution=0.0))
    steps = p.ranges / 0.0125
    assert np.allclose(steps, np.round(steps), atol=1e-9)
    assert np.all(np.abs(p.ranges - exact.ranges) <= 0.5 * 0.0125 + 1e-12)
    assert np.any(p.ranges != exact.ranges)


def test_range_noise_is_gaussian_with_its_standard_deviation():
    sonar = make_sonar(range_noise=0.02, range_resolution=0.0)
    truth = ping(EMPTY, EMPTY[:, 0], sonar._replace(range_noise=0.0)).ranges
    err = np.concatenate([ping(EMPTY, EMPTY[:, 0], sonar, seed=s).ranges - truth for s in range(40)])
    n = err.size  # 5,120 draws
    assert abs(err.mean()) < 4.0 * 0.02 / math.sqrt(n)
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n)
    assert lo < np.sum(err**2) / 0.02**2 < hi  # the variance in its 99.9 % chi-square interval
    assert stats.kstest(err / 0.02, "norm").pvalue > 0.001


def test_dropouts_read_nan_at_their_rate():
    sonar = make_sonar(dropout=0.1)
    nan = sum(int(np.isnan(ping(EMPTY, EMPTY[:, 0], sonar, seed=s).ranges).sum()) for s in range(40))
    lo, hi = stats.binom.ppf([0.0005, 0.9995], 40 * 128, 0.1)
    assert lo <= nan <= hi


def test_the_roughness_has_its_rms_over_many_seabeds():
    sonar = EXACT._replace(roughness=0.02)
    heights = []
    for s in range(400):
        p = ping(EMPTY, EMPTY[:, 0], sonar, seed=s)
        _, z = profile_points(p.ranges, p.angles)
        heights.append(z + 2.0)
    ms = np.mean(np.square(heights))
    assert ms == pytest.approx(0.02**2, rel=0.1)


def test_the_same_seed_gives_the_same_ping():
    pts, cum = straight_pipe(0.2)
    sonar = make_sonar(roughness=0.01, dropout=0.05)
    a, b = ping(pts, cum, sonar, seed=3), ping(pts, cum, sonar, seed=3)
    assert np.array_equal(a.ranges, b.ranges, equal_nan=True)


@pytest.mark.parametrize(
    "field, value",
    [
        ("n_beams", 4),
        ("n_beams", 64.5),
        ("swath_deg", 0.0),
        ("range_noise", math.nan),
        ("dropout", 0.9),
        ("sub_rays", True),
    ],
)
def test_bad_settings_raise_one_line_errors_naming_the_field(field, value):
    with pytest.raises(SonarError, match=field) as e:
        make_sonar(**{field: value})
    assert "\n" not in str(e.value)
    with pytest.raises(SonarError, match="unknown"):
        make_sonar(beams=3)


# --- the detector -----------------------------------------------------------------------------


def test_the_detector_finds_the_pipe_where_it_is_to_a_centimetre():
    errors = []
    for seed in range(300):
        rng = np.random.default_rng(seed)
        x0, angle = rng.uniform(-1.0, 1.0), rng.uniform(-0.5, 0.5)  # the camera's footprint
        p = render_ping(*straight_pipe(x0, angle), (0.0, 0.0, 0.0), rng)
        fix = detect_profile(p)
        assert fix.found, (seed, x0, angle)
        errors.append(fix.lateral - p.pipe_x[0])
        assert fix.height == pytest.approx(0.25, abs=0.04) and fix.seabed_depth == pytest.approx(
            2.0, abs=0.01
        )
    e = np.abs(errors)
    assert np.median(e) < 0.01 and np.percentile(e, 95) < 0.025 and e.max() < 0.05
    assert abs(np.mean(errors)) < 0.005  # no side bias


def test_a_tilted_fan_finds_the_pipe_ahead_and_where_along_the_track():
    tau = math.radians(45.0)
    errors = []
    for seed in range(100):
        rng = np.random.default_rng(seed)
        x0, angle = rng.uniform(-1.0, 1.0), rng.uniform(-0.5, 0.5)  # the pipe through (0, x0)
        p = render_ping(*straight_pipe(x0, angle), (0.0, 0.0, 0.0), rng, LOOK_AHEAD_SONAR)
        fix = detect_profile(p)
        assert fix.found and fix.seabed_depth == pytest.approx(2.0, abs=0.01)
        # the section's centre: the axis (1.875 m down) on the fan, forward 1.875·tan τ
        forward = (2.0 - 0.125) * math.tan(tau)
        assert fix.forward == pytest.approx(forward, abs=0.05)
        # a tilted fan cuts an oblique pipe in a sheared section: a point Δz above the axis lies
        # nearer by Δz·tan τ, so beside the axis by −Δz·tan τ·tan α; the top half is fitted
        err = fix.lateral - (x0 + forward * math.tan(angle))
        assert abs(err) <= 0.015 + 0.125 * math.tan(tau) * abs(math.tan(angle))
        errors.append((err, math.tan(angle)))
    err, tan_a = np.array(errors).T
    assert np.median(np.abs(err[np.abs(tan_a) < 0.1])) < 0.01
    assert stats.pearsonr(err, tan_a).statistic < -0.5  # the shear's sign


def test_the_detector_sees_across_the_swath_beyond_the_camera():
    for x0 in (-2.5, -1.8, 1.6, 2.4):
        fix = detect_profile(ping(*straight_pipe(x0), seed=1))
        assert fix.found and fix.lateral == pytest.approx(x0, abs=0.03)


@pytest.mark.parametrize(
    "sonar",
    [DOWNWARD_SONAR, make_sonar(roughness=0.01), make_sonar(range_noise=0.03, dropout=0.1)],
    ids=["default", "rough 1 cm", "noisy 3 cm, 10 % dropouts"],
)
def test_no_false_detections_on_pipe_free_seabeds(sonar):
    n, false = 2000, 0
    snr = []
    for s in range(n):
        fix = detect_profile(ping(EMPTY, EMPTY[:, 0], sonar, seed=s))
        false += fix.found
        snr.append(fix.snr)
    # no false alarm in 2000 pings: the rate is below 0.15 % at 95 % (rule of three: 3/n)
    assert false == 0
    assert np.median(snr) < 4.0  # the threshold (6) is well above the typical noise peak


@pytest.mark.parametrize("burial, rate", [(0.0, 1.0), (0.5, 1.0), (1.0, 0.0)])
def test_burial(burial, rate):
    found = 0
    for seed in range(200):
        rng = np.random.default_rng(seed)
        p = render_ping(*straight_pipe(rng.uniform(-1.0, 1.0)), (0.0, 0.0, 0.0), rng, burial=burial)
        fix = detect_profile(p)
        found += fix.found
        if fix.found:
            assert fix.lateral == pytest.approx(p.pipe_x[0], abs=0.1)
            assert fix.height == pytest.approx(0.25 * (1.0 - burial), abs=0.04)
    assert found == 200 * rate


def test_the_detector_checks_its_input():
    p = ping(EMPTY, EMPTY[:, 0])
    with pytest.raises(ValueError, match="diameter"):
        detect_profile(p, diameter=-1.0)
    with pytest.raises(ValueError, match="threshold"):
        detect_profile(p, threshold=math.nan)
    with pytest.raises(ValueError, match="angles and ranges"):
        detect_profile((p.angles, p.ranges[:5]))
    assert detect_profile((p.angles, np.full(128, np.nan))) == SonarFix(False)


# --- the track ------------------------------------------------------------------------------


@pytest.mark.parametrize("angle", [0.0, 0.25, -0.4])
def test_the_track_gives_the_cameras_observation_of_a_straight_pipe(angle):
    errors = []
    for seed in range(30):
        rng = np.random.default_rng(seed)
        pts, cum = straight_pipe(rng.uniform(-0.4, 0.4), angle, north=2.0)  # near the last pose
        track = SonarTrack()
        for k in range(5):
            pose = (0.5 * k, 0.0, 0.1 * math.sin(k))  # 0.5 m a ping, weaving
            view = track.update(pose, detect_profile(render_ping(pts, cum, pose, rng)))
        truth = observe(pts, cum, *pose, 10.0, PAPER_CAMERA)
        assert view.in_view and truth.in_view and view.pings == 5
        errors.append(
            [view.x1 - truth.x1, view.y1 - truth.y1, view.x2 - truth.x2, view.y_near - truth.y_near]
        )
        true_angle = angle - pose[2]
        assert view.angle == pytest.approx(true_angle, abs=0.06)
    e = np.abs(errors)
    assert np.all(np.median(e, axis=0) < 0.03) and e.max() < 0.15


def test_the_track_with_one_ping_takes_the_pipe_along_the_track_and_forgets_on_reset():
    pts, cum = straight_pipe(0.3)
    track = SonarTrack()
    view = track.update((0.0, 0.0, 0.0), detect_profile(ping(pts, cum)))
    assert view.in_view and view.pings == 1 and view.angle == 0.0
    assert view.x1 == view.x2 == pytest.approx(0.3, abs=0.03) and (view.y_near, view.y1) == (0.0, 3.0)
    # a pipe the fan sees outside the camera's footprint: detected, not in view
    far = track.update((1.0, 0.0, 0.0), detect_profile(ping(*straight_pipe(2.0), pose=(1.0, 0.0, 0.0))))
    assert far.detected and not far.in_view
    miss = track.update((1.5, 0.0, 0.0), SonarFix(False))
    assert not miss.in_view and not miss.detected
    track.reset()
    assert track.view((0.0, 0.0, 0.0)).pings == 0
    with pytest.raises(ValueError, match="memory"):
        SonarTrack(memory=0)
    with pytest.raises(ValueError, match="min_spread"):
        SonarTrack(min_spread=-1.0)
    # the memory keeps the newest detections only
    short = SonarTrack(memory=3)
    for k in range(5):
        view = short.update((0.5 * k, 0.0, 0.0), SonarFix(True, lateral=0.1 * k))
    assert view.pings == 3 and view.lateral == pytest.approx(0.4)
    assert view.angle == pytest.approx(math.atan(0.2))


def test_a_carried_line_is_the_remembered_pipe_drawn_from_the_new_pose_for_carry_pings():
    # exact fixes of a pipe along north 0.3 m to starboard, 2 m ahead of poses 0.5 m apart
    tracks = {carry: SonarTrack(carry=carry) for carry in (0, 1, 2)}
    for track in tracks.values():
        for k in range(4):
            view = track.update((0.5 * k, 0.0, 0.0), SonarFix(True, lateral=0.3, forward=2.0))
        assert view.in_view and view.detected and view.angle == pytest.approx(0.0, abs=1e-12)
    # a miss from a pose turned 0.1 rad to starboard: the pipe along north 0.3 m to starboard is,
    # in that camera frame, at 0.3 / cos 0.1 m at forward 0 and at −0.1 rad to the track
    psi = 0.1
    views = {
        c: [t.update((2.0 + 0.5 * k, 0.0, psi), SonarFix(False)) for k in range(3)] for c, t in tracks.items()
    }
    for carry, seen in views.items():
        for k, view in enumerate(seen):
            assert not view.detected and view.pings == 4
            assert view.lateral == pytest.approx(0.3 / math.cos(psi), abs=1e-9)
            assert view.angle == pytest.approx(-psi, abs=1e-9)
            assert view.in_view == (k < carry)  # shown for `carry` misses in a row, then lost
            if view.in_view:  # the near end at forward 0, the far end at the footprint's depth
                assert (view.y_near, view.y1) == (0.0, pytest.approx(3.0))
                assert view.x2 == pytest.approx(0.3 / math.cos(psi))
                assert view.x1 == pytest.approx(0.3 / math.cos(psi) - 3.0 * math.tan(psi))
    # a new detection ends the carry count: the next miss is carried again
    track = tracks[1]
    assert track.update((4.0, 0.0, 0.0), SonarFix(True, lateral=0.3, forward=2.0)).in_view
    assert track.update((4.5, 0.0, 0.0), SonarFix(False)).in_view
    assert not track.update((5.0, 0.0, 0.0), SonarFix(False)).in_view
    # nothing remembered: nothing to carry
    empty = SonarTrack(carry=1)
    assert empty.update((0.0, 0.0, 0.0), SonarFix(False)) == NO_VIEW
    assert SonarSensor().track.carry == CARRY == 1
    with pytest.raises(ValueError, match="carry"):
        SonarTrack(carry=-1)


def test_the_sensor_is_render_detect_and_track_from_one_generator():
    pts, cum = straight_pipe(0.2, 0.1)
    sensor = SonarSensor(burial=0.5)
    assert sensor.sonar == LOOK_AHEAD_SONAR
    rng, twin = np.random.default_rng(5), np.random.default_rng(5)
    track = SonarTrack(along=2.0)
    for k in range(4):
        pose = (0.6 * k, 0.0, 0.0)
        view = sensor.step(pts, cum, pose, rng)
        fix = detect_profile(render_ping(pts, cum, pose, twin, LOOK_AHEAD_SONAR, burial=0.5))
        assert view == track.update(pose, fix) == sensor.view  # every ping finds the pipe
    assert view.in_view and view.pings == 4 and sensor.fix.found
    truth = observe(pts, cum, *pose, 10.0, PAPER_CAMERA)
    assert view.x1 == pytest.approx(truth.x1, abs=0.05) and view.x2 == pytest.approx(truth.x2, abs=0.05)
    hidden = (0.0, math.inf, math.inf, math.inf)
    buried = sensor.step(pts, cum, (3.0, 0.0, 0.0), rng, hidden)
    assert buried.in_view and not buried.detected and buried.pings == 4  # the memory, carried one ping
    buried = sensor.step(pts, cum, (3.5, 0.0, 0.0), rng, hidden)
    assert not buried.in_view and not buried.detected and buried.pings == 4  # the memory stays
    sensor.reset()
    assert sensor.view.pings == 0 and sensor.track.view((0.0, 0.0, 0.0)).pings == 0
    with pytest.raises(ValueError, match="burial"):
        SonarSensor(burial=1.5)
    with pytest.raises(SonarError, match="n_beams"):
        SonarSensor(DOWNWARD_SONAR._replace(n_beams=2))


def test_the_sensor_writes_the_observation_slots_as_the_vision_camera_does():
    from pipefollow.sim import decision as sim

    pts, cum = straight_pipe(0.3, 0.0)
    s = np.zeros(sim.STATE_SIZE)
    s[sim.X], s[sim.Y], s[sim.PSI] = -2.0, 0.0, 0.0
    sensor = SonarSensor()
    rng = np.random.default_rng(0)
    view = sensor.look(s, pts, cum, rng)
    assert view.in_view and s[sim.IN_VIEW] == 1.0
    assert (s[sim.X1], s[sim.Y1], s[sim.X2], s[sim.Y_NEAR]) == (view.x1, view.y1, view.x2, view.y_near)
    assert s[sim.E_DIST] == pytest.approx(0.3, abs=0.03) and s[sim.E_ANGL] == 0.0 and s[sim.LAST_SIDE] == 1.0
    # the pipe buried under the fan: the remembered line one ping (CARRY), then lost, the last
    # sighting's slots staying
    hidden = (0.0, math.inf, math.inf, math.inf)
    assert sensor.look(s, pts, cum, rng, hidden).in_view and s[sim.IN_VIEW] == 1.0
    kept = s[: sim.E_ANGL + 1].copy()
    sensor.look(s, pts, cum, rng, hidden)
    assert s[sim.IN_VIEW] == 0.0 and np.array_equal(s[: sim.E_DIST], kept[: sim.E_DIST])


# --- the evaluation helpers -------------------------------------------------------------------


def test_the_statistics_and_the_heuristic_on_the_sonar():
    from pipefollow.evaluation.sonar import heuristic_on_sonar, sonar_statistics

    row = sonar_statistics(n=40)
    assert row["detection_rate"] == 1.0 and row["false_alarm_rate"] == 0.0 and row["max_error_cm"] < 5.0
    assert sonar_statistics(burial=1.0, n=20)["detection_rate"] == 0.0
    from pipefollow.sim.suites import get_suite

    loop = heuristic_on_sonar(get_suite("heldout"), n_pipes=4, seconds=20.0)
    assert loop["exact"]["pipes"] == loop["sonar"]["pipes"] == 4
    assert loop["sonar"]["in_view"] > 0.8 and loop["sonar"]["progress_m"] > 4.0
    down = heuristic_on_sonar(get_suite("heldout"), n_pipes=4, seconds=20.0, sonar=DOWNWARD_SONAR)
    assert down["sonar"]["mean_return"] < loop["sonar"]["mean_return"]  # a fan under the AUV lags
