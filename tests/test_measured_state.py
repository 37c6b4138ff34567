"""The named states: the paper's (x1, y1, x2, v_x), and it with the DVL's sway and the gyro's yaw rate."""

import math

import numpy as np
import pytest

from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.learners.rbf import STATE_GRID
from pipefollow.sim import decision as sim
from pipefollow.sim.disturbance import make_disturbance, noise_count
from pipefollow.sim.observation import STATE_NAMES, slots, units
from pipefollow.sim.pipeline import builtin
from pipefollow.training.agents import make_agent
from pipefollow.training.compiled import train, train_compiled
from pipefollow.training.policy_files import load_policy, save_policy


def _truth(info) -> tuple[float, float]:
    """Sway over ground and yaw rate from the info: ν_r, the pose and the current (not the sensors)."""
    u, v, r = info["nu"]
    psi = info["pose"][2]
    speed, beta = info["current"]
    vn, ve = speed * math.cos(beta), speed * math.sin(beta)
    return v - math.sin(psi) * vn + math.cos(psi) * ve, r


def test_a_current_across_the_heading_is_all_sway_over_ground_at_rest():
    # at rest (ν_r = 0), heading north, a 0.1 m/s current towards east: the DVL reads +0.1 m/s (starboard)
    env = PipelineFollowingEnv([[0.0, 0.0], [10.0, 0.0]], 10, state="paper+drift",
                               disturbance=make_disturbance(0.1, 90.0))  # fmt: skip
    obs, info = env.reset(seed=0)
    assert info["pose"][2] == 0.0 and obs.shape == (5,)
    assert obs[4] == pytest.approx(0.1, abs=1e-15)
    for _ in range(5):
        obs, _, _, _, info = env.step([0.3])
        assert obs[4] == pytest.approx(_truth(info)[0], abs=1e-12)


def test_the_sensors_noise_has_its_standard_deviation_and_the_paper_state_is_unchanged():
    d = make_disturbance(0.1, 45.0, dvl_noise=0.02, gyro_noise_deg=1.0)
    assert noise_count(d) == 2 and noise_count(make_disturbance(0.1, 45.0)) == 0
    env = PipelineFollowingEnv("paper-validation", 200, state="paper+drift+yaw", disturbance=d)
    obs, info = env.reset(seed=3)
    errors = []
    for t in range(200):
        obs, _, _, _, info = env.step([0.2 * math.sin(t / 5.0)])
        sway, rate = _truth(info)
        errors.append((obs[4] - sway, obs[5] - rate))
    e = np.array(errors)
    # s.d. of 200 normal draws is within ±15 % of σ with probability > 0.97
    assert 0.85 * 0.02 < e[:, 0].std() < 1.15 * 0.02
    assert 0.85 * math.radians(1.0) < e[:, 1].std() < 1.15 * math.radians(1.0)
    assert abs(e[:, 0].mean()) < 3 * 0.02 / math.sqrt(200)
    # the paper's state: the four leading slots, as before
    paper = PipelineFollowingEnv("paper-validation", 200)
    assert paper.observation_space.shape == (4,) and paper.setup.observation_units == ("m", "m", "m", "m/s")
    assert env.setup.observation_units == ("m", "m", "m", "m/s", "m/s", "rad/s")
    assert env.observation_space.shape == (6,) and list(slots("paper")) == [0, 1, 2, 3]


@pytest.mark.parametrize("state, n", [("paper", 1764), ("paper+drift", 8820), ("paper+yaw", 8820),
                                      ("paper+drift+yaw", 44100)])  # fmt: skip
def test_each_measured_entry_multiplies_the_features_by_five(state, n):
    agent = make_agent("cacla", state=state)
    assert agent.grid.n_features == n and agent.grid.ndim == len(units(state))
    assert all(np.array_equal(a, b) for a, b in zip(agent.grid.centres[:4], STATE_GRID.centres, strict=True))


@pytest.mark.parametrize("name", ["cacla", "sarsa"])
def test_compiled_path_equals_the_environment_path_on_a_measured_state(name):
    pipe = builtin("paper-left")
    d = make_disturbance(0.1, 60.0, camera_noise=0.05, dvl_noise=0.02, gyro_noise_deg=0.5)
    params = sim.PAPER_SIM._replace(disturbance=d)
    options = {"supervised": True} if name == "cacla" else {}
    a = make_agent(name, rng=np.random.default_rng(5), state="paper+drift+yaw", **options)
    b = make_agent(name, rng=np.random.default_rng(5), state="paper+drift+yaw", **options)
    env = PipelineFollowingEnv(pipe, 20, params=params, state="paper+drift+yaw")
    env.np_random = np.random.default_rng(17)
    stats_env = train(env, a, 6)
    stats_fast = train_compiled(b, pipe, 6, chunk=4, params=params, env_rng=np.random.default_rng(17))
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
    assert np.abs(a.weights).sum() > 0
    with pytest.raises(ValueError, match="observes state 'paper', the agent 'paper\\+drift\\+yaw'"):
        train(PipelineFollowingEnv(pipe, 20), a, 1)


def test_a_policy_file_keeps_its_state(tmp_path):
    agent = make_agent("cacla", state="paper+yaw", rng=np.random.default_rng(0))
    train_compiled(agent, builtin("paper-left"), 3, episode_seconds=10)
    loaded = load_policy(save_policy(agent, tmp_path / "p.npz"))
    assert loaded.state == "paper+yaw" and loaded.grid == agent.grid
    np.testing.assert_array_equal(loaded.weights, agent.weights)
    names = ", ".join(STATE_NAMES).replace("+", "\\+")
    with pytest.raises(ValueError, match="state must be one of " + names):
        make_agent("cacla", state="paper+sonar")


def test_the_vector_environment_observes_the_same_measured_state():
    from pipefollow.envs.vector_env import PipelineFollowingVectorEnv

    d = make_disturbance(0.1, 45.0, dvl_noise=0.01, gyro_noise_deg=0.1)
    vec = PipelineFollowingVectorEnv(
        2, "paper-validation", episode_seconds=8, disturbance=d, state="paper+drift+yaw"
    )
    single = PipelineFollowingEnv("paper-validation", 8, disturbance=d, state="paper+drift+yaw")
    obs, _ = vec.reset(seed=4)
    one, _ = single.reset(seed=5)  # sub-environment i is the single environment reset with seed + i
    assert vec.single_observation_space == single.observation_space and obs.shape == (2, 6)
    np.testing.assert_array_equal(obs[1], one)
    for _ in range(5):
        obs, *_ = vec.step(np.full((2, 1), 0.25))
        one, *_ = single.step([0.25])
        np.testing.assert_array_equal(obs[1], one)


def test_a_measured_state_policy_is_evaluated_on_its_own_state(tmp_path):
    from click.testing import CliRunner

    from pipefollow.cli import main

    out = tmp_path / "p"
    res = CliRunner().invoke(main, ["train", "--algorithm", "cacla", "--supervised", "--state", "paper+drift",
                                    "--episodes", "3", "--seconds", "5", "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    policy = str(out / "policy.npz")
    for args in (["evaluate", "--controller", policy, "--current", "0.1,90"],
                 ["benchmark", "--controller", policy, "--pipes", "2"]):  # fmt: skip
        res = CliRunner().invoke(main, [*args, "--json"])
        assert res.exit_code == 0, res.output
    # the benchmark's compiled loop and the environment's episodes agree on the agent's own state
    from pipefollow.evaluation.benchmark import _env_episodes, run_episodes

    agent = load_policy(policy)
    pipes = [builtin("paper-validation"), builtin("paper-right")]
    params = sim.PAPER_SIM._replace(disturbance=make_disturbance(0.1, 90.0))
    fast, _ = run_episodes(agent, pipes, 30, params)
    slow, poses = np.zeros_like(fast), np.zeros((2, 31, 3))
    _env_episodes(agent, pipes, 30, params, slow, poses)
    np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-9)
