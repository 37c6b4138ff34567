"""RBF features (eqs. 17–18) against a naive evaluation over every centre of the full grid."""

from __future__ import annotations

import itertools
import json
import timeit

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from pipefollow.learners.rbf import (
    ACTION_CENTRES,
    ACTION_CENTRES_DEG,
    ACTION_GRID,
    STATE_CENTRES,
    STATE_GRID,
    RBFGrid,
    dim_activations,
    grid_features,
)


def naive_features(grid: RBFGrid, x) -> np.ndarray:
    """Eq. 18 centre by centre: full squared distance with per-dimension widths, in C order."""
    x = np.clip(np.asarray(x, dtype=float), [c[0] for c in grid.centres], [c[-1] for c in grid.centres])
    widths = np.array([0.5 * np.max(np.diff(c)) for c in grid.centres])
    out = []
    for centre in itertools.product(*grid.centres):
        d2 = (x - np.array(centre)) ** 2
        if grid.form == "normalized":
            out.append(np.exp(-np.sum(d2 / (2.0 * widths**2))))
        else:
            out.append(np.exp(-np.sum(d2 / widths)))
    out = np.array(out)
    return out / out.sum() if grid.form == "normalized" else out


def random_points(grid: RBFGrid, n: int, rng: np.random.Generator, margin: float = 0.0) -> np.ndarray:
    lo = np.array([c[0] for c in grid.centres])
    hi = np.array([c[-1] for c in grid.centres])
    span = hi - lo
    return rng.uniform(lo - margin * span, hi + margin * span, size=(n, len(grid.centres)))


# --- constants --------------------------------------------------------------------------------


def test_feature_counts():
    assert STATE_GRID.shape == (7, 6, 7, 6)
    assert STATE_GRID.n_features == 1764
    assert ACTION_GRID.shape == (13,)
    assert STATE_GRID.n_features * ACTION_GRID.n_features == 22932


def test_centres_as_in_the_paper():
    assert_array_equal(STATE_CENTRES[0], [-1, -0.8, -0.4, 0, 0.4, 0.8, 1])
    assert_array_equal(STATE_CENTRES[1], [0, 0.375, 1.125, 1.875, 2.625, 3])
    assert_array_equal(STATE_CENTRES[2], STATE_CENTRES[0])
    assert_array_equal(STATE_CENTRES[3], [-0.25, -0.156, 0.031, 0.219, 0.406, 0.5])
    assert_array_equal(ACTION_CENTRES_DEG, [-90, -81, -63, -45, -27, -9, 0, 9, 27, 45, 63, 81, 90])
    assert_allclose(ACTION_CENTRES * 90.0, ACTION_CENTRES_DEG, rtol=0, atol=1e-12)
    assert STATE_GRID.form == "normalized"


def test_widths_are_half_the_largest_spacing():
    # x1, x2: spacings 0.2, 0.4, 0.4, 0.4, 0.4, 0.2 -> 0.2; y1: 0.375, 0.75, 0.75, 0.75, 0.375 -> 0.375;
    # v_x: 0.094, 0.187, 0.188, 0.187, 0.094 -> 0.094; actions: 9°/18° steps over 90° -> 0.2 / 2.
    assert_allclose(STATE_GRID.widths, [0.2, 0.375, 0.2, 0.094], rtol=0, atol=1e-12)
    assert_allclose(ACTION_GRID.widths, [0.1], rtol=0, atol=1e-12)


def test_constants_are_read_only():
    with pytest.raises(ValueError):
        STATE_CENTRES[0][0] = 5.0
    with pytest.raises(ValueError):
        STATE_GRID.packed[0][0] = 5.0


# --- features ---------------------------------------------------------------------------------


@pytest.mark.parametrize("form", ["normalized", "literal"])
def test_state_features_equal_naive_evaluation(form):
    grid = RBFGrid(STATE_CENTRES, form=form)
    rng = np.random.default_rng(1)
    for x in random_points(grid, 20, rng):
        assert_allclose(grid.features(x), naive_features(grid, x), rtol=1e-12, atol=1e-300)


@pytest.mark.parametrize("form", ["normalized", "literal"])
def test_action_features_equal_naive_evaluation(form):
    grid = RBFGrid((ACTION_CENTRES,), form=form)
    for a in np.linspace(-1.0, 1.0, 41):
        expected = naive_features(grid, [a])
        assert_allclose(grid.features([a]), expected, rtol=1e-12, atol=1e-300)
        out = np.empty(13)
        dim_activations(a, grid.packed[0], grid.widths[0], form == "normalized", out)
        assert_allclose(out, expected, rtol=1e-12, atol=1e-300)


@pytest.mark.parametrize("ndim", [1, 2, 3, 5])
def test_other_dimensions_equal_naive_evaluation(ndim):
    rng = np.random.default_rng(ndim)
    centres = tuple(np.sort(rng.uniform(-2, 2, size=rng.integers(2, 6))) for _ in range(ndim))
    for form in ("normalized", "literal"):
        grid = RBFGrid(centres, form=form)
        for x in random_points(grid, 5, rng):
            assert_allclose(grid.features(x), naive_features(grid, x), rtol=1e-12, atol=1e-300)


def test_c_order_matches_kron():
    x = np.array([0.3, 1.4, -0.65, 0.1])
    per_dim = []
    for j, c in enumerate(STATE_CENTRES):
        out = np.empty(c.size)
        dim_activations(x[j], c, STATE_GRID.widths[j], True, out)
        per_dim.append(out)
    kron = per_dim[0]
    for a in per_dim[1:]:
        kron = np.kron(kron, a)
    assert_allclose(STATE_GRID.features(x), kron, rtol=1e-14, atol=0)
    # the feature of centre (i, j, k, l) sits at the C-order flat index
    phi = STATE_GRID.features(x).reshape(STATE_GRID.shape)
    assert_allclose(phi[2, 3, 1, 4], np.prod([per_dim[d][i] for d, i in enumerate((2, 3, 1, 4))]), rtol=1e-14)


def test_normalized_features_sum_to_one():
    rng = np.random.default_rng(2)
    for x in random_points(STATE_GRID, 200, rng, margin=0.2):
        phi = STATE_GRID.features(x)
        assert abs(phi.sum() - 1.0) < 1e-12
        assert np.all(phi >= 0.0)


def test_feature_at_a_centre():
    # At a grid centre the literal features peak at exactly 1 for that centre.
    grid = RBFGrid(STATE_CENTRES, form="literal")
    x = np.array([0.4, 1.125, -0.8, 0.219])
    phi = grid.features(x).reshape(grid.shape)
    assert phi[4, 2, 1, 3] == 1.0
    assert np.argmax(STATE_GRID.features(x)) == np.ravel_multi_index((4, 2, 1, 3), grid.shape)


@pytest.mark.parametrize("form", ["normalized", "literal"])
def test_inputs_outside_the_grid_are_clipped(form):
    grid = RBFGrid(STATE_CENTRES, form=form)
    lo = np.array([c[0] for c in STATE_CENTRES])
    hi = np.array([c[-1] for c in STATE_CENTRES])
    rng = np.random.default_rng(3)
    for x in random_points(grid, 30, rng, margin=1.0):
        assert_array_equal(grid.features(x), grid.features(np.clip(x, lo, hi)))
    assert_array_equal(
        grid.features([5.0, -1.0, -7.0, 2.0]), grid.features(np.r_[hi[0], lo[1], lo[2], hi[3]])
    )
    assert_array_equal(ACTION_GRID.features([1.7]), ACTION_GRID.features([1.0]))


def test_features_into_out_and_compiled_entry_point_agree():
    x = np.array([-0.2, 2.2, 0.7, 0.0])
    out = np.full(STATE_GRID.n_features, np.nan)
    res = STATE_GRID.features(x, out)
    assert res is out
    direct = np.empty(STATE_GRID.n_features)
    grid_features(x, *STATE_GRID.packed, True, direct)
    assert_array_equal(out, direct)
    assert STATE_GRID.features(x) is not STATE_GRID.features(x)  # a fresh array without out


def test_features_accept_lists_and_float32():
    x = [0.1, 1.0, -0.3, 0.2]
    assert_allclose(STATE_GRID.features(np.array(x, dtype=np.float32)), STATE_GRID.features(x), rtol=1e-6)


def test_features_time():
    # target: one state's features through the Python method in ≤ 5 µs (median).
    x = np.array([0.1, 1.0, -0.3, 0.2])
    out = np.empty(STATE_GRID.n_features)
    STATE_GRID.features(x, out)
    runs = timeit.repeat(lambda: STATE_GRID.features(x, out), number=200, repeat=15)
    median_us = float(np.median(runs)) / 200 * 1e6
    assert median_us < 25.0  # generous: shared CI machines; measured ≈3 µs


# --- validation -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "x, match",
    [
        ([0.0, 1.0, 0.0], "4 entries"),
        ([[0.0, 1.0, 0.0, 0.1]], "4 entries"),
        ([0.0, np.nan, 0.0, 0.1], "finite"),
        ([0.0, 1.0, np.inf, 0.1], "finite"),
    ],
)
def test_features_reject_bad_inputs(x, match):
    with pytest.raises(ValueError, match=match):
        STATE_GRID.features(x)


def test_features_reject_bad_out():
    with pytest.raises(ValueError, match="out"):
        STATE_GRID.features([0, 1, 0, 0], out=np.empty(10))
    with pytest.raises(ValueError, match="out"):
        STATE_GRID.features([0, 1, 0, 0], out=np.empty(1764, dtype=np.float32))


@pytest.mark.parametrize(
    "centres, match",
    [
        ((), "at least one dimension"),
        (np.array([0.0, 1.0]), "sequence"),
        (([0.0],), "at least 2"),
        (([[0.0, 1.0], [2.0, 3.0]],), "1-D"),
        (([0.0, 1.0, 1.0],), "strictly increasing"),
        (([0.0, 2.0, 1.0],), "strictly increasing"),
        (([0.0, np.inf],), "finite"),
        (([0.0, np.nan],), "finite"),
        (([0.0, "a"],), "numbers"),
    ],
)
def test_grid_validation(centres, match):
    with pytest.raises(ValueError, match=f"centres.*{match}"):
        RBFGrid(centres)


def test_grid_form_validation():
    with pytest.raises(ValueError, match="form must be one of 'normalized', 'literal'"):
        RBFGrid(STATE_CENTRES, form="gaussian")


def test_grid_copies_its_centres():
    c = np.array([0.0, 1.0, 3.0])
    grid = RBFGrid((c,))
    c[0] = -5.0
    assert grid.centres[0][0] == 0.0
    assert_allclose(grid.widths, [1.0])


# --- storage ----------------------------------------------------------------------------------


@pytest.mark.parametrize("grid", [STATE_GRID, ACTION_GRID, RBFGrid(STATE_CENTRES, form="literal")])
def test_dict_round_trip(grid):
    d = grid.to_dict()
    assert d["form"] == grid.form
    assert all(isinstance(c, list) and all(type(v) is float for v in c) for c in d["centres"])
    back = RBFGrid.from_dict(json.loads(json.dumps(d)))
    assert back == grid
    assert hash(back) == hash(grid)
    for a, b in zip(back.centres, grid.centres, strict=True):
        assert_array_equal(a, b)
    x = random_points(grid, 1, np.random.default_rng(4))[0]
    assert_array_equal(back.features(x), grid.features(x))


def test_round_trip_through_npz(tmp_path):
    path = tmp_path / "grid.npz"
    np.savez(path, grid=np.array(json.dumps(STATE_GRID.to_dict())))
    with np.load(path, allow_pickle=False) as z:
        assert RBFGrid.from_dict(json.loads(str(z["grid"]))) == STATE_GRID


def test_grids_differ_by_form_and_centres():
    assert RBFGrid(STATE_CENTRES, form="literal") != STATE_GRID
    assert RBFGrid(STATE_CENTRES[:3]) != STATE_GRID
    assert RBFGrid((ACTION_CENTRES,)) == ACTION_GRID
