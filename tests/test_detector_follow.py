"""The detector through bends and curves: following the pipe beyond its strongest straight leg."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pipefollow.perception.detector import detect_pipe
from pipefollow.perception.follow import STEP_PX, follow_pipe
from pipefollow.perception.image import Renderer
from pipefollow.perception.textures import make_textures
from pipefollow.perception.water import WATER_PRESETS
from pipefollow.sim.camera import PAPER_CAMERA, observe

PX = 3.0 / 96  # metres per pixel of the default 64 × 96 image (square pixels)


def polyline(points: list[tuple[float, float]]) -> tuple[np.ndarray, np.ndarray]:
    """Earth points for an AUV at (0, 0) heading along earth x: camera (lateral, forward) = (y, x)."""
    pts = np.array([[fwd, lat] for lat, fwd in points], dtype=float)
    return pts, np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])


def l_bend(turn_deg: float, lat0: float, vertex_fwd: float) -> tuple[np.ndarray, np.ndarray]:
    """A pipe up the view at lateral ``lat0`` that turns by ``turn_deg`` to starboard at ``vertex_fwd``."""
    a = math.radians(turn_deg)
    return polyline(
        [(lat0, -20.0), (lat0, vertex_fwd), (lat0 + 10.0 * math.sin(a), vertex_fwd + 10.0 * math.cos(a))]
    )


def distance_to_segment(p, a, b) -> float:
    """Distance from point p to segment a–b (hand geometry, independent of the detector)."""
    p, a, b = (np.asarray(v, float) for v in (p, a, b))
    t = np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    return float(np.linalg.norm(p - (a + t * (b - a))))


@pytest.mark.parametrize("turn", [30.0, 45.0, 60.0, 90.0])
def test_far_end_of_a_rendered_l_bend_lies_on_the_second_leg(turn):
    # the exact camera's far end is where the second leg leaves the footprint; a detector that
    # reports one straight leg puts it at the vertex or on the first leg's line, ≥ 0.3 m off
    renderer = Renderer(WATER_PRESETS["clear"])
    far_errors, near_errors, off_leg = [], [], []
    for seed in range(8):
        rng = np.random.default_rng(seed)
        lat0, vertex_fwd = rng.uniform(-0.6, -0.2), rng.uniform(1.0, 1.8)
        pts, cum = l_bend(turn, lat0, vertex_fwd)
        seen, x1, y1, x2, y_near, _, _ = observe(pts, cum, 0.0, 0.0, 0.0, 20.0, PAPER_CAMERA)
        assert seen
        det = detect_pipe(renderer.render(pts, cum, (0.0, 0.0, 0.0), make_textures(rng), rng))
        assert det.found
        far_errors.append(math.hypot(det.x1 - x1, det.y1 - y1))
        near_errors.append(math.hypot(det.x2 - x2, det.y_near - y_near))
        vertex = (lat0, vertex_fwd)
        second_leg_end = (
            lat0 + 10.0 * math.sin(math.radians(turn)),
            vertex_fwd + 10.0 * math.cos(math.radians(turn)),
        )
        off_leg.append(distance_to_segment((det.x1, det.y1), vertex, second_leg_end))
        # beyond the vertex along the second leg, not at it
        assert math.hypot(det.x1 - lat0, det.y1 - vertex_fwd) > 0.3
    assert np.median(far_errors) <= 0.03
    assert np.median(near_errors) <= 0.03
    assert np.median(off_leg) <= 0.03
    assert max(off_leg) <= 0.15  # a far end near the footprint's corner may go out on the other side


def test_far_end_of_a_rendered_arc_is_where_it_leaves_the_footprint():
    # a circular arc of radius 2.5 m (5° chords) through the view: the straight leg is a piece of it
    renderer = Renderer(WATER_PRESETS["clear"])
    errors = []
    for seed in range(6):
        rng = np.random.default_rng(100 + seed)
        cx = rng.uniform(2.2, 2.6)  # the arc's centre, to starboard at forward 0
        angles = np.radians(np.arange(-120.0, 61.0, 5.0))
        lat = cx - 2.5 * np.cos(angles)
        fwd = 2.5 * np.sin(angles)
        pts, cum = polyline(list(zip(lat, fwd, strict=True)))
        seen, x1, y1, x2, y_near, _, _ = observe(pts, cum, 0.0, 0.0, 0.0, cum[-1] / 2, PAPER_CAMERA)
        assert seen and math.hypot(x1 - x2, y1 - y_near) > 1.5
        det = detect_pipe(renderer.render(pts, cum, (0.0, 0.0, 0.0), make_textures(rng), rng))
        assert det.found
        errors += [math.hypot(det.x1 - x1, det.y1 - y1), math.hypot(det.x2 - x2, det.y_near - y_near)]
    assert np.median(errors) <= 0.03
    assert max(errors) <= 0.3  # no gross error (a walk that stops short keeps the leg's end)


def edge_image(lines, shape=(96, 64)) -> np.ndarray:
    """An edge image with the given pixel runs set: (row0, row1, col) vertical, (row, col0, col1) not."""
    edges = np.zeros(shape, np.uint8)
    for kind, a, b, c in lines:
        if kind == "v":
            edges[a:b, c] = 255
        else:
            edges[a, b:c] = 255
    return edges


def test_walk_stops_where_the_two_edges_end():
    # two edges 8 px apart (columns 28 and 36) from row 40 down to the bottom: the pipe's end is
    # at row 40, y = 3 − 40 · 3/96 = 1.75 m; the walk starts at y = 0.5 on the centre line going up
    edges = edge_image([("v", 40, 96, 28), ("v", 40, 96, 36)])
    x_centre = -1.0 + 32.5 * PX
    x, y, steps, *_ = follow_pipe(edges, x_centre, 0.5, 0.0, 1.0, 4 * PX, 1.0, 3.0, 100)
    assert x == pytest.approx(x_centre, abs=1.5 * PX)
    assert 1.75 - STEP_PX * PX - PX <= y <= 1.75 + PX  # stops within a step (and a pixel) of the end
    assert steps == pytest.approx((1.75 - 0.5) / (STEP_PX * PX), abs=1.0)


def test_walk_turns_a_bend_and_ends_on_the_border():
    # edges 8 px apart up columns 28/36, then both turning 45° to starboard (the outer edge at row
    # 42, the inner at row 46, as offset lines of a centre line that turns at pixel (32, 44)) to the
    # right border; in continuous pixel units (centres at index + 0.5) the centre line leaves
    # through x = 1 (column 64) at row 44.5 − 31.5 = 13, y = 3 − 13 · 3/96 ≈ 2.594 m
    cv2 = pytest.importorskip("cv2")
    edges = np.zeros((96, 64), np.uint8)
    for (c0, r0), (c1, r1), (c2, r2) in (((28, 95), (28, 42), (63, 7)), ((36, 95), (36, 46), (63, 19))):
        cv2.line(edges, (c0, r0), (c1, r1), 255)
        cv2.line(edges, (c1, r1), (c2, r2), 255)
    x, y, steps, *_ = follow_pipe(edges, -1.0 + 32.5 * PX, 0.5, 0.0, 1.0, 4 * PX, 1.0, 3.0, 100)
    assert x == pytest.approx(1.0)
    assert y == pytest.approx(3.0 - 13.0 * PX, abs=2 * PX)
    assert steps > 0


def test_walk_does_not_follow_a_single_edge_or_texture():
    # one edge alone (a shadow, a seabed ridge) is not a pipe: no step is taken
    edges = edge_image([("v", 0, 96, 28)])
    assert follow_pipe(edges, -1.0 + 32.5 * PX, 0.5, 0.0, 1.0, 4 * PX, 1.0, 3.0, 100)[2] == 0
    # nor scattered edge pixels: 3 % of the pixels, twice the most Canny left on 100 pipe-free
    # clear-water frames (1.4 %, mean 0.4 %)
    for seed in range(5):
        noise = (np.random.default_rng(seed).random((96, 64)) < 0.03).astype(np.uint8) * 255
        assert follow_pipe(noise, 0.0, 0.5, 0.0, 1.0, 4 * PX, 1.0, 3.0, 100)[2] <= 1


@pytest.mark.parametrize("turn", [110.0, 135.0, 150.0])
def test_far_end_of_a_rendered_hook_lies_after_the_corner(turn):
    # a hook sharper than the walk can turn: the second leg that starts at the walk's stop carries
    # the far end on to where the exact camera has it (the first leg's corner is ≥ 0.8 m from it)
    renderer = Renderer(WATER_PRESETS["clear"])
    for seed in range(8):
        rng = np.random.default_rng(seed)
        lat0, vertex_fwd = rng.uniform(-0.2, 0.2), rng.uniform(1.6, 2.4)
        pts, cum = l_bend(turn, lat0, vertex_fwd)
        seen, x1, y1, x2, y_near, _, _ = observe(pts, cum, 0.0, 0.0, 0.0, 20.0, PAPER_CAMERA)
        assert seen and math.hypot(x1 - lat0, y1 - vertex_fwd) > 0.8
        det = detect_pipe(renderer.render(pts, cum, (0.0, 0.0, 0.0), make_textures(rng), rng))
        assert det.found
        assert math.hypot(det.x1 - x1, det.y1 - y1) < 0.2, seed
        assert math.hypot(det.x2 - x2, det.y_near - y_near) < 0.2, seed
