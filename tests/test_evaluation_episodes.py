"""One controller on one pipeline (``pipefollow.evaluation.episodes``), as ``pipefollow evaluate`` runs it."""

from __future__ import annotations

import json

from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.evaluation import episodes as ev
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim.disturbance import NO_DISTURBANCE, make_disturbance
from pipefollow.sim.pipeline import builtin
from pipefollow.sim.suites import get_suite


def test_default_seconds():
    assert ev.default_seconds("paper-validation") == 60.0
    assert ev.default_seconds("paper-left") == ev.default_seconds("paper-right") == 20.0
    assert ev.default_seconds("random:hard") == ev.default_seconds("random") == 20.0  # training families
    # the kinds of pipe benchmark runs for 60 s: a suite's pipe, a user's file
    assert ev.default_seconds("heldout-003") == ev.default_seconds("mine.json") == 60.0


def test_episodes_alike_only_without_anything_random():
    pipe = builtin("paper-left")
    assert ev.episodes_alike(pipe, 0.0, 0.0, NO_DISTURBANCE)
    assert ev.episodes_alike(pipe, 0.0, 0.0, make_disturbance(0.1, 45.0))  # a constant current
    assert not ev.episodes_alike(pipe, 0.1, 0.0, NO_DISTURBANCE)
    assert not ev.episodes_alike(pipe, 0.0, 5.0, NO_DISTURBANCE)
    assert not ev.episodes_alike(get_suite("easy"), 0.0, 0.0, NO_DISTURBANCE)
    assert not ev.episodes_alike(pipe, 0.0, 0.0, make_disturbance(miss_prob=0.1))


def test_evaluate_gives_the_commands_numbers(tmp_path):
    run = ev.evaluate(Heuristic(), "paper-validation", episodes=2, seed=4, start_noise=0.5)
    res = CliRunner().invoke(
        main, ["evaluate", "--pipeline", "paper-validation", "--episodes", "2", "--seed", "4",
               "--start-noise", "0.5", "--json"],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    from_cli = json.loads(res.stdout)
    assert run.seconds == from_cli["seconds"] == 60.0
    assert run.summary() == {k: from_cli[k] for k in run.summary()}
    assert run.frames == [] and run.pipe.name == "paper-validation"
    run.write_plot(tmp_path / "p.png", "heuristic")
    assert (tmp_path / "p.png").stat().st_size > 0
