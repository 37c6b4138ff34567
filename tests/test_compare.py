"""Comparisons over training seeds × pipes: rliable's definitions, checked against rliable's own numbers.

tests/data/rliable_reference.json holds rliable 1.2's point estimates and intervals on stored
matrices, made by tests/data/make_rliable_reference.py (its docstring has the command). rliable
draws its bootstrap from NumPy's global generator and this package from an explicit Generator, so
the intervals agree within the Monte-Carlo spread measured over rliable's global seeds.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.stats
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.evaluation import compare as cmp

REF = json.loads((Path(__file__).parent / "data" / "rliable_reference.json").read_text(encoding="utf-8"))
SCORES = {k: np.array(v) for k, v in REF["scores"].items()}
TAUS = np.array(REF["taus"])


def _spread(key: str, label: str) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation of rliable's interval ends over its global seeds."""
    ends = np.array([run[key][label] for run in REF["intervals"]], dtype=float)
    return ends.mean(axis=0), ends.std(axis=0, ddof=1)


def _assert_within_monte_carlo(ours, key, label, floor):
    centre, sd = _spread(key, label)
    k = len(REF["intervals"])
    # our value and rliable's mean are independent estimates: 5 sd of their difference, or one step
    # of the statistic's lattice where rliable's draws all landed on the same value
    tol = np.maximum(5.0 * sd * np.sqrt(1.0 + 1.0 / k), floor)
    assert np.all(np.abs(np.asarray(ours, dtype=float) - centre) <= tol), (key, label, ours, centre, tol)


@pytest.mark.parametrize("label", sorted(SCORES))
def test_point_estimates_equal_rliables(label):
    assert cmp.iqm(SCORES[label]) == pytest.approx(REF["iqm"][label], abs=1e-12)
    assert cmp.mean(SCORES[label]) == pytest.approx(REF["mean"][label], abs=1e-12)
    taus_share = cmp.performance_profile(SCORES[label], TAUS, reps=100)["share"]
    np.testing.assert_allclose(taus_share, REF["profile"][label], atol=1e-12)


@pytest.mark.parametrize("pair", sorted(REF["poi"]))
def test_probability_of_improvement_equals_rliables(pair):
    x, y = pair.split(">")
    assert cmp.probability_of_improvement(SCORES[x], SCORES[y]) == pytest.approx(REF["poi"][pair], abs=1e-12)


@pytest.mark.parametrize("label", sorted(SCORES))
def test_iqm_and_mean_intervals_agree_with_rliables(label):
    r = cmp.aggregate_intervals(SCORES[label], reps=REF["reps"]["aggregate"], seed=7)
    _assert_within_monte_carlo(r["ci95_iqm"], "iqm", label, floor=1e-9)
    _assert_within_monte_carlo(r["ci95_mean"], "mean", label, floor=1e-9)
    assert r["ci95_iqm"][0] <= r["iqm"] <= r["ci95_iqm"][1]


@pytest.mark.parametrize("pair", ["C>A"])
def test_probability_of_improvement_intervals_agree_with_rliables(pair):
    x, y = pair.split(">")
    r = cmp.poi_interval(SCORES[x], SCORES[y], reps=REF["reps"]["poi"], seed=11)
    step = 1.0 / (SCORES[x].shape[0] * SCORES[y].shape[0] * SCORES[x].shape[1])
    _assert_within_monte_carlo(r["ci95"], "poi", pair, floor=2 * step)


@pytest.mark.parametrize("label", sorted(SCORES))
def test_performance_profile_intervals_agree_with_rliables(label):
    r = cmp.performance_profile(SCORES[label], TAUS, reps=REF["reps"]["profile"], seed=5)
    step = 1.0 / SCORES[label].size
    _assert_within_monte_carlo(np.array([r["ci95_low"], r["ci95_high"]]), "profile", label, floor=2 * step)


def test_the_bootstrap_keeps_the_pipes_and_resamples_the_runs():
    # every pipe's runs are equal: resampling runs changes nothing, whatever the pipes' spread
    x = np.tile(np.linspace(-100.0, 50.0, 40), (4, 1))
    r = cmp.aggregate_intervals(x, reps=2_000)
    assert r["ci95_iqm"] == pytest.approx([r["iqm"]] * 2) and r["ci95_mean"] == pytest.approx([r["mean"]] * 2)
    one_run = cmp.aggregate_intervals(np.array([[1.0, 5.0, -3.0]]), reps=500)
    assert one_run["ci95_mean"] == pytest.approx([1.0, 1.0])


def test_probability_of_improvement_by_hand():
    # one pipe; X's runs 2, 3 against Y's 2, 1: 2=2 counts ½, 2>1, 3>2, 3>1 → 3.5 of 4 pairs
    assert cmp.probability_of_improvement(np.array([[2.0], [3.0]]), np.array([[2.0], [1.0]])) == 0.875
    # averaged over pipes: the second pipe X always loses
    x, y = np.array([[2.0, 0.0], [3.0, 0.0]]), np.array([[2.0, 1.0], [1.0, 1.0]])
    assert cmp.probability_of_improvement(x, y) == (0.875 + 0.0) / 2
    assert cmp.probability_of_improvement(x, x) == 0.5


def test_iqm_by_hand():
    # 8 values: the middle half is the 3rd to the 6th smallest
    x = np.array([[10.0, -5.0, 0.0, 1.0], [2.0, 3.0, 100.0, -50.0]])
    assert cmp.iqm(x) == (0.0 + 1.0 + 2.0 + 3.0) / 4
    assert cmp.mean(x) == x.mean()


def test_compare_summary_has_every_learner_and_ordered_pair():
    out = cmp.compare({k: SCORES[k] for k in ("A", "B", "C")}, reps=1_000).summary
    assert list(out["learners"]) == ["A", "B", "C"] and out["pipes"] == SCORES["A"].shape[1]
    pairs = [(p["x"], p["y"]) for p in out["probability_of_improvement"]]
    assert len(pairs) == 6 and set(pairs) == {(a, b) for a in "ABC" for b in "ABC" if a != b}
    prof = out["learners"]["A"]["profile"]
    assert prof["share"][0] == 1.0 - np.mean(SCORES["A"] <= prof["tau"][0]) and prof["share"][-1] == 0.0


def test_compare_refuses_learners_on_different_pipes():
    with pytest.raises(ValueError, match="different numbers of pipes"):
        cmp.compare({"a": np.zeros((2, 3)), "b": np.zeros((2, 4))})


LABELLED = ["compare", "heuristic", "los", "heuristic", "--label", "H", "--label", "L", "--label", "H"]


def _compare_json(*extra) -> dict:
    """``compare --json`` of the heuristic twice (H) and LOS once (L) on 6 held-out pipes of 20 s."""
    args = [*LABELLED, "--pipes", "6", "--seconds", "20", "--reps", "500", "--json", *extra]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    return json.loads(res.stdout)


def test_cli_compare_json_plot_and_labels(tmp_path):
    plot = tmp_path / "c.png"
    out = _compare_json("--plot", str(plot))
    assert out["learners"]["H"]["runs"] == 2 and out["learners"]["L"]["runs"] == 1
    assert out["policies"] == {"H": ["heuristic", "heuristic"], "L": ["los"]}
    assert out["plot"] == str(plot) and plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out["suite"] == "heldout" and out["pipes"] == 6


def test_cli_compare_label_count_must_match(tmp_path):
    res = CliRunner().invoke(main, ["compare", "heuristic", "los", "--label", "H"])
    assert res.exit_code == 2 and "one per policy" in res.stderr


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 7, 8, 13, 100])
def test_iqm_is_scipys_trimmed_mean(n):
    from scipy.stats import trim_mean

    x = np.random.default_rng(n).normal(size=(1, n)).round(1)  # rounded: ties
    assert cmp.iqm(x) == pytest.approx(trim_mean(x, 0.25, axis=None), abs=1e-12)


def test_cli_compare_writes_the_score_matrices_it_judged_in_rliables_layout(tmp_path):
    scores_file = tmp_path / "scores.json"
    out = _compare_json("--scores", str(scores_file))
    stored = json.loads(scores_file.read_text())
    assert stored["scores"] == out["scores"] and stored["tasks"] == out["tasks"]
    assert out["tasks"] == [f"heldout-{k:03d}" for k in range(6)]
    mats = {k: np.array(v) for k, v in out["scores"].items()}
    assert mats["H"].shape == (2, 6) and mats["L"].shape == (1, 6)  # runs × tasks, as rliable takes them
    # the matrices are the ones judged: compare's point estimates recomputed from them by hand
    for label, m in mats.items():
        learner = out["learners"][label]
        assert learner["mean"] == pytest.approx(float(m.mean()), rel=1e-12)
        assert learner["iqm"] == pytest.approx(float(scipy.stats.trim_mean(m.ravel(), 0.25)), rel=1e-12)
    assert np.array_equal(mats["H"][0], mats["H"][1])  # the heuristic twice: deterministic runs
    bad = CliRunner().invoke(main, [*LABELLED, "--pipes", "2", "--scores", str(tmp_path / "s.csv")])
    assert bad.exit_code == 2 and "--scores" in bad.stderr
