"""The episode ends at the far end of a finite pipe (reading pipe_end), alike on every path."""

import math

import numpy as np
import pytest

from pipefollow import readings as rd
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.envs.vector_env import PipelineFollowingVectorEnv
from pipefollow.evaluation.benchmark import _env_episodes, run_episodes
from pipefollow.learners.heuristic import Heuristic
from pipefollow.learners.los import LOS
from pipefollow.sim import decision as sim
from pipefollow.sim import episode as ep
from pipefollow.sim.pipeline import Pipeline
from pipefollow.training.agents import make_agent
from pipefollow.training.compiled import run_episode, train, train_compiled

# 6 m north, then 4 m with a 20° bend to starboard: about 22 s at cruise speed, shorter than 60 s
BEND = math.radians(20.0)
END = [6.0 + 4.0 * math.cos(BEND), 4.0 * math.sin(BEND)]
SHORT = Pipeline(np.array([[0.0, 0.0], [6.0, 0.0], END]), "short")
ENDS, PAPER = rd.sim_params(rd.parse("default")), rd.sim_params(rd.parse("pipe_end=continue"))


@pytest.fixture
def pipe_file(tmp_path):
    path = tmp_path / "short.json"
    SHORT.save(path)
    return str(path)


def heuristic_episode(env):
    """The heuristic's episode in ``env``: its rewards, progress after each decision, the last step."""
    obs, info = env.reset(seed=0)
    rewards, progress, agent = [], [], Heuristic()
    while True:
        obs, r, terminated, truncated, info = env.step([agent.act(obs)])
        rewards.append(r)
        progress.append(float(info["progress_m"]))
        if terminated or truncated:
            return np.array(rewards), np.array(progress), (terminated, truncated, info)


def test_reaching_the_far_end_of_a_pipe_file_ends_the_episode(pipe_file):
    length = SHORT.length
    rewards, progress, (terminated, truncated, info) = heuristic_episode(PipelineFollowingEnv(pipe_file, 60))
    assert terminated and not truncated and bool(info["reached_pipe_end"])
    assert 15 < len(rewards) < 60  # well before the time limit
    # reached: within half a metre of the end, and not one decision before
    assert length - ep.END_MARGIN_M <= progress[-1] <= length and progress[-2] < length - ep.END_MARGIN_M
    assert bool(info["pipe_in_view"]) and rewards.min() > -10.0  # the end still in the camera: no −10
    # the paper's reading: the episode runs its 60 s; past the end the pipe is lost (−10) until the
    # search finds it again behind the AUV, and what follows adds up to less than nothing
    rewards_p, progress_p, (terminated, truncated, info) = heuristic_episode(
        PipelineFollowingEnv(pipe_file, 60, params=PAPER)
    )
    assert truncated and not terminated and not info["reached_pipe_end"] and len(rewards_p) == 60
    np.testing.assert_array_equal(rewards_p[: len(rewards)], rewards)  # the same until the end
    assert progress_p[-1] == length and np.sum(rewards_p == -10.0) >= 3
    assert rewards_p[len(rewards) :].sum() < 0


def test_finishing_the_pipe_scores_no_worse_than_stopping_halfway(pipe_file):
    # A controller that stops where the heuristic passes half the pipe gets the heuristic's rewards
    # until then and at most 0 a decision after: eq. 19 is v_x − e_dist² − e_angl² − Δa² ≤ v_x = 0
    # at rest, and a lost pipe gives −10. Running on to the end must not score less.
    for params, finishing_pays in ((ENDS, True), (PAPER, False)):
        rewards, progress, _ = heuristic_episode(PipelineFollowingEnv(pipe_file, 60, params=params))
        k = int(np.argmax(progress >= SHORT.length / 2)) + 1  # decisions until half the pipe is passed
        stopped_at_best = rewards[:k].sum() + 0.0 * (60 - k)
        assert (rewards.sum() >= stopped_at_best) == finishing_pays


@pytest.mark.parametrize("agent", [Heuristic(), LOS()], ids=["heuristic", "los"])
def test_the_compiled_episodes_end_where_the_environment_ends(agent):
    pipes = [SHORT, SHORT.mirror("mirrored")]
    fast, poses = run_episodes(agent, pipes, 60.0, ENDS)
    slow, slow_poses = np.zeros_like(fast), np.zeros_like(poses)
    _env_episodes(agent, pipes, 60.0, ENDS, slow, slow_poses)
    np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-9)
    np.testing.assert_allclose(poses, slow_poses, rtol=0, atol=1e-9)
    n = int(fast[0, ep.STAT_N_SEEN])  # every decision ended in view: the decisions made
    assert fast[0, ep.STAT_IN_VIEW] == 1.0 and n < 60
    np.testing.assert_array_equal(poses[0, n + 1 :], np.repeat(poses[0, n : n + 1], 60 - n, axis=0))
    assert fast[0, ep.STAT_PROGRESS] >= SHORT.length - ep.END_MARGIN_M


@pytest.mark.parametrize("kind", ["cacla", "sarsa"])
def test_a_policy_of_a_learner_ends_alike_in_its_compiled_loop_and_the_environment(kind):
    agent = make_agent(kind, supervised=True, rng=np.random.default_rng(1)) if kind == "cacla" else (
        make_agent(kind, rng=np.random.default_rng(1))
    )  # fmt: skip
    if kind == "cacla":
        agent.weights[3] = 0.0  # k(s) = 0: the heuristic acts, so the AUV reaches the end
    fast, _ = run_episodes(agent, [SHORT], 60.0, ENDS)
    slow, slow_poses = np.zeros_like(fast), np.zeros((1, 61, 3))
    _env_episodes(agent, [SHORT], 60.0, ENDS, slow, slow_poses)
    np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-9)


def test_training_to_the_pipe_end_equals_the_environment_path_with_no_bootstrap_from_the_end():
    a = make_agent("cacla", supervised=True, rng=np.random.default_rng(0))
    b = make_agent("cacla", supervised=True, rng=np.random.default_rng(0))
    opts = dict(sigma_start=0.05, sigma_end=0.01)
    stats_env = train(PipelineFollowingEnv(SHORT, 60, params=ENDS), a, 6, **opts)
    stats_fast = train_compiled(b, SHORT, 6, episode_seconds=60.0, params=ENDS, **opts)
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
    assert np.all(stats_env[:, ep.STAT_PROGRESS] >= SHORT.length - ep.END_MARGIN_M)  # each ended there
    # the terminal update bootstraps from nothing; under the paper's reading the weights move otherwise
    c = make_agent("cacla", supervised=True, rng=np.random.default_rng(0))
    train_compiled(c, SHORT, 6, episode_seconds=60.0, params=PAPER, **opts)
    assert not np.allclose(c.weights, b.weights)


def test_the_vector_environment_terminates_with_the_single_one():
    vec = PipelineFollowingVectorEnv(2, pipeline=SHORT, episode_seconds=60)
    single = PipelineFollowingEnv(SHORT, 60)
    obs, _ = vec.reset(seed=[0, 0])
    o1, _ = single.reset(seed=0)
    agent = Heuristic()
    for _ in range(60):
        obs, r, terminated, truncated, infos = vec.step([agent.act(obs[0]), agent.act(obs[1])])
        o1, r1, te1, tr1, info1 = single.step([agent.act(o1)])
        np.testing.assert_allclose(obs[0], o1, rtol=0, atol=1e-12)
        assert (r[0], terminated[0], truncated[0]) == (r1, te1, tr1)
        if te1:
            assert terminated.all() and infos["reached_pipe_end"].tolist() == [True, True]
            assert infos["_reached_pipe_end"].all()
            assert infos["episode_progress_m"][0] == pytest.approx(float(info1["episode_progress_m"]))
            break
    else:
        pytest.fail("the episode did not end at the pipe's end")
    obs, r, terminated, truncated, _ = vec.step([0.0, 0.0])  # next-step autoreset
    assert not terminated.any() and (r == 0.0).all()
    np.testing.assert_array_equal(obs[0], single.reset()[0])  # a fresh start: the single one's first
    assert vec.states[0, sim.PROGRESS_MAX] == 0.0  # back at the pipe's start


def test_stepping_past_the_pipe_end_warns_and_keeps_terminating():
    env = PipelineFollowingEnv(SHORT, 60)
    *_, (terminated, _, _) = heuristic_episode(env)
    assert terminated
    with pytest.warns(UserWarning, match="after the episode's end"):
        _, _, terminated, truncated, info = env.step([0.0])
    assert terminated and not truncated and bool(info["reached_pipe_end"])
    strict = PipelineFollowingEnv(SHORT, 60, strict_reset=True)
    heuristic_episode(strict)
    from gymnasium.error import ResetNeeded

    with pytest.raises(ResetNeeded):
        strict.step([0.0])


def test_run_episode_of_the_environment_stops_at_the_end_and_counts_the_distance(pipe_file):
    stats = run_episode(PipelineFollowingEnv(pipe_file, 60), Heuristic())
    n = len(stats.poses) - 1
    assert n < 60 and stats.pipe_in_view == 1.0 and stats.time_lost_s == 0.0
    swum = np.hypot(*np.diff(stats.poses[:, :2], axis=0).T).sum()  # the straight lines between poses
    assert stats.swum_m == pytest.approx(swum, rel=1e-12) and stats.back_m == 0.0
