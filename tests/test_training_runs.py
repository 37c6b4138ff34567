"""A learner trained into a folder (``pipefollow.training.runs``), as ``pipefollow train`` does it."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow import readings as rd
from pipefollow.cli import main
from pipefollow.learners.registry import LEARNERS
from pipefollow.training import runs
from pipefollow.training.policy_files import load_policy


def test_step_sizes_are_the_registrys():
    assert runs.step_sizes("sarsa") == ("alpha", "discount")
    assert set(runs.step_sizes("cacla")) == set(LEARNERS["cacla"].step_sizes.values())
    assert "alpha_v" in runs.step_sizes("ac")


def test_train_into_writes_what_the_command_writes(tmp_path):
    agent = runs.new_agent("cacla", 3, rd.DEFAULT, skew_deg=22.5)
    (tmp_path / "lib").mkdir()
    run = runs.train_into(tmp_path / "lib", agent, "paper-left", 4, seed=3, seconds=10.0)
    args = ["train", "--algorithm", "cacla", "--skew", "22.5", "--episodes", "4", "--seconds", "10"]
    res = CliRunner().invoke(main, [*args, "--seed", "3", "--out", str(tmp_path / "cli"), "--json"])
    assert res.exit_code == 0, res.output
    from_cli = json.loads(res.stdout)
    summary = run.summary()
    assert summary["returns"] == from_cli["returns"]
    assert {k: v for k, v in summary.items() if k not in ("policy", "learning_curve")} == {
        k: v for k, v in from_cli.items() if k not in ("policy", "learning_curve")
    }
    np.testing.assert_array_equal(load_policy(run.policy).weights, load_policy(from_cli["policy"]).weights)
    assert run.text().splitlines()[1:] == [
        "options: skew 22.5°",
        f"policy: {run.policy}",
        f"learning curve: {run.learning_curve}",
    ]


def test_train_into_removes_the_folders_it_was_given_when_training_fails(tmp_path):
    made = tmp_path / "a"
    out = made / "b"
    out.mkdir(parents=True)
    agent = runs.new_agent("sarsa", 0, rd.DEFAULT)
    with pytest.raises(KeyboardInterrupt):
        runs.train_into(out, agent, "paper-left", 3, seed=0, progress=_interrupt, made=made)
    assert not made.exists()


def _interrupt(n):
    raise KeyboardInterrupt


def test_option_differences_keep_the_step_sizes_and_name_the_rest():
    agent = runs.new_agent("cacla", 0, rd.DEFAULT, skew_deg=22.5)
    agent.params = agent.params._replace(alpha_v=0.1, discount=0.5)  # step sizes: always kept
    assert runs.option_differences(agent, rd.DEFAULT, None, None) == []
    assert runs.option_differences(agent, rd.DEFAULT, 22.5, False) == []
    (skew,) = runs.option_differences(agent, rd.DEFAULT, 45.0, None)
    assert skew.startswith("skew ") and "(this run: " in skew
    (supervised,) = runs.option_differences(agent, rd.DEFAULT, None, True)
    assert supervised == "supervised False (this run: True)"
