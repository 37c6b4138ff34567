"""pipefollow rollouts: a controller's episodes as a Minari dataset, read back with Minari."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main

minari = pytest.importorskip("minari")
pytest.importorskip("h5py")
pytest.importorskip("jax")
pytestmark = pytest.mark.rollouts


def _load(folder, dataset_id, monkeypatch):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(folder))
    return minari.load_dataset(dataset_id)


def test_heuristic_rollouts_read_back_as_the_episodes_benchmark_runs(tmp_path, monkeypatch):
    args = [
        "rollouts",
        "--suite",
        "heldout",
        "--pipes",
        "3",
        "--seconds",
        "20",
        "--out",
        str(tmp_path),
        "--json",
    ]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["dataset_id"] == "pipefollow/heldout-heuristic-v0" and out["episodes"] == 3
    data = _load(tmp_path, out["dataset_id"], monkeypatch)
    assert data.total_episodes == 3 and data.total_steps == 60
    bench = CliRunner().invoke(main, ["benchmark", "--pipes", "3", "--seconds", "20", "--json"])
    returns = [e["return"] for e in json.loads(bench.stdout)["episodes"]]
    for ep, ret in zip(data.iterate_episodes(), returns, strict=True):
        assert ep.observations.shape == (21, 4) and ep.actions.shape == (20, 1)
        # the same episodes as benchmark's (Minari stores the rewards as float32)
        assert ep.rewards.sum() == pytest.approx(ret, rel=1e-6)
        assert ep.infos["pose"].shape == (21, 3) and ep.infos["current"].shape == (21, 2)
        assert ep.truncations[-1] and not ep.terminations.any()
        np.testing.assert_array_equal(ep.infos["pipe_in_view"][1:], ep.observations[1:, 1] >= 0.0)


def test_exploring_rollouts_of_a_policy_differ_from_deterministic_ones(tmp_path, monkeypatch):
    policy = tmp_path / "p"
    CliRunner().invoke(
        main, ["train", "--algorithm", "cacla", "--episodes", "3", "--out", str(policy), "--json"]
    )
    common = [
        "rollouts",
        "--controller",
        str(policy),
        "--pipes",
        "2",
        "--seconds",
        "10",
        "--out",
        str(tmp_path),
    ]
    assert CliRunner().invoke(main, [*common, "--name", "pipefollow/det-v0"]).exit_code == 0
    assert CliRunner().invoke(main, [*common, "--sigma", "0.5", "--name", "pipefollow/exp-v0"]).exit_code == 0
    det = next(iter(_load(tmp_path, "pipefollow/det-v0", monkeypatch).iterate_episodes()))
    exp = next(iter(_load(tmp_path, "pipefollow/exp-v0", monkeypatch).iterate_episodes()))
    assert not np.array_equal(det.actions, exp.actions)


def test_an_existing_dataset_is_not_replaced(tmp_path):
    args = ["rollouts", "--pipes", "1", "--seconds", "5", "--out", str(tmp_path)]
    assert CliRunner().invoke(main, args).exit_code == 0
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2 and "already holds the dataset" in res.stderr
