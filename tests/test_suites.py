"""Pipeline suites: seeded, reproducible, within their levels, held-out disjoint from training."""

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.sim.pipe_names import parse_random_spec
from pipefollow.sim.pipeline import BUILTIN_NAMES, load
from pipefollow.sim.suites import (
    HELDOUT_STREAM,
    LEVELS,
    MAX_HEADING_DEG,
    MIN_LENGTH_M,
    SUITES,
    TRAIN_STREAM,
    SuiteError,
    draw_index,
    get_suite,
    min_length_for,
    seed_sequence,
)


def _headings(points):
    d = np.diff(points, axis=0)
    return np.arctan2(d[:, 1], d[:, 0])


def test_heldout_suites_have_at_least_100_pipes_long_enough_for_a_minute():
    for name, suite in SUITES.items():
        if not suite.is_training:
            pipes = suite.pipes()
            assert len(pipes) >= 100, name
            # 60 s at well above the 0.48 m/s cruise speed
            assert min(p.length for p in pipes) >= max(MIN_LENGTH_M, 60 * 0.6), name
            assert len({p.name for p in pipes}) == len(pipes)


@pytest.mark.parametrize("level", ["easy", "medium", "hard"])
def test_pipes_stay_within_their_level(level):
    lv = LEVELS[level]
    for pipe in get_suite(level).pipes(50):
        h = _headings(pipe.points)
        # the first segment is a straight heading north; the heading never exceeds the bound
        assert h[0] == 0.0
        assert np.degrees(np.abs(h)).max() <= MAX_HEADING_DEG + 1e-9
        turns = np.degrees(np.abs(np.angle(np.exp(1j * np.diff(h)))))
        assert turns.max() <= lv.turn_deg[1] + 1e-9
        seg = np.hypot(*np.diff(pipe.points, axis=0).T)
        straight = seg[seg > 2 * lv.radius_m[1] * math.sin(math.radians(5.0)) + 1e-9]
        assert straight.min() >= lv.straight_m[0] - 1e-9
        assert seg.max() <= lv.straight_m[1] + 1e-9


def test_arcs_are_discretized_in_small_steps_and_corners_are_sharp():
    pipes = get_suite("medium").pipes(40)
    turns = np.concatenate([np.degrees(np.abs(np.diff(_headings(p.points)))) for p in pipes])
    assert np.any(turns > 30.0 - 1e-9)  # sharp corners with the full turn
    assert np.any((turns > 0.0) & (turns <= 10.0 + 1e-9))  # pieces of arcs


def test_pipes_are_reproducible_and_a_longer_pipe_extends_the_shorter():
    s = get_suite("hard")
    a, b = s.pipe(7), s.pipe(7)
    np.testing.assert_array_equal(a.points, b.points)
    assert not np.array_equal(s.pipe(8).points[:5], a.points[:5])
    long = s.pipe(7, min_length=200.0)
    assert long.length >= 200.0
    np.testing.assert_array_equal(long.points[: len(a.points)], a.points)
    assert min_length_for(60.0) == MIN_LENGTH_M and min_length_for(600.0) > 360.0


def test_heldout_pipes_are_disjoint_from_training_by_construction():
    # the seeds' entropy differs in the stream word, for any index a training draw can give
    rng = np.random.default_rng(0)
    train_keys = {tuple(seed_sequence("mixed", TRAIN_STREAM, draw_index(rng)).entropy) for _ in range(5000)}
    train_keys |= {tuple(seed_sequence("mixed", TRAIN_STREAM, k).entropy) for k in range(1000)}
    held = get_suite("heldout")
    held_keys = {tuple(seed_sequence(held.family, held.stream, k).entropy) for k in range(held.count)}
    assert held.stream == HELDOUT_STREAM != TRAIN_STREAM
    assert not train_keys & held_keys
    # and the pipes themselves differ: no held-out pipe is among the first training pipes
    for level in ("easy", "medium", "hard"):
        heldout = {get_suite(f"heldout-{level}").pipe(k).points.tobytes() for k in range(100)}
        train = {get_suite(level).pipe(k).points.tobytes() for k in range(300)}
        assert not heldout & train


def test_training_draws_come_from_the_generator():
    s = get_suite("mixed")
    a = [s.draw(np.random.default_rng(5)).points for _ in range(2)]
    np.testing.assert_array_equal(a[0], a[1])
    rng = np.random.default_rng(5)
    assert not np.array_equal(s.draw(rng).points, s.draw(rng).points)


def test_random_specs():
    assert parse_random_spec("random").name == "mixed"
    assert parse_random_spec("random:hard").name == "hard"
    assert parse_random_spec("paper-left") is None
    with pytest.raises(SuiteError, match="held-out"):
        parse_random_spec("random:heldout")
    with pytest.raises(SuiteError, match="unknown"):
        parse_random_spec("random:nope")
    with pytest.raises(SuiteError, match="'nope'"):
        get_suite("nope")
    with pytest.raises(IndexError):
        get_suite("heldout").pipe(100)


def test_cli_lists_and_exports_suites(tmp_path):
    runner = CliRunner()
    res = runner.invoke(main, ["suites", "--json"])
    assert res.exit_code == 0, res.output
    rows = {r["name"]: r for r in json.loads(res.stdout)["suites"]}
    assert rows["heldout"]["count"] == 100 and rows["heldout"]["kind"] == "heldout"
    assert rows["hard"]["count"] is None and rows["hard"]["turn_deg"] == [45.0, 90.0]
    assert not set(rows) & set(BUILTIN_NAMES)
    res = runner.invoke(
        main, ["suites", "export", "heldout-hard", "--out", str(tmp_path / "x"), "--pipes", "3"]
    )
    assert res.exit_code == 0, res.output
    files = sorted((tmp_path / "x").iterdir())
    assert [f.name for f in files] == [f"heldout-hard-00{k}.json" for k in range(3)]
    np.testing.assert_array_equal(load(files[2]).points, get_suite("heldout-hard").pipe(2).points)


@pytest.mark.parametrize(
    "args",
    [
        ["suites", "export", "nope", "--out", "OUT"],
        ["suites", "export", "heldout", "--out", "OUT", "--pipes", "101"],
    ],
)
def test_cli_suite_errors_are_one_line_and_write_nothing(tmp_path, args):
    out = tmp_path / "out"
    res = CliRunner().invoke(main, [str(out) if a == "OUT" else a for a in args])
    assert res.exit_code == 2
    assert res.stderr.startswith("pipefollow: error: ") and res.stderr.count("\n") == 1
    assert not out.exists() or not any(out.iterdir())


def test_sharp_pipes_have_corners_of_90_to_150_degrees_short_straights_and_never_cross():
    from pipefollow.sim.suites import SHARP_MAX_HEADING_DEG, _segment_gap

    lv = LEVELS["sharp"]
    suite = get_suite("heldout-sharp")
    assert suite.count == 100 and not suite.is_training
    for pipe in suite.pipes(30):
        p = pipe.points
        h = _headings(p)
        turns = np.degrees(np.abs(np.angle(np.exp(1j * np.diff(h)))))
        assert turns.min() >= 90.0 - 1e-9 and turns.max() <= 150.0 + 1e-9  # corners only, no arcs
        assert np.degrees(np.abs(h)).max() <= SHARP_MAX_HEADING_DEG + 1e-9
        seg = np.hypot(*np.diff(p, axis=0).T)
        assert seg.min() >= lv.straight_m[0] - 1e-9 and seg.max() <= lv.straight_m[1] + 1e-9
        # straights that do not meet stay apart (no crossing): at a hook of ≤ 150° after a straight
        # of ≥ 3 m the next-but-one straight passes 3·sin(30°) = 1.5 m from the first at the least
        for j in range(len(p) - 1):
            for i in range(j - 1):
                assert _segment_gap(p[i], p[i + 1], p[j], p[j + 1]) > 1.5 - 1e-9
    np.testing.assert_array_equal(suite.pipe(3).points, suite.pipe(3).points)
    long = suite.pipe(3, min_length=200.0)
    np.testing.assert_array_equal(long.points[: len(suite.pipe(3).points)], suite.pipe(3).points)


def test_segment_gap_against_hand_values():
    from pipefollow.sim.suites import _segment_gap

    assert _segment_gap((0, 0), (2, 0), (1, -1), (1, 1)) == 0.0  # crossing
    assert _segment_gap((0, 0), (2, 0), (0, 1), (2, 1)) == 1.0  # parallel, 1 apart
    assert math.isclose(_segment_gap((0, 0), (1, 0), (2, 1), (3, 2)), math.sqrt(2.0))  # end to end
