"""Distributions over disturbances, drawn per episode (pipefollow.sim.randomization)."""

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from pipefollow.sim import randomization as rz
from pipefollow.sim.disturbance import MAX_BURIED, NO_DISTURBANCE, DisturbanceError, check


def draws(r: rz.Randomization, rng: np.random.Generator, n: int) -> list:
    """``n`` episodes' disturbances, drawn one after the other from ``rng`` as training draws them."""
    return [rz.draw(r, rng) for _ in range(n)]


# ---------------------------------------------------------------------------------------------
# The map from uniforms to a record, by hand


def test_from_uniforms_by_hand():
    r = rz.Randomization(
        current_speed=(0.1, 0.3),
        current_direction_deg=(0.0, 360.0),
        current_time_constant=20.0,
        current_speed_sd=0.01,
        current_direction_sd_deg=5.0,
        camera_noise=(0.0, 0.04),
        miss_prob=(0.1, 0.2),
        buried_prob=0.5,
        buried_count=2,
        buried_length_m=(1.0, 3.0),
        buried_region_m=(10.0, 30.0),
    )
    u = np.zeros(rz.DRAWS)
    u[:4] = [0.5, 0.25, 0.75, 0.5]
    u[4:7] = [0.9, 0.0, 0.0]  # cell 0: 0.9 ≥ 0.5, no stretch
    u[7:10] = [0.1, 0.5, 0.5]  # cell 1 ([20, 30] m): a 2-m stretch in the middle of the room left
    d = rz.from_uniforms(r, u)
    assert d.current_speed == pytest.approx(0.2)
    assert d.current_direction == pytest.approx(math.pi / 2)  # 90°, towards east
    assert (d.current_time_constant, d.current_speed_sd) == (20.0, 0.01)
    assert d.current_direction_sd == pytest.approx(math.radians(5.0))
    assert d.camera_noise == pytest.approx(0.03)
    assert d.miss_prob == pytest.approx(0.15)
    # the stretch starts at 20 + 0.5 · (10 − 2) = 24 m and ends at 26 m; it fills the first slot
    assert d.buried_from == (24.0, math.inf, math.inf, math.inf)
    assert d.buried_to == (26.0, math.inf, math.inf, math.inf)
    assert check(d) is d


def test_off_draws_no_disturbance_and_consumes_the_same_numbers():
    rng_a, rng_b = np.random.default_rng(3), np.random.default_rng(3)
    assert rz.NONE.is_off
    assert rz.draw(rz.NONE, rng_a) == NO_DISTURBANCE
    rz.draw(rz.PRESETS["harsh"], rng_b)
    assert rng_a.random() == rng_b.random()  # DRAWS uniforms each, whatever is on


def test_same_seed_same_draws_and_kinds_do_not_shift_each_other():
    r = rz.PRESETS["moderate"]
    a = draws(r, np.random.default_rng(11), 50)
    b = draws(r, np.random.default_rng(11), 50)
    assert a == b
    quiet = draws(replace(r, camera_noise=(0.0, 0.0), buried_prob=0.0), np.random.default_rng(11), 50)
    assert [d.current_speed for d in quiet] == [d.current_speed for d in a]
    assert [d.miss_prob for d in quiet] == [d.miss_prob for d in a]
    assert all(d.camera_noise == 0.0 and math.isinf(d.buried_from[0]) for d in quiet)


def test_a_current_without_speed_has_no_direction_and_no_variation():
    r = rz.Randomization(current_speed=(0.0, 0.0), current_time_constant=30.0, current_speed_sd=0.1)
    assert rz.draw(r, np.random.default_rng(0)) == NO_DISTURBANCE


# ---------------------------------------------------------------------------------------------
# The distributions, against scipy


def test_speed_direction_and_noise_are_uniform_on_their_ranges():
    r = rz.Randomization(
        current_speed=(0.05, 0.25), current_direction_deg=(-90.0, 90.0), camera_noise=(0.0, 0.1)
    )
    ds = draws(r, np.random.default_rng(2026), 4000)
    speed = np.array([d.current_speed for d in ds])
    direction = np.degrees([d.current_direction for d in ds])
    noise = np.array([d.camera_noise for d in ds])
    assert stats.kstest(speed, stats.uniform(0.05, 0.2).cdf).pvalue > 0.01
    assert stats.kstest(direction, stats.uniform(-90.0, 180.0).cdf).pvalue > 0.01
    assert stats.kstest(noise, stats.uniform(0.0, 0.1).cdf).pvalue > 0.01
    # the three come from separate uniforms: uncorrelated
    assert abs(stats.pearsonr(speed, noise).statistic) < 0.05


def test_buried_cells_hold_a_stretch_with_their_probability():
    r = rz.Randomization(
        buried_prob=0.3, buried_count=3, buried_length_m=(0.5, 2.0), buried_region_m=(6.0, 36.0)
    )
    ds = draws(r, np.random.default_rng(5), 3000)
    counts = np.array([sum(math.isfinite(a) for a in d.buried_from) for d in ds])
    # three independent cells: the count is binomial(3, 0.3)
    observed = np.bincount(counts, minlength=4)
    expected = stats.binom(3, 0.3).pmf(np.arange(4)) * len(ds)
    assert stats.chisquare(observed, expected).pvalue > 0.01
    lengths = np.array(
        [b - a for d in ds for a, b in zip(d.buried_from, d.buried_to, strict=True) if math.isfinite(a)]
    )
    assert stats.kstest(lengths, stats.uniform(0.5, 1.5).cdf).pvalue > 0.01


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(0.0, 1.0, exclude_max=True), min_size=rz.DRAWS, max_size=rz.DRAWS),
    st.integers(1, MAX_BURIED),
    st.floats(0.1, 1.0),
)
def test_every_draw_is_a_valid_disturbance_inside_its_ranges(u, count, prob):
    region = (2.0, 2.0 + 5.0 * count)
    r = rz.check(replace(rz.PRESETS["harsh"], buried_prob=prob, buried_count=count, buried_region_m=region))
    d = rz.from_uniforms(r, np.array(u))
    check(d)  # sorted, disjoint stretches; every value in its domain
    assert 0.0 <= d.current_speed <= 0.3 and 0.0 <= d.camera_noise <= 0.1 and 0.0 <= d.miss_prob <= 0.1
    for a, b in zip(d.buried_from, d.buried_to, strict=True):
        if math.isfinite(a):
            # the length is drawn in [0.5, 2]; b - a recomputes it with one rounding of a + length
            assert region[0] <= a < b <= region[1] and 0.5 - 1e-12 <= b - a <= 2.0 + 1e-12


# ---------------------------------------------------------------------------------------------
# Presets, tables and bad input


@pytest.mark.parametrize("name", list(rz.PRESETS))
def test_presets_are_valid_and_round_trip(name):
    r = rz.resolve(name)
    assert rz.from_dict(rz.to_dict(r)) == r
    for d in draws(r, np.random.default_rng(0), 200):
        check(d)


def test_table_starts_from_a_preset_and_a_number_is_a_fixed_value():
    r = rz.from_dict({"preset": "moderate", "current_speed": [0.05, 0.25], "miss_prob": 0.02})
    assert r.current_speed == (0.05, 0.25)
    assert r.miss_prob == (0.02, 0.02)
    assert r.camera_noise == rz.PRESETS["moderate"].camera_noise
    assert rz.draw(r, np.random.default_rng(1)).miss_prob == 0.02


@pytest.mark.parametrize(
    ("table", "field"),
    [
        ({"current_speed": [0.2, 0.1]}, "current_speed"),
        ({"current_speed": [-0.1, 0.1]}, "current_speed"),
        ({"camera_noise": [0.05, 0.0]}, "camera_noise"),
        ({"current_speed_sd": -0.01, "current_time_constant": 10}, "current_speed_sd"),
        ({"current_direction_sd_deg": 5.0}, "current_time_constant"),
        ({"miss_prob": [0.0, 1.5]}, "miss_prob"),
        ({"miss_prob": -0.1}, "miss_prob"),
        ({"buried_prob": 1.1}, "buried_prob"),
        ({"buried_count": 0}, "buried_count"),
        ({"buried_count": 2.5}, "buried_count"),
        ({"buried_prob": 0.5, "buried_length_m": [1, 50]}, "buried_length_m"),
        ({"camera_noise": [0.0, "a lot"]}, "camera_noise high"),
        ({"current_speed": [0.0, math.nan]}, "current_speed high"),
        ({"current_speed": [0.1, 0.2, 0.3]}, "current_speed"),
        ({"preset": "stormy"}, "preset 'stormy'"),
        ({"speed": 0.1}, "unknown key 'speed'"),
    ],
)
def test_bad_tables_are_one_line_errors_naming_the_field(table, field):
    with pytest.raises(DisturbanceError) as e:
        rz.from_dict(table, source="exp.toml [randomization]")
    message = str(e.value)
    assert message.startswith("exp.toml [randomization]: ")
    assert field in message
    assert "\n" not in message


def test_the_vision_preset_spans_the_calibrated_detector_up_to_turbidity_0_2():
    import json
    from pathlib import Path

    rows = json.loads((Path(__file__).parents[1] / "docs" / "vision" / "calibration.json").read_text())
    usable = [r for r in rows if r["turbidity"] <= 0.2]
    r = rz.PRESETS["vision"]
    assert r.camera_noise == (min(u["camera_noise"] for u in usable), max(u["camera_noise"] for u in usable))
    assert r.miss_prob == (min(u["miss_prob"] for u in usable), max(u["miss_prob"] for u in usable))
    assert r.current_speed == (0.0, 0.0)


def test_unknown_preset_name_lists_the_presets():
    with pytest.raises(DisturbanceError, match="choose from none, mild, moderate, vision, harsh"):
        rz.resolve("calm-ish")


@pytest.mark.parametrize(
    ("disturbance", "randomization", "both"),
    [
        (None, "mild", False),
        (NO_DISTURBANCE, "mild", False),
        ({}, {"preset": "mild"}, False),
        (NO_DISTURBANCE._replace(camera_noise=0.1), None, False),
        (NO_DISTURBANCE._replace(camera_noise=0.1), "mild", True),
        ({"camera_noise": 0.0}, {"preset": "mild"}, True),  # a table given counts, even of zeros
    ],
)
def test_a_disturbance_and_a_randomization_are_not_both_given(disturbance, randomization, both):
    assert rz.both_given(disturbance, randomization) is both
    if both:
        with pytest.raises(DisturbanceError, match="not both"):
            rz.check_not_both(disturbance, randomization)
    else:
        rz.check_not_both(disturbance, randomization)
