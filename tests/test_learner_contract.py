"""What every learner of the registry must do: one set of tests over all of them.

A learner added to ``pipefollow.learners.registry`` is held to these without a new test: its
compiled loop equals its agent in the environment (with random disturbances too), its policy file
round-trips, ``pipefollow train --algorithm NAME`` and ``benchmark`` with its policy work, and an
experiment trial runs it.
"""

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow import readings as rd
from pipefollow.cli import main
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.evaluation.benchmark import _env_episodes, run_episodes
from pipefollow.experiments.schema import Phase, TrialConfig
from pipefollow.experiments.trial import run_trial
from pipefollow.learners.options import SWITCHES as OPTIONS
from pipefollow.learners.registry import LEARNERS, NAMES, learner, learner_of
from pipefollow.sim import decision as sim
from pipefollow.sim.disturbance import make_disturbance
from pipefollow.sim.pipeline import builtin
from pipefollow.sim.suites import get_suite
from pipefollow.training.agents import make_agent
from pipefollow.training.compiled import train, train_compiled
from pipefollow.training.policy_files import load_policy, save_policy

# every learner, and each with every shared option it takes switched on
ON = {
    "skew_deg": [22.5],
    "supervised": [True],
    "actor_update": ["positive", "sign"],
    "actor_repeats": ["var"],
    "critic_lambda": [0.6],
}  # OPTIONS switched on
SETUPS = [(name, {}) for name in NAMES] + [
    (name, {option: value})
    for name in NAMES
    for option in OPTIONS
    if option in LEARNERS[name].options
    for value in ON[option]
]
IDS = [name + "".join(f"-{k}={v}" for k, v in opts.items()) for name, opts in SETUPS]

NOISY = make_disturbance(0.1, 60.0, current_time_constant=20.0, current_speed_sd=0.03, camera_noise=0.05,
                         miss_prob=0.1)  # fmt: skip


def test_the_registry_knows_the_papers_learners_and_the_reference_one():
    assert {"sarsa", "cacla"} <= set(NAMES) and "ac" in NAMES  # the paper's learners and eq. 9's
    for name, kind in LEARNERS.items():
        assert kind.name == name and set(kind.options) <= set(OPTIONS) == set(ON)
        agent = make_agent(name)
        assert learner_of(agent) is kind and agent.algorithm == name
    with pytest.raises(ValueError, match="algorithm must be one of sarsa, cacla, ac, got 'q'"):
        learner("q")
    assert learner_of(object()) is None


@pytest.mark.parametrize(("name", "options"), SETUPS, ids=IDS)
def test_compiled_path_equals_the_environment_path(name, options):
    pipe = builtin("paper-left")
    a = make_agent(name, rng=np.random.default_rng(3), **options)
    b = make_agent(name, rng=np.random.default_rng(3), **options)
    stats_env = train(PipelineFollowingEnv(pipe, 20), a, 10, sigma_start=1.0, sigma_end=0.3)
    stats_fast = train_compiled(b, pipe, 10, chunk=4, sigma_start=1.0, sigma_end=0.3)
    assert stats_env[:, 3].sum() > 0  # the pipe was lost at times: the semi-Markov updates ran
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
    assert np.abs(a.weights).sum() > 0  # it learned something
    assert a.rng.standard_normal() == b.rng.standard_normal()  # the same random numbers


@pytest.mark.parametrize("name", NAMES)
def test_compiled_path_equals_the_environment_path_with_random_disturbances(name):
    pipe = builtin("paper-left")
    params = sim.PAPER_SIM._replace(disturbance=NOISY)
    a = make_agent(name, rng=np.random.default_rng(5))
    b = make_agent(name, rng=np.random.default_rng(5))
    env = PipelineFollowingEnv(pipe, 20, params=params)
    env.np_random = np.random.default_rng(17)
    stats_env = train(env, a, 6)
    stats_fast = train_compiled(b, pipe, 6, chunk=4, params=params, env_rng=np.random.default_rng(17))
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)


def _trained(name, options, episodes=15):
    agent = make_agent(
        name, rng=np.random.default_rng(1), readings=rd.parse("rbf_width=half-range"), **options
    )
    train_compiled(agent, builtin("paper-left"), episodes)
    return agent


@pytest.mark.parametrize(("name", "options"), SETUPS, ids=IDS)
def test_policy_file_round_trip(tmp_path, name, options):
    agent = _trained(name, options)
    path = save_policy(agent, tmp_path / "p.npz")
    loaded = load_policy(path)
    assert learner_of(loaded) is learner(name) and loaded.params == agent.params
    assert loaded.grid == agent.grid and loaded.readings == "rbf_width=half-range"
    np.testing.assert_array_equal(loaded.weights, agent.weights)
    for obs in np.random.default_rng(0).uniform([-1, 0, -1, -0.2], [1, 3, 1, 0.5], size=(30, 4)):
        assert loaded.act(obs, explore=False) == agent.act(obs, explore=False)
    with np.load(path, allow_pickle=False) as z:
        assert str(z["algorithm"]) == name


@pytest.mark.parametrize(("name", "options"), SETUPS, ids=IDS)
def test_benchmark_runs_the_learners_compiled_loop_as_the_environment_does(name, options):
    agent = _trained(name, options, episodes=8)
    pipes = get_suite("heldout").pipes(3)
    # calm: one compiled call over all pipes; noisy: one call per pipe with the pipe's generator
    for params in (sim.PAPER_SIM, sim.PAPER_SIM._replace(disturbance=NOISY)):
        res, poses = run_episodes(agent, pipes, 30.0, params, noise_seed=2)
        env_res, env_poses = np.zeros_like(res), np.zeros_like(poses)
        _env_episodes(agent, pipes, 30.0, params, env_res, env_poses, noise_seed=2)
        np.testing.assert_allclose(res, env_res, rtol=0, atol=1e-9)
        np.testing.assert_allclose(poses, env_poses, rtol=0, atol=1e-9)
        assert res[:, 4].sum() > 0  # some decisions in view, with their e_dist²


@pytest.mark.parametrize("name", NAMES)
def test_cli_train_and_benchmark_its_policy(tmp_path, name):
    runner = CliRunner()
    out = tmp_path / name
    args = ["train", "--algorithm", name, "--episodes", "4", "--seconds", "10", "--out", str(out), "--json"]
    if "supervised" in learner(name).options:
        args.append("--supervised")
    res = runner.invoke(main, args)
    assert res.exit_code == 0, res.output
    trained = json.loads(res.stdout)
    assert len(trained["returns"]) == 4
    policy = load_policy(trained["policy"])
    assert policy.algorithm == name
    res = runner.invoke(
        main,
        ["benchmark", "--controller", trained["policy"], "--suite", "heldout-easy", "--pipes", "3", "--json"],
    )
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    assert summary["n_episodes"] == 3 and "vs_heuristic" in summary


@pytest.mark.parametrize("name", [n for n in NAMES if "skew_deg" not in LEARNERS[n].options])
def test_cli_refuses_an_option_the_learner_does_not_take(tmp_path, name):
    res = CliRunner().invoke(
        main, ["train", "--algorithm", name, "--skew", "22.5", "--out", str(tmp_path / "x")]
    )
    assert res.exit_code == 2 and "--skew applies to --algorithm cacla only" in res.stderr
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("name", NAMES)
def test_an_experiment_trial_runs_every_learner(name):
    config = TrialConfig(name="t", algorithm=name, phases=(Phase("paper-left", 3),), episode_seconds=10.0)
    result = run_trial(config, 4)
    assert result.stats.shape == (3, 4) and set(result.evaluation) == {"learned", "heuristic"}
    assert result.weights.shape == make_agent(name).weights.shape
