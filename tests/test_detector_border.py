"""The detector's second look: short pieces of pipe cut by the view's border."""

from __future__ import annotations

import math

import numpy as np

from pipefollow.perception.detector import detect_pipe
from pipefollow.perception.detector_border import BORDER_CONTRAST, brighter_inside
from pipefollow.perception.image import Renderer
from pipefollow.perception.pixels import pixel_grid
from pipefollow.perception.textures import make_textures
from pipefollow.perception.water import WATER_PRESETS
from pipefollow.sim.camera import PAPER_CAMERA, observe


def across_far_corner(chord: float, angle: float, side: float) -> tuple[np.ndarray, np.ndarray]:
    """A straight 40-m pipe whose centre line cuts a chord of ``chord`` m off a far corner of the view.

    The AUV is at (0, 0) heading along earth x, so camera (lateral, forward) = earth (y, x); the
    line meets the far border (forward 3 m) and the side border (lateral ``side`` m) at
    ``angle`` (rad) to the far border.
    """
    a = np.array([side * (1.0 - chord * math.cos(angle)), 3.0])
    b = np.array([side * 1.0, 3.0 - chord * math.sin(angle)])
    d = (b - a) / np.linalg.norm(b - a)
    lat_fwd = np.array([a - 20.0 * d, a + 20.0 * d])
    return lat_fwd[:, ::-1].copy(), np.array([0.0, 40.0])


def test_a_short_piece_across_a_far_corner_is_found_with_its_ends():
    # the exact camera's piece (sim/camera.py) is the answer; the first look alone (Hough
    # segments ≥ 8 px, support ≥ 0.75 m) found 14 of these 40 pieces, with the second look 28
    renderer = Renderer(WATER_PRESETS["clear"])
    found, first_look, errors = 0, 0, []
    for seed in range(40):
        rng = np.random.default_rng(seed)
        chord, angle = rng.uniform(0.4, 0.8), math.radians(rng.uniform(35.0, 55.0))
        pts, cum = across_far_corner(chord, angle, rng.choice([-1.0, 1.0]))
        seen, x1, y1, x2, y_near, _, _ = observe(pts, cum, 0.0, 0.0, 0.0, 20.0, PAPER_CAMERA)
        assert seen and abs(math.hypot(x1 - x2, y1 - y_near) - chord) < 1e-6
        image = renderer.render(pts, cum, (0.0, 0.0, 0.0), make_textures(rng), rng)
        first_look += detect_pipe(image).found
        det = detect_pipe(image, border_pieces=True)
        if det.found:
            found += 1
            # either order: which end is near is ambiguous on a piece across the view
            kept = max(math.hypot(det.x1 - x1, det.y1 - y1), math.hypot(det.x2 - x2, det.y_near - y_near))
            swapped = max(math.hypot(det.x2 - x1, det.y_near - y1), math.hypot(det.x1 - x2, det.y1 - y_near))
            errors.append(min(kept, swapped))
    assert first_look <= 16
    assert found >= 24
    assert max(errors) <= 0.05


def test_second_look_adds_no_detection_on_frames_without_pipe():
    renderer = Renderer(WATER_PRESETS["clear"])
    rng = np.random.default_rng(7)
    added = 0
    for i in range(150):
        if i % 15 == 0:
            tex = make_textures(rng)
        pose = (rng.uniform(-50.0, 50.0), rng.uniform(-50.0, 50.0), rng.uniform(-3.1, 3.1))
        img = renderer.render(np.zeros((0, 2)), np.zeros(0), pose, tex, rng)
        added += detect_pipe(img, border_pieces=True).found and not detect_pipe(img).found
    assert added <= 1


def test_brighter_inside_asks_the_middle_brighter_than_both_sides_in_view():
    grid = pixel_grid(1.0, 3.0, 96, 64)
    img = np.full((96, 64), 100, dtype=np.uint8)
    img[:, 28:36] = 100 + int(BORDER_CONTRAST) + 10  # a bright vertical band, x ∈ [−0.125, 0.125)
    ends = np.array([[0.0, 0.5], [0.0, 2.5]])  # along the band's middle
    assert brighter_inside(img, grid, ends, 1.0, 0.0, 0.3)
    assert not brighter_inside(255 - img, grid, ends, 1.0, 0.0, 0.3)  # a dark band is no pipe
    # a band no brighter than the seabed beside it
    flat = np.full((96, 64), 100, dtype=np.uint8)
    assert not brighter_inside(flat, grid, ends, 1.0, 0.0, 0.3)
    # along the left border one side lies outside the image: the side in view decides
    left = np.array([[-0.95, 0.5], [-0.95, 2.5]])
    img2 = np.full((96, 64), 100, dtype=np.uint8)
    img2[:, :4] = 130
    assert brighter_inside(img2, grid, left, 1.0, 0.0, 0.3)
