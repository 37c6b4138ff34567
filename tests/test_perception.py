"""The camera image's conventions, the water record's checks and the pipe detector on known geometry."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from pipefollow.perception import detector
from pipefollow.perception.detector import detect_pipe
from pipefollow.perception.image import Renderer, pixel_centres
from pipefollow.perception.textures import make_textures
from pipefollow.perception.water import WATER_PRESETS, Water, WaterError, make_water, water_from
from pipefollow.sim.camera import PAPER_CAMERA, observe

STILL = Water(turbidity=0.0, light_falloff=0.0, blur=0.0, noise=0.0, snow=0.0)  # a noiseless camera


def straight_pipe(x0: float, psi: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A 40-m pipe along north whose centre line is at camera x = x0 for an AUV at (0, 0, psi=0)."""
    pts = np.array([[-20.0, x0], [20.0, x0]])
    return pts, np.array([0.0, 40.0])


# --- the water record -------------------------------------------------------------------------


def test_default_water_is_valid_and_presets_grow_murkier():
    assert water_from(None) == Water()
    t = [WATER_PRESETS[k].turbidity for k in ("clear", "moderate", "turbid")]
    assert t == sorted(t) and t[0] < t[2]


@pytest.mark.parametrize(
    "field, value",
    [
        ("turbidity", math.nan),
        ("turbidity", -0.1),
        ("light_falloff", 1.0),
        ("blur", 9.0),
        ("noise", -1.0),
        ("snow", math.inf),
        ("burial", 0.9),
        ("growth", 1.5),
        ("width", 8),
        ("height", 20.5),
        ("pipe_diameter", 0.0),
        ("altitude", 0.1),
    ],
)
def test_bad_water_setting_is_a_one_line_error_naming_the_field(field, value):
    with pytest.raises(WaterError, match=f"^water setting {field} ") as err:
        make_water(**{field: value})
    assert "\n" not in str(err.value)


def test_unknown_water_setting_and_preset_are_refused():
    with pytest.raises(WaterError, match="unknown water setting"):
        make_water(turbidty=0.2)
    with pytest.raises(WaterError, match="preset 'murky'"):
        water_from("murky")
    assert water_from({"preset": "turbid", "burial": 0.3}) == WATER_PRESETS["turbid"]._replace(burial=0.3)


# --- the image's conventions --------------------------------------------------------------------


def test_pixel_centres_follow_the_issue_conventions():
    xs, ys = pixel_centres()
    assert xs[0] == pytest.approx(-1 + 0.5 * 2 / 64) and xs[-1] == pytest.approx(1 - 0.5 * 2 / 64)
    assert ys[0] == pytest.approx(3 - 0.5 * 3 / 96) and ys[-1] == pytest.approx(0.5 * 3 / 96)


@pytest.mark.parametrize("x0", [-0.6, 0.0, 0.45])
def test_pipe_appears_in_the_columns_within_its_radius_of_its_lateral_position(x0):
    rng = np.random.default_rng(3)
    tex = make_textures(rng)
    img = Renderer(STILL).render(*straight_pipe(x0), (0.0, 0.0, 0.0), tex, rng)
    assert img.shape == (96, 64) and img.dtype == np.uint8
    xs, _ = pixel_centres()
    # AUV at the origin heading north: camera x (starboard) is east, the pipe's y coordinate
    inside = np.abs(xs - x0) < 0.125 - 1e-9
    outside = np.abs(xs - x0) > 0.125 + 1e-9
    # coated pipe (albedo ≥ 0.78 × 0.55) against seabed (albedo ≤ 0.95 but mean 0.36): medians per column
    col = np.median(img, axis=0)
    assert col[inside].min() > np.percentile(col[outside], 95)


def test_rows_run_from_the_far_edge_down_to_the_near_edge():
    rng = np.random.default_rng(4)
    tex = make_textures(rng)
    # the pipe ends 1.5 m ahead of the AUV: only rows nearer than 1.5 m (the lower half) show it
    pts, cum = np.array([[-20.0, 0.0], [1.5, 0.0]]), np.array([0.0, 21.5])
    img = Renderer(STILL).render(pts, cum, (0.0, 0.0, 0.0), tex, rng).astype(float)
    _, ys = pixel_centres()
    centre = img[:, 30:34].mean(axis=1)
    assert centre[ys < 1.3].min() > centre[ys > 1.7].max()


def test_same_generator_state_gives_the_same_image_and_another_seed_another():
    def frame(seed):
        rng = np.random.default_rng(seed)
        return Renderer(WATER_PRESETS["moderate"]).render(
            *straight_pipe(0.2), (1.0, 0.0, 0.3), make_textures(rng), rng
        )

    assert np.array_equal(frame(5), frame(5))
    assert not np.array_equal(frame(5), frame(6))


def test_burial_covers_the_pipes_starboard_side():
    rng = np.random.default_rng(8)
    tex = make_textures(rng)
    clean = Renderer(STILL).render(*straight_pipe(0.0), (0.0, 0.0, 0.0), tex, rng).astype(float)
    buried = Renderer(STILL._replace(burial=0.5)).render(*straight_pipe(0.0), (0.0, 0.0, 0.0), tex, rng)
    xs, _ = pixel_centres()
    port, starboard = (xs > -0.1) & (xs < -0.02), (xs > 0.02) & (xs < 0.1)
    # looking north along the pipe, starboard is east = camera +x; burial 0.5 covers x > 0
    assert np.array_equal(buried[:, port], clean[:, port])
    assert buried[:, starboard].mean() < clean[:, starboard].mean() - 20


# --- the detector -------------------------------------------------------------------------------


def random_frames(water: Water, n: int, seed: int, min_visible: float = 1.0):
    """Frames of straight pipes at random offsets and angles whose visible piece is ≥ min_visible long."""
    rng = np.random.default_rng(seed)
    renderer = Renderer(water)
    out, tex = [], None
    while len(out) < n:
        if len(out) % 25 == 0:
            tex = make_textures(rng)
        pts, cum = straight_pipe(rng.uniform(-0.8, 0.8))
        pose = (rng.uniform(-5.0, 5.0), 0.0, rng.uniform(-0.6, 0.6))
        seen, x1, y1, x2, y_near, _, _ = observe(pts, cum, *pose, 20.0 + pose[0], PAPER_CAMERA)
        if not seen or math.hypot(x1 - x2, y1 - y_near) < min_visible:
            continue
        image = renderer.render(pts, cum, pose, tex, rng)
        empty = renderer.render(np.zeros((0, 2)), np.zeros(0), pose, tex, rng)
        out.append((image, empty, (x1, y1, x2, y_near)))
    return out


@pytest.mark.slow  # 300 rendered frames with and without the pipe (≈ 18 s); CI runs it
def test_clear_water_detection_rate_error_and_false_detections():
    frames = random_frames(WATER_PRESETS["clear"], 300, seed=2026)
    errors, found, false = [], 0, 0
    for image, empty, (x1, y1, x2, y_near) in frames:
        det = detect_pipe(image)
        if det.found:
            found += 1
            errors += [math.hypot(det.x1 - x1, det.y1 - y1), math.hypot(det.x2 - x2, det.y_near - y_near)]
        false += detect_pipe(empty).found
    assert found / len(frames) >= 0.98
    assert np.median(errors) <= 0.03
    assert false / len(frames) <= 0.02


@pytest.mark.slow  # 200 rendered frames with and without the pipe (≈ 12 s); CI runs it
def test_half_buried_pipe_is_found_as_its_visible_half():
    # burial 0.5 leaves the pipe's port half in view (test_burial_covers_the_pipes_starboard_side):
    # two edges half a diameter apart, whose centre line lies a quarter diameter to port of the axis
    water = WATER_PRESETS["clear"]._replace(burial=0.5)
    d = water.pipe_diameter
    frames = random_frames(water, 200, seed=2027)
    offsets, found, false = [], 0, 0
    for image, empty, (x1, y1, x2, y_near) in frames:
        det = detect_pipe(image, pipe_diameter=d)
        false += detect_pipe(empty, pipe_diameter=d).found
        if not det.found:
            continue
        found += 1
        # signed distance of the detection's ends to the true axis, to port negative (camera x at y)
        for x, y in ((det.x1, det.y1), (det.x2, det.y_near)):
            t = (y - y_near) / (y1 - y_near) if y1 != y_near else 0.0
            offsets.append(x - (x2 + t * (x1 - x2)))
    assert found / len(frames) >= 0.9
    assert abs(np.median(offsets) - (-0.25 * d)) <= 0.2 * d
    assert false / len(frames) <= 0.02


def test_detector_reads_a_foreign_image_of_another_size_and_footprint():
    cv2 = pytest.importorskip("cv2")
    # a dark pipe on a bright, noisy seabed drawn by OpenCV: 128 × 160 pixels over a 4 m × 4 m footprint
    rng = np.random.default_rng(0)
    img = np.clip(rng.normal(180, 6, (160, 128)), 0, 255).astype(np.uint8)
    # centre line from (x, y) = (−0.5, 0) to (1.0, 4) m; column = (x + 2)/4·128, row = (4 − y)/4·160
    p0, p1 = (int(round(1.5 / 4 * 128)), 160), (int(round(3.0 / 4 * 128)), 0)
    cv2.line(img, p0, p1, 60, thickness=int(round(0.3 / 4 * 128)))
    det = detect_pipe(img, half_width=2.0, depth=4.0, pipe_diameter=0.3)
    assert det.found
    assert det.x1 == pytest.approx(1.0, abs=0.06) and det.y1 == pytest.approx(4.0, abs=0.06)
    assert det.x2 == pytest.approx(-0.5, abs=0.06) and det.y_near == pytest.approx(0.0, abs=0.06)


@pytest.mark.parametrize(
    "image",
    [
        np.zeros((96, 64), np.uint8),
        np.full((96, 64), 255, np.uint8),
        np.random.default_rng(1).integers(0, 256, (96, 64)).astype(np.uint8),
        np.clip(np.random.default_rng(2).normal(100, 20, (96, 64)), 0, 255).astype(np.uint8),
    ],
    ids=["blank", "saturated", "uniform-noise", "gaussian-noise"],
)
def test_blank_saturated_and_noise_images_are_not_found(image):
    assert not detect_pipe(image).found


@pytest.mark.parametrize(
    "image, message",
    [
        (np.zeros((96, 64), np.float32), "dtype uint8, got float32"),
        (np.zeros((96, 64, 3), np.uint8), r"shape \(96, 64, 3\)"),
        (np.zeros((10, 64), np.uint8), r"shape \(10, 64\)"),
        ([[0, 1], [2, 3]], "got list"),
    ],
)
def test_wrong_shape_or_dtype_is_a_one_line_value_error(image, message):
    with pytest.raises(ValueError, match=message) as err:
        detect_pipe(image)
    assert "\n" not in str(err.value)


def test_without_opencv_a_one_line_error_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "cv2", None)
    monkeypatch.setattr(detector, "_CV2", None)
    with pytest.raises(ImportError, match="extra 'vision'"):
        detect_pipe(np.zeros((96, 64), np.uint8))


# --- the detector's tracking (a previous detection) --------------------------------------------


def test_tracking_orders_the_ends_the_way_of_the_previous_detection():
    # a pipe across the view: from (−1, 2) to (1, 2.1); the previous frame had it from port to starboard
    previous = detector.Detection(True, 1.0, 2.0, -1.0, 2.0, 1.0)
    flipped = detector.Detection(True, -1.0, 2.0, 1.0, 2.1, 0.8)
    assert detector.same_way(flipped, previous) == detector.Detection(True, 1.0, 2.1, -1.0, 2.0, 0.8)
    kept = detector.Detection(True, 0.9, 2.2, -1.0, 1.9, 0.8)
    assert detector.same_way(kept, previous) == kept


def test_tracking_adds_no_false_detections_on_frames_without_pipe():
    frames = random_frames(WATER_PRESETS["clear"], 150, seed=7)
    false = 0
    for _, empty, (x1, y1, x2, y_near) in frames:
        # the previous frame saw the pipe where it was; this one has none
        false += detect_pipe(empty, previous=detector.Detection(True, x1, y1, x2, y_near, 1.0)).found
    assert false / len(frames) <= 0.02


def test_texture_cache_gives_a_fresh_draws_tiles_and_leaves_the_generator_where_it_would():
    from pipefollow.perception.textures import TextureCache

    cache = TextureCache(size=2)
    for growth in (True, False):
        fresh = np.random.default_rng(11)
        want = make_textures(fresh, growth)
        after = fresh.random(3)
        for _ in range(2):  # a miss, then a hit
            rng = np.random.default_rng(11)
            got = cache.draw(rng, growth)
            np.testing.assert_array_equal(got.seabed, want.seabed)
            np.testing.assert_array_equal(got.growth, want.growth)
            np.testing.assert_array_equal(rng.random(3), after)
    # without growth the seabed is the same tile and the growth tile is blank
    np.testing.assert_array_equal(
        make_textures(np.random.default_rng(4), False).seabed, make_textures(np.random.default_rng(4)).seabed
    )
    assert not make_textures(np.random.default_rng(4), False).growth.any()
    # the oldest scene leaves when a third comes
    cache.draw(np.random.default_rng(12))
    assert len(cache._scenes) == 2
