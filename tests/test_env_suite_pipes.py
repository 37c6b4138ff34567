"""A suite's pipe by name (``heldout-003``) in the environments, as ``evaluate --pipeline`` takes it."""

import json

import gymnasium as gym
import numpy as np
import pytest
from click.testing import CliRunner

import pipefollow.envs  # noqa: F401 (registers the ids)
from pipefollow.cli import main
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim.pipeline import PipelineError
from pipefollow.sim.suites import get_suite, min_length_for
from pipefollow.training.compiled import run_episode

VALIDATION = "pipefollow/PipelineFollowingValidation-v0"  # 60-s episodes


def test_gym_make_takes_a_held_out_pipe_and_evaluates_it_as_evaluate_does():
    env = gym.make(VALIDATION, pipeline="heldout-003")
    expected = get_suite("heldout").pipe(3, min_length_for(60.0))
    np.testing.assert_array_equal(env.unwrapped.pipeline.points, expected.points)
    ret = run_episode(env, Heuristic(), seed=0).ret
    res = CliRunner().invoke(main, ["evaluate", "--pipeline", "heldout-003", "--json"])
    assert res.exit_code == 0, res.output
    assert ret == pytest.approx(json.loads(res.output)["mean_return"], abs=1e-12)


def test_the_pipe_is_as_long_as_the_episode_needs_and_a_reset_option_switches_it():
    short = gym.make("pipefollow/PipelineFollowing-v0", pipeline="heldout-007")  # 20-s episodes
    long = get_suite("heldout").pipe(7, min_length_for(60.0))
    p = short.unwrapped.pipeline
    assert p.length >= min_length_for(20.0)
    np.testing.assert_array_equal(p.points[:2], long.points[:2])  # a prefix of the longer pipe
    env = gym.make(VALIDATION)
    env.reset(seed=0, options={"pipeline": "heldout-hard-012"})
    expected = get_suite("heldout-hard").pipe(12, min_length_for(60.0))
    np.testing.assert_array_equal(env.unwrapped.pipeline.points, expected.points)


def test_the_vector_environment_takes_suite_pipes_per_sub_environment():
    venv = gym.make_vec(VALIDATION, num_envs=2, pipeline=["heldout-000", "heldout-sharp-001"])
    names = [p.name for p in venv.unwrapped.pipelines]
    assert names == ["heldout-000", "heldout-sharp-001"]
    expected = get_suite("heldout-sharp").pipe(1, min_length_for(60.0))
    np.testing.assert_array_equal(venv.unwrapped.pipelines[1].points, expected.points)


def test_a_pipe_past_the_suite_and_training_on_a_suite_pipe_are_refused(tmp_path):
    with pytest.raises(PipelineError, match="has pipes 0 to 99"):
        gym.make(VALIDATION, pipeline="heldout-100")
    args = ["train", "--algorithm", "cacla", "--pipeline", "heldout-003", "--out", str(tmp_path / "o")]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2
    assert "a suite's pipe is for judging a policy" in res.output
    assert len(res.output.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()
