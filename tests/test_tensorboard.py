"""train --tensorboard DIR: the per-episode series of the learning curve, read back with TensorBoard."""

from __future__ import annotations

import csv
import json

import pytest
from click.testing import CliRunner

from pipefollow.cli import main

pytest.importorskip("tensorboard")
pytestmark = pytest.mark.tensorboard


def _scalars(folder) -> dict[str, list[tuple[int, float]]]:
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator
    from tensorboard.util import tensor_util

    ea = EventAccumulator(str(folder), size_guidance={"tensors": 0})
    ea.Reload()
    return {
        tag: [(e.step, float(tensor_util.make_ndarray(e.tensor_proto))) for e in ea.Tensors(tag)]
        for tag in ea.Tags()["tensors"]
    }


def test_tensorboard_holds_the_learning_curve_episode_by_episode(tmp_path):
    out, tb = tmp_path / "run", tmp_path / "tb"
    args = ["train", "--algorithm", "cacla", "--episodes", "12", "--out", str(out), "--tensorboard", str(tb)]
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    logged = _scalars(tb)
    assert set(logged) >= {"episode/return", "episode/pipe_in_view", "episode/sigma"}
    with (out / "learning_curve.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [s for s, _ in logged["episode/return"]] == list(range(12))
    assert [v for _, v in logged["episode/return"]] == pytest.approx(
        [float(r["return"]) for r in rows], rel=1e-6
    )
    assert [v for _, v in logged["episode/sigma"]] == pytest.approx(
        [float(r["sigma"]) for r in rows], rel=1e-6
    )
    assert json.loads(res.stdout)["returns"] == pytest.approx(
        [v for _, v in logged["episode/return"]], rel=1e-6
    )


def test_tensorboard_is_refused_for_deep_learners_before_any_work(tmp_path):
    res = CliRunner().invoke(
        main,
        ["train", "--algorithm", "ppo", "--out", str(tmp_path / "r"), "--tensorboard", str(tmp_path / "tb")],
    )
    assert res.exit_code == 2 and "--tensorboard applies to --algorithm sarsa and cacla" in res.stderr
    assert not (tmp_path / "r").exists()
