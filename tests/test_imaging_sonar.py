"""The forward-looking imaging sonar: its image against analytic answers, its detector and its map."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, stats

from pipefollow.perception.imaging_detect import ImageFix, detect_image, seabed_level
from pipefollow.perception.imaging_sonar import (
    FLS,
    ImagingSonar,
    ImagingSonarError,
    SonarImage,
    bin_ranges,
    check_imaging_sonar,
    n_bins,
    render_image,
)
from pipefollow.perception.imaging_track import LINK_M, ImagingMap, ImagingSensor

FAR = np.array([[0.0, 100.0], [50.0, 100.0]])  # a pipe 100 m to port: an empty seabed
FAR_CUM = np.array([0.0, 50.0])


def straight(angle_deg: float, forward: float = 2.0, lateral: float = 0.0):
    """A straight pipe through (forward, lateral) at ``angle_deg`` to the track, from pose (0, 0, 0)."""
    a = math.radians(angle_deg)
    d = np.array([math.cos(a), math.sin(a)])  # earth x is forward, earth y lateral at ψ = 0
    p0 = np.array([forward, lateral])
    return np.array([p0 - 10.0 * d, p0 + 10.0 * d]), np.array([0.0, 20.0])


def test_flat_seabed_energy_matches_the_integral():
    """Each range bin's energy is ∫ cos²i · G(δ)² dρ over the seabed it covers (scipy), the first bin too."""
    s = FLS
    img = render_image(FAR, FAR_CUM, (0.0, 0.0, 0.0), np.random.default_rng(0))
    r = bin_ranges(s)
    tilt, k = math.radians(s.tilt_deg), 4.0 * math.log(2.0) / math.radians(s.vertical_deg) ** 2
    h = s.altitude
    energy = (img.mean[64] - s.floor * math.sin(tilt) ** 2) * s.range_resolution

    def f(rho):
        rr = math.hypot(rho, h)
        return (h / rr) ** 2 * math.exp(-k * (math.atan2(h, rho) - tilt) ** 2)

    for j in (0, 1, 2, 10, 11, 40, 41, 86, 87):  # no ripple from the 1-cm sampling; nothing nearer in bin 0
        r0, r1 = r[j] - s.range_resolution / 2, r[j] + s.range_resolution / 2
        exact, _ = integrate.quad(f, math.sqrt(r0 * r0 - h * h), math.sqrt(r1 * r1 - h * h))
        assert energy[j] == pytest.approx(exact, rel=0.005), j
    # every beam sees the same flat seabed
    assert np.allclose(img.mean, img.mean[0])


def test_speckle_is_a_standard_exponential():
    img = render_image(FAR, FAR_CUM, (0.0, 0.0, 0.0), np.random.default_rng(3))
    ratio = (img.intensity / img.mean).ravel()
    assert stats.kstest(ratio, "expon").pvalue > 0.01


def shadowed_image(rng, share, bins=10, mean_level=2.0):
    """A uniform seabed (mean ``mean_level``), its first ``share`` of beams in shadow over ``bins`` bins."""
    nb = n_bins(FLS)
    mean = np.full((FLS.n_beams, nb), mean_level)
    mean[: int(share * FLS.n_beams), :bins] = 0.035 * mean_level  # the noise floor's share
    return SonarImage(mean * rng.standard_exponential(mean.shape), mean, FLS)


def test_the_seabed_level_ignores_the_shadowed_beams():
    """With half the beams of ten range bins in shadow the level stays the lit seabed's (not the median's)."""
    rng = np.random.default_rng(11)
    for share in (0.0, 0.5, 0.8):
        img = shadowed_image(rng, share)
        level = np.empty(img.intensity.shape[1])
        seabed_level(img.intensity, level)
        assert np.median(level) == pytest.approx(2.0, rel=0.1)
        # measured: the shadowed bins' mean level 1.02-1.09 of the seabed's, none below 0.66
        assert 0.85 < level[:10].mean() / 2.0 < 1.2 and level[:10].min() / 2.0 > 0.5, share
        # the median over every beam falls towards the floor where half or more are shadowed
        if share >= 0.5:
            assert np.median(img.intensity[:, :10], axis=0).mean() / math.log(2.0) < 0.5 * 2.0


def test_a_range_bin_with_too_few_lit_cells_takes_the_nearest_level():
    """16 beams, ten of them shadowed in bins 0-3 and 8-11: six lit cells there, fewer than eight."""
    rng = np.random.default_rng(13)
    mean = np.full((16, 40), 2.0)
    mean[:10, :4] = mean[:10, 8:12] = 0.07
    level = np.empty(40)
    seabed_level(mean * rng.standard_exponential(mean.shape), level)
    assert np.all(level[:4] == level[4])
    assert level[8] == level[9] == level[7] and level[10] == level[11] == level[12]  # the nearer own bin
    assert level[4] == pytest.approx(2.0, rel=0.6)  # one bin's estimate from 16 cells


def test_the_seabed_level_of_a_small_sonar():
    """16 beams: a bin's level from its own lit cells (at least half the beams), near the mean."""
    rng = np.random.default_rng(14)
    intensity = 2.0 * rng.standard_exponential((16, 400))
    level = np.empty(400)
    seabed_level(intensity, level)
    assert level.mean() == pytest.approx(2.0, rel=0.1)


@pytest.mark.parametrize("share", [0.4, 0.5, 0.8])
def test_no_piece_where_most_beams_are_in_shadow(share):
    """Measured: no piece in 20 pings at 40-80 % (a piece in each with the median of every beam as level)."""
    rng = np.random.default_rng(12)
    assert not any(detect_image(shadowed_image(rng, share)).found for _ in range(20))


def test_the_shadow_behind_a_pipe_across_the_track():
    """The central beam's shadow ends where the ray grazing the pipe's top meets the seabed."""
    s, radius, forward = FLS, 0.125, 2.0
    points, cum = straight(90.0, forward)
    img = render_image(points, cum, (0.0, 0.0, 0.0), np.random.default_rng(0), diameter=2 * radius)
    beam = img.mean[s.n_beams // 2]
    floor = s.floor * math.sin(math.radians(s.tilt_deg)) ** 2
    shadow = np.flatnonzero(np.isclose(beam, floor))
    # the tangent from the transducer (0, h) to the circle of centre (F, R): where it meets the seabed
    h = s.altitude
    dx, dz = forward, radius - h
    dist = math.hypot(dx, dz)
    below = math.atan2(-dz, dx) - math.asin(radius / dist)  # the tangent's depression (upper tangent)
    rho_end = h / math.tan(below)
    r_end = math.hypot(rho_end, h)
    last = bin_ranges(s)[shadow[-1]] + s.range_resolution / 2
    assert abs(last - r_end) <= 2 * s.range_resolution
    # the pipe's highlight lies just before the shadow and outshines the seabed
    assert beam[: shadow[0]].max() > 3 * np.median(beam)


@pytest.mark.parametrize("angle", [0.0, 30.0, 60.0, 90.0])
@pytest.mark.parametrize("burial", [0.0, 0.5])
def test_detector_finds_straight_pipes(angle, burial):
    points, cum = straight(angle, 2.0, 0.3)
    rng = np.random.default_rng(int(angle) + int(10 * burial))
    a = math.radians(angle)
    normal = np.array([math.cos(a), -math.sin(a)])  # (lateral, forward) normal of the pipe's line
    found, errors = 0, []
    for _ in range(20):
        fix = detect_image(render_image(points, cum, (0.0, 0.0, 0.0), rng, burial=burial))
        if not fix.found:
            continue
        found += 1
        for x, y in ((fix.x1, fix.y1), (fix.x2, fix.y2)):  # each end's distance from the pipe's axis
            errors.append(abs((x - 0.3) * normal[0] + (y - 2.0) * normal[1]))
        assert fix.y1 >= fix.y2  # the far end is the one further forward
    assert found >= 19
    # measured: medians 0.01-0.05 m, 90 % within 0.085 m, the worst end 0.16 m (along the track, far)
    assert np.median(errors) < 0.06 and np.quantile(errors, 0.9) < 0.1 and max(errors) < 0.25


def test_no_piece_on_an_empty_seabed():
    rng = np.random.default_rng(7)
    assert not any(detect_image(render_image(FAR, FAR_CUM, (0.0, 0.0, 0.0), rng)).found for _ in range(300))


def test_same_seed_same_image():
    points, cum = straight(40.0)
    a = render_image(points, cum, (0.1, 0.2, 0.3), np.random.default_rng(5))
    b = render_image(points, cum, (0.1, 0.2, 0.3), np.random.default_rng(5))
    assert np.array_equal(a.intensity, b.intensity)


def test_a_buried_stretch_hides_the_pipe():
    points, cum = straight(90.0)
    rng = np.random.default_rng(0)
    open_ = render_image(points, cum, (0.0, 0.0, 0.0), rng)
    hidden = render_image(
        points, cum, (0.0, 0.0, 0.0), rng, buried_from=np.array([0.0]), buried_to=np.array([20.0])
    )
    empty = render_image(FAR, FAR_CUM, (0.0, 0.0, 0.0), rng)
    assert np.allclose(hidden.mean, empty.mean)
    assert not np.allclose(open_.mean, empty.mean)


def highlights(*segments, step=0.02):
    """An ImageFix whose highlights lie along the segments ((x0, y0), (x1, y1)), camera frame."""
    pts = []
    for (x0, y0), (x1, y1) in segments:
        n = int(math.hypot(x1 - x0, y1 - y0) / step) + 1
        t = np.linspace(0.0, 1.0, n)
        pts.append(np.column_stack((x0 + t * (x1 - x0), y0 + t * (y1 - y0))))
    pts = np.concatenate(pts)
    return ImageFix(True, highlights=len(pts), points=pts)


def axis_map(**kw):
    """A map whose lines are the highlights' own (no move from the pipe's face to its axis)."""
    m = ImagingMap(**kw)
    m._settings[6] = 0.0
    return m


def test_map_moves_what_it_saw_into_the_footprint():
    """A line seen 1.5-3 m ahead lies 0.5-2 m ahead after a metre forward; a turn to port moves it behind."""
    m = axis_map()
    v = m.update((0.0, 0.0, 0.0), highlights(((0.2, 1.5), (0.2, 3.0))))
    assert v.in_view and (v.x1, v.y1, v.x2, v.y_near) == pytest.approx((0.2, 3.0, 0.2, 1.5), abs=0.02)
    v = m.update((1.0, 0.0, 0.0), ImageFix(False))
    assert v.in_view and (v.x1, v.y1, v.x2, v.y_near) == pytest.approx((0.2, 2.0, 0.2, 0.5), abs=0.02)
    # heading to port (ψ = -π/2) from (2.5, 0): the earth points (1.5..3, 0.2) lie 0.2 m behind
    assert not m.view((2.5, 0.0, -math.pi / 2)).in_view


def test_map_joins_two_legs_at_a_bend():
    """Along the track to 2.5 m, then to starboard: near end on the first leg, far end at the second's end."""
    m = axis_map()
    v = m.update((0.0, 0.0, 0.0), highlights(((0.0, 0.3), (0.0, 2.5)), ((0.0, 2.5), (0.9, 2.0))))
    assert v.in_view
    assert (v.x2, v.y_near) == pytest.approx((0.0, 0.3), abs=0.03)
    assert (v.x1, v.y1) == pytest.approx((0.9, 2.0), abs=0.03)


def test_map_starts_on_the_line_under_the_auv_not_the_strongest():
    """Two lines that meet at no bend: with no last view the one passing nearer the AUV is shown.

    The AUV's leg runs from under it to 1.2 m ahead; a longer leg beyond a hook's corner (its
    lines cross 1.5 m past the first leg's piece, beyond ``LINK_M``) has more highlights, so it is
    the strongest line. A first view shows the AUV's leg; once a view was shown, the strongest
    line again (the camera's tracker keeps the leg it started on); after a view without the pipe,
    the AUV's leg again.
    """
    assert LINK_M < 1.5  # the lines cross at (0, 2.7), 1.5 m past the first leg's piece: no bend
    legs = highlights(((0.0, 0.3), (0.0, 1.2)), ((-1.0, 1.2), (0.2, 3.0)))
    m = axis_map()
    v = m.update((0.0, 0.0, 0.0), legs)
    assert v.in_view
    assert (v.x1, v.y1, v.x2, v.y_near) == pytest.approx((0.0, 1.2, 0.0, 0.3), abs=0.03)
    v = m.update((0.0, 0.0, 0.0), legs)  # the strongest, the other leg, in the last view's way
    assert (v.x1, v.y1, v.x2, v.y_near) == pytest.approx((0.2, 3.0, -1.0, 1.2), abs=0.05)
    # a view without the pipe (from 100 m away) forgets the last view: the next starts on the AUV's again
    assert not m.update((100.0, 100.0, 0.0), ImageFix(False)).in_view
    v = m.update((0.0, 0.0, 0.0), ImageFix(False))
    assert (v.x1, v.y1, v.x2, v.y_near) == pytest.approx((0.0, 1.2, 0.0, 0.3), abs=0.03)
    m.reset()
    v = m.update((0.0, 0.0, 0.0), legs)
    assert (v.x1, v.y1, v.x2, v.y_near) == pytest.approx((0.0, 1.2, 0.0, 0.3), abs=0.03)


def test_map_keeps_the_last_way():
    """A line across the track keeps the way it was first shown in, whichever end is nearer the AUV."""
    m = axis_map()
    v = m.update((0.0, 0.0, 0.0), highlights(((0.3, 1.0), (-0.8, 2.4))))
    assert (v.x2, v.y_near) == pytest.approx((0.3, 1.0), abs=0.03)  # the end nearer the AUV: near
    # turned round at (3, 0): the far end, earth (2.4, -0.8), is now the nearer (0.8, 0.6); the way is kept
    v = m.update((3.0, 0.0, math.pi), ImageFix(False))
    assert (v.x1, v.y1, v.x2, v.y_near) == pytest.approx((0.8, 0.6, -0.3, 2.0), abs=0.03)
    m.reset()  # without a last way the end nearer the AUV is the near one
    m.update((0.0, 0.0, 0.0), highlights(((0.3, 1.0), (-0.8, 2.4))))
    m._last[:2] = math.nan
    v = m.view((3.0, 0.0, math.pi))
    assert (v.x2, v.y_near) == pytest.approx((0.8, 0.6), abs=0.03)


def test_map_clips_a_line_to_the_footprint_along_itself():
    """A line leaving the footprint's side within the margin ends where it crosses it, its slope kept."""
    m = axis_map()
    v = m.update((0.0, 0.0, 0.0), highlights(((0.5, 1.0), (1.08, 2.16))))  # x = 0.5 + (y − 1) / 2
    assert (v.x1, v.y1, v.x2, v.y_near) == pytest.approx((1.0, 2.0, 0.5, 1.0), abs=0.02)


def test_map_forgets_old_pings():
    m = axis_map(memory=2)
    m.update((0.0, 0.0, 0.0), highlights(((0.0, 1.0), (0.0, 2.5))))
    assert m.update((0.0, 0.0, 0.0), ImageFix(False)).in_view  # one ping old: kept
    assert m.update((0.0, 0.0, 0.0), ImageFix(False)).in_view is False  # two: forgotten


def test_a_look_from_another_pose_leaves_the_map_as_it_was():
    m = axis_map()
    m.update((0.0, 0.0, 0.0), highlights(((0.3, 1.0), (-0.8, 2.4))))
    kept = m._last.copy()
    m.view((3.0, 0.0, math.pi))
    np.testing.assert_array_equal(m._last, kept)


def test_sensor_sees_a_straight_pipe_ahead():
    points, cum = straight(0.0, 2.0, -0.4)
    sensor = ImagingSensor()
    rng = np.random.default_rng(1)
    view = sensor.step(points, cum, (0.0, 0.0, 0.0), rng)
    assert view.in_view and sensor.fix.found
    assert view.x1 == pytest.approx(-0.4, abs=0.08) and view.x2 == pytest.approx(-0.4, abs=0.08)


@pytest.mark.parametrize("setting", ["smooth", "smooth_beams", "min_cells", "max_pieces"])
def test_bad_detect_settings_are_one_line_errors(setting):
    img = render_image(FAR, FAR_CUM, (0.0, 0.0, 0.0), np.random.default_rng(0))
    with pytest.raises(ValueError, match=f"detect setting {setting} must be a whole number ≥ 1, got 0$"):
        detect_image(img, **{setting: 0})


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("n_beams", 4),
        ("fov_deg", 0.0),
        ("range_resolution", -1.0),
        ("tilt_deg", 90.0),
        ("altitude", float("nan")),
    ],
)
def test_bad_settings_name_the_field(field, value):
    with pytest.raises(ImagingSonarError, match=field):
        check_imaging_sonar(ImagingSonar(**{field: value}))


def test_ranges_that_never_reach_the_seabed():
    with pytest.raises(ImagingSonarError, match="never reach"):
        check_imaging_sonar(ImagingSonar(range_min=0.5, range_max=1.5))
    with pytest.raises(ImagingSonarError, match="range_max"):
        check_imaging_sonar(ImagingSonar(range_min=3.0, range_max=2.5))
    with pytest.raises(ImagingSonarError, match="n_beams must be a finite number"):
        check_imaging_sonar(ImagingSonar(n_beams=float("inf")))


def test_bad_map_sensor_and_render_arguments_are_one_line_errors():
    with pytest.raises(ValueError, match="memory"):
        ImagingMap(memory=0)
    with pytest.raises(ValueError, match="burial"):
        ImagingSensor(burial=1.5)
    with pytest.raises(ValueError, match=r"unknown detect setting\(s\) \['thresh'\]"):
        ImagingSensor(detect={"thresh": 4.0})
    with pytest.raises(ImagingSonarError, match="out"):
        render_image(FAR, FAR_CUM, (0.0, 0.0, 0.0), np.random.default_rng(0), out=np.empty((3, 3)))


def test_the_level_s_selections_equal_numpy_s_median_and_quantile():
    from pipefollow.perception.imaging_detect import _median, _quantile

    rng = np.random.default_rng(15)
    for n in (1, 2, 3, 8, 127, 128):
        x = rng.standard_exponential(n)
        x[: n // 3] = x[0]  # ties
        assert _median(x.copy(), n) == pytest.approx(np.median(x), rel=1e-12)
        assert _quantile(x.copy(), n, 0.9) == pytest.approx(np.quantile(x, 0.9), rel=1e-12)


def test_a_sample_s_shares_are_what_deposit_adds():
    from pipefollow.perception.imaging_sonar import _deposit, _shares

    rng = np.random.default_rng(16)
    for _ in range(200):
        lo = rng.uniform(2.1, 4.5)
        hi = lo + rng.uniform(0.0, 0.03)
        row, out = np.zeros(88), np.zeros(2)
        _deposit(row, lo, hi, 1.3, 2.2, 0.025)
        first, count = _shares(lo, hi, 1.3, 2.2, 0.025, 88, out)
        if count == 3:  # three bins or more: left to _deposit
            assert first == -1 and np.count_nonzero(row) >= 3
            continue
        mine = np.zeros(88)
        for j in range(count):
            mine[first + j] += out[j]
        np.testing.assert_array_equal(mine, row)
    assert _shares(2.3, 2.4, 1.0, 2.2, 0.025, 88, np.zeros(2)) == (-1, 3)  # four bins: left to _deposit
