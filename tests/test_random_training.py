"""Training on a new random pipe every episode: compiled path = environment path; seeds reproduce."""

import json
import math

import gymnasium as gym
import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.experiments.schema import Phase, TrialConfig
from pipefollow.experiments.trial import run_trial
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim.suites import get_suite, min_length_for
from pipefollow.training.agents import make_agent
from pipefollow.training.compiled import train
from pipefollow.training.random_pipes import train_random_compiled

KINDS = {
    "cacla": dict(algorithm="cacla"),
    "supervised-skew": dict(algorithm="cacla", skew_deg=22.5, supervised=True),
    "sarsa": dict(algorithm="sarsa"),
}


@pytest.mark.parametrize("kind", KINDS)
def test_compiled_random_pipe_training_equals_the_environment(kind):
    episodes = 10
    a = make_agent(rng=np.random.default_rng(3), **KINDS[kind])
    b = make_agent(rng=np.random.default_rng(3), **KINDS[kind])
    env = PipelineFollowingEnv("random:hard", 20)
    env.np_random = np.random.default_rng(11)
    pipes = []
    stats_env = train(env, a, episodes, callback=lambda e, ep: pipes.append(env.pipeline.points.copy()))
    stats_fast = train_random_compiled(
        b, get_suite("hard"), episodes, pipe_rng=np.random.default_rng(11), chunk=4
    )
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
    # the pipes were new each episode, and the compiled path drew the same ones
    rng = np.random.default_rng(11)
    for points in pipes:
        np.testing.assert_array_equal(points, get_suite("hard").draw(rng, min_length_for(20)).points)
    assert len({p.tobytes() for p in pipes}) == episodes


def test_random_pipe_training_is_reproducible_and_seed_dependent():
    def run(seed):
        agent = make_agent("cacla", rng=np.random.default_rng(seed))
        stats = train_random_compiled(
            agent, get_suite("mixed"), 6, pipe_rng=np.random.default_rng(seed + 100)
        )
        return stats, agent.weights

    s1, w1 = run(1)
    s2, w2 = run(1)
    s3, _ = run(2)
    np.testing.assert_array_equal(s1, s2)
    np.testing.assert_array_equal(w1, w2)
    assert not np.array_equal(s1, s3)


def test_gym_make_random_draws_a_new_pipe_every_reset_and_reports_the_episode():
    env = gym.make("pipefollow/PipelineFollowing-v0", pipeline="random:easy", episode_seconds=5)
    env.reset(seed=4)
    first = env.unwrapped.pipeline.points.copy()
    env.reset()
    second = env.unwrapped.pipeline.points.copy()
    assert not np.array_equal(first, second)
    rng = np.random.default_rng(4)
    suite = get_suite("easy")
    np.testing.assert_array_equal(first, suite.draw(rng, min_length_for(5)).points)
    np.testing.assert_array_equal(second, suite.draw(rng, min_length_for(5)).points)
    env.reset(seed=4)
    np.testing.assert_array_equal(env.unwrapped.pipeline.points, first)
    # the episode's summary is in every info, the episode so far: a count over the steps
    h = Heuristic()
    obs, info = env.reset(seed=4)
    assert np.isnan(info["episode_pipe_in_view"]) and np.isnan(info["episode_rms_e_dist"])  # no decision
    seen, e2 = 0, 0.0
    for t in range(5):
        obs, r, term, trunc, info = env.step([h.act(obs) if info["pipe_in_view"] else 0.0])
        seen += info["pipe_in_view"]
        e2 += info["e_dist"] ** 2 if info["pipe_in_view"] else 0.0
        assert trunc == (t == 4) and info["episode_pipe_in_view"] == seen / (t + 1)
        assert info["episode_progress_m"] == info["progress_m"]
    assert info["episode_pipe_in_view"] == seen / 5
    assert info["episode_progress_m"] == info["progress_m"] > 0.5
    assert info["episode_rms_e_dist"] == pytest.approx(math.sqrt(e2 / seen), rel=1e-12)


def test_vector_env_autoresets_onto_new_pipes():
    envs = gym.make_vec(
        "pipefollow/PipelineFollowing-v0",
        num_envs=1,
        vectorization_mode="sync",
        pipeline="random",
        episode_seconds=2,
    )
    envs.reset(seed=0)
    seen = set()
    for _ in range(9):
        envs.step(np.zeros((1, 1), dtype=np.float32))
        seen.add(envs.unwrapped.envs[0].unwrapped.pipeline.points.tobytes())
    envs.close()
    assert len(seen) >= 3


def test_trial_with_random_phases_is_reproducible():
    config = TrialConfig(
        name="t",
        supervised=True,
        phases=(Phase("random:easy", 5), Phase("random:hard", 5)),
        evaluate_on="paper-validation",
    )
    a, b = run_trial(config, 7), run_trial(config, 7)
    np.testing.assert_array_equal(a.stats, b.stats)
    np.testing.assert_array_equal(a.weights, b.weights)
    assert a.stats.shape == (10, 4)
    # the same numbers as the library call with the trial's generator's child
    rng = np.random.default_rng(7)
    from pipefollow.experiments.trial import build_agent

    agent = build_agent(config, rng)
    pipe_rng = rng.spawn(1)[0]
    s1 = train_random_compiled(agent, get_suite("easy"), 5, pipe_rng=pipe_rng)
    s2 = train_random_compiled(agent, get_suite("hard"), 5, pipe_rng=pipe_rng)
    np.testing.assert_array_equal(np.concatenate([s1, s2]), a.stats)


def test_cli_train_on_random_pipes(tmp_path):
    args = [
        "train",
        "--algorithm",
        "cacla",
        "--pipeline",
        "random:medium",
        "--episodes",
        "4",
        "--seconds",
        "10",
    ]
    r1 = CliRunner().invoke(main, [*args, "--out", str(tmp_path / "a"), "--json"])
    r2 = CliRunner().invoke(main, [*args, "--out", str(tmp_path / "b"), "--json"])
    assert r1.exit_code == 0, r1.output
    assert json.loads(r1.stdout)["returns"] == json.loads(r2.stdout)["returns"]
    bad = CliRunner().invoke(main, [*args[:4], "random:heldout", *args[5:], "--out", str(tmp_path / "c")])
    assert bad.exit_code == 2 and bad.stderr.startswith("pipefollow: error: ") and "held-out" in bad.stderr
    assert not (tmp_path / "c").exists()


def test_reset_option_switches_between_a_family_and_a_fixed_pipe():
    env = PipelineFollowingEnv("paper-left", 5)
    env.reset(seed=1, options={"pipeline": "random:medium"})
    rng = np.random.default_rng(1)
    np.testing.assert_array_equal(
        env.pipeline.points, get_suite("medium").draw(rng, min_length_for(5)).points
    )
    env.reset(options={"pipeline": "paper-right"})
    assert env.pipeline.name == "paper-right" and env.suite is None
    env.reset()
    assert env.pipeline.name == "paper-right"


@pytest.mark.parametrize("spec", ["random:nope", "random:heldout-hard"])
def test_experiment_with_a_bad_random_phase_is_refused_before_any_work(tmp_path, spec):
    toml = tmp_path / "e.toml"
    toml.write_text(
        '[experiment]\nname = "e"\n[[trial]]\nname = "t"\n'
        f'phases = [{{ pipeline = "{spec}", episodes = 2 }}]\n'
    )
    out = tmp_path / "run"
    res = CliRunner().invoke(
        main, ["reproduce", "--experiment", str(toml), "--out", str(out), "--backend", "serial"]
    )
    assert res.exit_code == 2, res.output
    assert res.stderr.startswith("pipefollow: error: ") and res.stderr.count("\n") == 1
    assert spec.partition(":")[2] in res.stderr
    assert not (out / "trials").exists() or not any((out / "trials").iterdir())
