"""Reproducing an experiment (``pipefollow.experiments.reproduction``), as ``pipefollow reproduce`` does."""

from __future__ import annotations

import json

from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.experiments import reproduction


def test_configure_applies_quick_where_nothing_is_given():
    name, exp = reproduction.configure("paper", quick=True, trials=["sarsa"])
    assert name == "paper" and exp.repeats == reproduction.QUICK_REPEATS
    assert all(p.episodes == reproduction.QUICK_EPISODES for t in exp.trials for p in t.phases)
    _, exp = reproduction.configure("paper", quick=True, repeats=3, episodes=4, trials=["sarsa"])
    assert exp.repeats == 3 and all(p.episodes == 4 for t in exp.trials for p in t.phases)
    _, exp = reproduction.configure("paper", trials=["sarsa"])
    assert exp.repeats == 5


def test_default_run_dir():
    assert reproduction.default_run_dir("paper") == "reproduction"
    assert reproduction.default_run_dir("paper", quick=True) == "reproduction-quick"
    assert reproduction.default_run_dir("readings", quick=True) == "reproduction-readings-quick"


def test_reproduce_summarises_as_the_command_prints(tmp_path):
    notes = []
    rep = reproduction.reproduce(
        "paper", tmp_path / "run", overrides=dict(repeats=1, episodes=2, trials=["sarsa"]), figures=False,
        note=notes.append, backend="serial", show_progress=False,
    )  # fmt: skip
    assert notes == [] and rep.run.trials_computed == 1
    assert [p.name for p in rep.outputs] == ["results.csv", "evaluation.csv"]
    text = reproduction.summary_text(rep)
    assert text.startswith("paper: 1 trials (1 computed, 0 reused)")
    assert text.splitlines()[-1] == f"wrote {rep.outputs[-1]}"
    args = ["reproduce", "--out", str(tmp_path / "run"), "--repeats", "1", "--episodes", "2"]
    args += ["--trial", "sarsa", "--backend", "serial", "--no-figures", "--json"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    again = json.loads(res.stdout)
    assert again["trials_reused"] == 1
    assert again["trials"] == reproduction.summary(rep)["trials"]
