"""The tracker's memory of the pieces it showed (pipefollow.perception.piece_memory)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pipefollow.perception.piece_memory import MemoryParams, PieceMemory
from pipefollow.perception.track_step import ACCEPTED, BEND, NO_DETECTION, OUT_SIZE, REJECTED, moved
from pipefollow.perception.tracker import PipeTracker
from pipefollow.sim.camera import to_camera


def exact_motion(before, after):
    """The navigation's (Δl, Δf, Δψ) without errors: the displacement in the earlier frame's axes."""
    x0, y0, psi0 = before
    dx, dy = after[0] - x0, after[1] - y0
    c, s = math.cos(psi0), math.sin(psi0)
    return np.array([-s * dx + c * dy, c * dx + s * dy, math.remainder(after[2] - psi0, 2 * math.pi)])


def output(in_view, x1=0.0, y1=0.0, x2=0.0, y_near=0.0, side=1.0):
    out = np.zeros(OUT_SIZE)
    out[:6] = (1.0 if in_view else 0.0, x1, y1, x2, y_near, side)
    return out


def test_moved_point_is_the_world_point_seen_from_the_new_pose():
    rng = np.random.default_rng(7)
    for _ in range(50):
        a = (rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-math.pi, math.pi))
        b = (a[0] + rng.uniform(-1, 1), a[1] + rng.uniform(-1, 1), a[2] + rng.uniform(-0.8, 0.8))
        p = rng.uniform(-4, 4, size=2)
        lat, fwd = to_camera(p[0], p[1], *a)
        dl, df, dpsi = exact_motion(a, b)
        got = moved(lat, fwd, dl, df, math.cos(dpsi), math.sin(dpsi))
        np.testing.assert_allclose(got, to_camera(p[0], p[1], *b), atol=1e-12)


def test_a_remembered_piece_is_shown_moved_and_clipped_where_the_track_shows_none():
    mem = PieceMemory(MemoryParams(size=4, seconds=10, min_piece=0.05))
    still = np.zeros(3)
    mem.step(still, ACCEPTED, output(True, 0.5, 3.0, 0.5, 0.0))  # a straight piece 0.5 m to starboard
    # one metre forward, the track shows nothing: the piece now runs from y = -1 to 2, clipped at 0
    out = mem.step(np.array([0.0, 1.0, 0.0]), NO_DETECTION, output(False, side=-1.0))
    np.testing.assert_allclose(out[:6], [1.0, 0.5, 2.0, 0.5, 0.0, 1.0], atol=1e-12)
    # a quarter turn to port on the spot: the far end (0.5, 2) is now at (2, -0.5), the near end
    # (0.5, -1) at (-1, -0.5): the piece lies behind the vehicle's centre, out of the footprint
    out = mem.step(np.array([0.0, 0.0, -math.pi / 2]), NO_DETECTION, output(False))
    assert out[0] == 0.0
    np.testing.assert_allclose(mem.remembered()[0, :4], [2.0, -0.5, -1.0, -0.5], atol=1e-12)


def test_the_shown_pipe_is_kept_not_overwritten():
    mem = PieceMemory()
    mem.step(np.zeros(3), ACCEPTED, output(True, 0.1, 3.0, 0.0, 0.0))
    shown = output(True, -0.3, 2.0, -0.2, 0.0, -1.0)
    out = mem.step(np.zeros(3), REJECTED, shown.copy())
    np.testing.assert_array_equal(out, shown)


def test_only_taken_detections_are_remembered_and_the_newest_is_shown():
    mem = PieceMemory(MemoryParams(size=4, seconds=10, min_piece=0.05))
    mem.step(np.zeros(3), ACCEPTED, output(True, -0.5, 3.0, -0.5, 0.0))
    mem.step(np.zeros(3), REJECTED, output(True, 0.9, 3.0, 0.9, 0.0))  # shown, but no detection taken
    mem.step(np.zeros(3), BEND, output(True, 0.2, 2.5, 0.0, 0.0))
    assert len(mem.remembered()) == 2
    out = mem.step(np.zeros(3), NO_DETECTION, output(False))
    np.testing.assert_allclose(out[1:5], [0.2, 2.5, 0.0, 0.0])


def test_pieces_are_forgotten_after_their_time_and_short_crossings_are_not_shown():
    mem = PieceMemory(MemoryParams(size=4, seconds=3, min_piece=0.2))
    mem.step(np.zeros(3), ACCEPTED, output(True, 0.0, 3.0, 0.0, 0.0))
    for _ in range(3):
        assert mem.step(np.zeros(3), NO_DETECTION, output(False))[0] == 1.0
    assert mem.step(np.zeros(3), NO_DETECTION, output(False))[0] == 0.0  # 4 frames old: forgotten
    assert len(mem.remembered()) == 0
    # a piece left with 0.1 m in the footprint (< min_piece) is not shown
    mem.reset()
    mem.step(np.zeros(3), ACCEPTED, output(True, 0.0, 3.0, 0.0, 0.0))
    assert mem.step(np.array([0.0, 2.9, 0.0]), NO_DETECTION, output(False))[0] == 0.0


def test_size_bounds_what_is_kept():
    mem = PieceMemory(MemoryParams(size=2, seconds=10, min_piece=0.05))
    for k in range(5):
        mem.step(np.zeros(3), ACCEPTED, output(True, 0.1 * k, 3.0, 0.0, 0.0))
    np.testing.assert_allclose(mem.remembered()[:, 0], [0.4, 0.3])


@pytest.mark.parametrize(
    "bad", [MemoryParams(size=0), MemoryParams(seconds=-1.0), MemoryParams(min_piece=-0.1)]
)
def test_bad_settings_are_refused(bad):
    with pytest.raises(ValueError, match="MemoryParams"):
        PieceMemory(bad)


def test_tracker_without_memory_loses_what_the_memory_shows():
    """A straight pipe seen once, then no detections: the line is lost, the memory still shows it."""
    with_mem, without = PipeTracker(), PipeTracker(memory=None)
    for t in (with_mem, without):
        t.reset(np.random.default_rng(1), (0.0, 0.0, 0.0))
    det = (0.0, 3.0, 0.0, 0.0)  # the pipe along the track, under the vehicle
    shown = []
    for k in range(8):
        pose = (0.45 * k, 0.0, 0.0)  # straight north along the pipe
        found = k < 2
        a = with_mem.step(pose, found, det).copy()
        b = without.step(pose, found, det).copy()
        if found:
            np.testing.assert_array_equal(a, b)  # the memory changes nothing while the track shows the pipe
        shown.append((a[0], b[0]))
    # the line is carried max_misses frames, then lost; the memory shows the pipe until it slides out
    assert any(a == 1.0 and b == 0.0 for a, b in shown)
