"""Pipelines: arc length, lookup, projection, mirroring, files, built-ins, the random generator."""

import json
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from pipefollow.sim import pipeline as pl
from pipefollow.sim.pipe_names import resolve_fixed
from pipefollow.sim.pipeline import Pipeline, PipelineError, builtin, load, random_pipeline


@pytest.fixture
def bent():
    # a 3-4-5 segment, then 6 m east
    return Pipeline(np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 10.0]]), "bent")


@pytest.fixture
def u_pipe():
    # 10 m north, 1 m east, 10 m back south: the return leg runs 1 m east of the first
    return Pipeline(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 1.0], [0.0, 1.0]]), "u")


def segment_lengths(points):
    return np.hypot(*np.diff(points, axis=0).T)


def turn_angles_deg(points):
    """Heading change at each interior vertex, positive to starboard (clockwise from north)."""
    d = np.diff(points, axis=0)
    headings = np.arctan2(d[:, 1], d[:, 0])
    turns = np.diff(headings)
    return np.degrees((turns + np.pi) % (2 * np.pi) - np.pi)


def test_arc_length_and_cumulative(bent):
    assert_allclose(bent.cumulative, [0.0, 5.0, 11.0])
    assert bent.length == pytest.approx(11.0)
    assert bent.start_heading == pytest.approx(math.atan2(4.0, 3.0))


def test_points_are_immutable(bent):
    with pytest.raises(ValueError):
        bent.points[0, 0] = 1.0
    with pytest.raises(ValueError):
        bent.cumulative[0] = 1.0


@pytest.mark.parametrize(
    ("s", "expected"),
    [
        (0.0, (0.0, 0.0)),
        (2.5, (1.5, 2.0)),
        (5.0, (3.0, 4.0)),
        (8.0, (3.0, 7.0)),
        (11.0, (3.0, 10.0)),
        (-3.0, (0.0, 0.0)),  # clipped to the ends
        (20.0, (3.0, 10.0)),
    ],
)
def test_point_at(bent, s, expected):
    assert_allclose(bent.point_at(s), expected, atol=1e-12)


@pytest.mark.parametrize(
    ("xy", "s", "dist"),
    [
        ((4.0, 7.0), 8.0, 1.0),  # 1 m north of the second segment
        ((1.5 + 0.8, 2.0 - 0.6), 2.5, 1.0),  # 1 m off the first segment, normal (0.8, -0.6)
        ((-3.0, -4.0), 0.0, 5.0),  # behind the start
        ((3.0, 13.0), 11.0, 3.0),  # beyond the end
        ((3.0, 4.0), 5.0, 0.0),  # on the vertex
    ],
)
def test_project_global(bent, xy, s, dist):
    got_s, got_d = bent.project(*xy)
    assert got_s == pytest.approx(s, abs=1e-12)
    assert got_d == pytest.approx(dist, abs=1e-12)


def test_project_windowed_keeps_the_nearby_leg(u_pipe):
    pts, cum = u_pipe.points, u_pipe.cumulative
    # (5, 0.6) is 0.4 m from the return leg (s = 11 + 5 = 16) but 0.6 m from the first leg (s = 5)
    assert pl.project(pts, cum, 5.0, 0.6, -np.inf, np.inf) == pytest.approx(16.0)
    assert u_pipe.project(5.0, 0.6) == pytest.approx((16.0, 0.4))
    assert pl.project(pts, cum, 5.0, 0.6, 3.0, 8.0) == pytest.approx(5.0)
    # the window also clamps within a segment: closest allowed point of [0, 3] is s = 3
    assert pl.project(pts, cum, 5.0, 0.0, 0.0, 3.0) == pytest.approx(3.0)
    # and from below: window [14, 21] on the return leg, point level with s = 18 on the first leg
    assert pl.project(pts, cum, 3.0, 0.0, 14.0, 21.0) == pytest.approx(18.0)
    # and the window's start clamps within a segment: unclamped this would be s = 12
    assert pl.project(pts, cum, 9.0, 1.0, 14.0, 21.0) == pytest.approx(14.0)
    # window on the connecting 1-m segment only
    assert pl.project(pts, cum, 5.0, 0.5, 10.2, 10.8) == pytest.approx(10.5)


def test_builtin_paper_left_geometry():
    p = builtin("paper-left")
    # x north, y east; left turns go towards negative y
    assert_allclose(p.points, [[0, 0], [2, 0], [2, -2.5], [-6, -2.5]], atol=1e-12)
    assert_allclose(turn_angles_deg(p.points), [-90.0, -90.0], atol=1e-9)
    assert p.start_heading == pytest.approx(0.0)


def test_builtin_paper_right_is_paper_left_mirrored():
    left, right = builtin("paper-left"), builtin("paper-right")
    assert_allclose(right.points, left.points * [1.0, -1.0], atol=1e-12)
    assert_allclose(right.points, [[0, 0], [2, 0], [2, 2.5], [-6, 2.5]], atol=1e-12)
    assert_allclose(turn_angles_deg(right.points), [90.0, 90.0], atol=1e-9)
    assert right.name == "paper-right"


def test_builtin_paper_validation_geometry():
    p = builtin("paper-validation")
    turns = turn_angles_deg(p.points)
    assert_allclose(np.sort(np.unique(np.round(np.abs(turns), 9))), [45.0, 90.0])
    assert np.any(turns > 0) and np.any(turns < 0)  # turns to both sides
    # segments 3–6 m; the last one is a longer run-out
    seg = segment_lengths(p.points)[:-1]
    assert np.all((seg >= 3.0 - 1e-9) & (seg <= 6.0 + 1e-9))


def test_unknown_builtin():
    with pytest.raises(PipelineError, match="paper-nowhere"):
        builtin("paper-nowhere")


def test_mirror_of_a_tilted_pipeline():
    # start heading 45°: mirror across the line x = y through (1, 1)
    p = Pipeline(np.array([[1.0, 1.0], [2.0, 2.0], [2.0, 3.0]]))
    m = p.mirror()
    # (2, 3) is (1, 2) from the start; its mirror across the diagonal is (2, 1) → (3, 2)
    assert_allclose(m.points, [[1, 1], [2, 2], [3, 2]], atol=1e-12)
    assert m.length == pytest.approx(p.length)
    assert_allclose(turn_angles_deg(m.points), -turn_angles_deg(p.points), atol=1e-9)
    assert_allclose(m.mirror().points, p.points, atol=1e-12)


def test_save_load_round_trip(tmp_path, bent):
    path = tmp_path / "sub" / "bent.json"
    bent.save(path)
    data = json.loads(path.read_text())
    assert data == {"points": [[0.0, 0.0], [3.0, 4.0], [3.0, 10.0]]}
    back = load(path)
    assert_array_equal(back.points, bent.points)
    assert_array_equal(back.cumulative, bent.cumulative)
    assert back.name == "bent"
    # no temporary files left behind
    assert sorted(f.name for f in path.parent.iterdir()) == ["bent.json"]


def test_save_load_round_trip_random(tmp_path):
    p = random_pipeline(np.random.default_rng(5), n_segments=6)
    p.save(tmp_path / "r.json")
    assert_array_equal(load(tmp_path / "r.json").points, p.points)


def test_resolve(tmp_path, bent):
    assert resolve_fixed(bent) is bent
    assert_array_equal(resolve_fixed("paper-left").points, builtin("paper-left").points)
    bent.save(tmp_path / "b.json")
    assert_array_equal(resolve_fixed(str(tmp_path / "b.json")).points, bent.points)
    with pytest.raises(PipelineError, match="nope"):
        resolve_fixed("nope")


def test_random_pipeline_is_reproducible():
    a = random_pipeline(np.random.default_rng(123), n_segments=8)
    b = random_pipeline(np.random.default_rng(123), n_segments=8)
    c = random_pipeline(np.random.default_rng(124), n_segments=8)
    assert_array_equal(a.points, b.points)
    assert not np.allclose(a.points[1:], c.points[1:])


@pytest.mark.parametrize("seed", range(5))
def test_random_pipeline_within_ranges(seed):
    n, lengths, turns = 12, (2.0, 4.5), (20.0, 70.0)
    p = random_pipeline(np.random.default_rng(seed), n, lengths, turns)
    assert p.points.shape == (n + 1, 2)
    assert_allclose(p.points[0], [0.0, 0.0])
    seg = segment_lengths(p.points)
    assert np.all((seg >= lengths[0] - 1e-9) & (seg <= lengths[1] + 1e-9))
    t = np.abs(turn_angles_deg(p.points))
    assert np.all((t >= turns[0] - 1e-9) & (t <= turns[1] + 1e-9))


def test_random_pipeline_turns_both_ways():
    t = np.concatenate(
        [turn_angles_deg(random_pipeline(np.random.default_rng(s), 10).points) for s in range(3)]
    )
    assert np.any(t > 0) and np.any(t < 0)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"n_segments": 0},
        {"length_range": (0.0, 3.0)},
        {"length_range": (5.0, 3.0)},
        {"turn_range_deg": (50.0, 30.0)},
        {"turn_range_deg": (-10.0, 30.0)},
        {"turn_range_deg": (30.0, 190.0)},
    ],
)
def test_random_pipeline_rejects_bad_arguments(kwargs):
    with pytest.raises(ValueError):
        random_pipeline(np.random.default_rng(0), **kwargs)


def _write(tmp_path, text, name="bad.json"):
    path = tmp_path / name
    path.write_text(text)
    return path


BAD_FILES = {
    "not JSON": ("{points: [[0, 0], [1, 0]]", "JSON"),
    "no points": ('{"pts": [[0, 0], [1, 0]]}', "points"),
    "a list, not an object": ("[[0, 0], [1, 0]]", "points"),
    "one point": ('{"points": [[0, 0]]}', "two distinct points"),
    "no points at all": ('{"points": []}', "two distinct points"),
    "integer beyond float range": ('{"points": [[0, 0], [1, 1' + "0" * 400 + "]]}", "too large"),
    "NaN": ('{"points": [[0, 0], [NaN, 1]]}', "NaN"),
    "infinity": ('{"points": [[0, 0], [1, Infinity]]}', "infinite"),
    "overflow to infinity": ('{"points": [[0, 0], [1e999, 1]]}', "infinite"),
    "zero-length segment": ('{"points": [[0, 0], [1, 0], [1, 0], [2, 0]]}', "zero-length segment"),
    "triple": ('{"points": [[0, 0], [1, 0, 2]]}', "pairs"),
    "single number rows": ('{"points": [0, 1, 2]}', "pairs"),
    "string coordinate": ('{"points": [[0, 0], [1, "2"]]}', "pairs"),
    "boolean coordinate": ('{"points": [[0, 0], [1, true]]}', "pairs"),
    "points not a list": ('{"points": "0,0 1,0"}', "pairs"),
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_load_bad_file(tmp_path, case):
    text, problem = BAD_FILES[case]
    path = _write(tmp_path, text)
    with pytest.raises(PipelineError) as info:
        load(path)
    message = str(info.value)
    assert str(path) in message
    assert problem.lower() in message.lower()
    assert "\n" not in message


def test_load_all_points_identical(tmp_path):
    path = _write(tmp_path, '{"points": [[1, 1], [1, 1], [1, 1]]}')
    with pytest.raises(PipelineError) as info:
        load(path)
    message = str(info.value)
    assert str(path) in message and "\n" not in message
    assert "distinct" in message or "zero-length" in message


def test_load_missing_file(tmp_path):
    path = tmp_path / "missing.json"
    with pytest.raises(PipelineError) as info:
        load(path)
    message = str(info.value)
    assert str(path) in message and "no such file" in message and "\n" not in message


def test_pipeline_constructor_validates():
    with pytest.raises(PipelineError, match="two distinct"):
        Pipeline(np.zeros((1, 2)), "one")
    with pytest.raises(PipelineError, match="zero-length"):
        Pipeline(np.array([[0.0, 0.0], [0.0, 0.0]]), "dup")
    with pytest.raises(PipelineError, match="NaN"):
        Pipeline(np.array([[0.0, 0.0], [np.nan, 0.0]]), "nan")
    with pytest.raises(PipelineError, match="pairs"):
        Pipeline(np.zeros((3, 3)), "triples")


def test_utf8_file_with_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + b'{"points": [[0, 0], [3, 4]]}')
    assert load(path).length == 5.0


@pytest.mark.parametrize("data", ['{"points": [[0, 0], [3, 4]]}'.encode("utf-16"), b"\x80\x81\xfe"])
def test_file_that_is_not_utf8_gives_a_pipeline_error(tmp_path, data):
    path = tmp_path / "p.json"
    path.write_bytes(data)
    with pytest.raises(PipelineError, match=r"p.json'?: not UTF-8 text"):
        load(path)
