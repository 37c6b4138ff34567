"""The compiled training path equals the Gymnasium-environment path, number for number."""

import numpy as np
import pytest

from pipefollow import readings as rd
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.sim import decision as sim
from pipefollow.sim.disturbance import make_disturbance
from pipefollow.sim.episode import new_book
from pipefollow.sim.pipeline import builtin
from pipefollow.training.agents import make_agent
from pipefollow.training.compiled import train, train_compiled

KINDS = {
    "cacla": dict(algorithm="cacla"),
    "cacla-skew": dict(algorithm="cacla", skew_deg=45.0),
    "supervised-skew": dict(algorithm="cacla", skew_deg=22.5, supervised=True),
    "supervised-skew-weights-step": dict(
        algorithm="cacla", skew_deg=22.5, supervised=True, readings=rd.parse("skew_step=weights")
    ),
    "supervised-skew-centred-k": dict(
        algorithm="cacla",
        skew_deg=22.5,
        supervised=True,
        readings=rd.parse("skew_sample=centred,k_update=positive,k_step=k"),
    ),
    "cacla-skew-moments-literal": dict(
        algorithm="cacla", skew_deg=45.0, readings=rd.parse("skew_sample=moments,rbf=literal,gamma_max=2")
    ),
    "sarsa": dict(algorithm="sarsa"),
    "sarsa-wide": dict(algorithm="sarsa", readings=rd.parse("rbf_width=half-range")),
}


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("pipeline", ["paper-left", "paper-validation"])
def test_compiled_path_equals_environment_path(kind, pipeline):
    pipe = builtin(pipeline)
    episodes = 12
    a = make_agent(rng=np.random.default_rng(3), **KINDS[kind])
    b = make_agent(rng=np.random.default_rng(3), **KINDS[kind])
    stats_env = train(PipelineFollowingEnv(pipe, 20), a, episodes)
    stats_fast = train_compiled(b, pipe, episodes, chunk=5)
    assert a.readings == KINDS[kind].get("readings", rd.DEFAULT).id
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
    # both consumed the same random numbers
    assert a.rng.standard_normal() == b.rng.standard_normal()


def test_equivalence_covers_lost_pipe_updates():
    # with full exploration the AUV loses the pipe: the semi-Markov path must be exercised
    pipe = builtin("paper-left")
    a = make_agent("cacla", rng=np.random.default_rng(0))
    b = make_agent("cacla", rng=np.random.default_rng(0))
    stats_env = train(PipelineFollowingEnv(pipe, 20), a, 10, sigma_start=1.0, sigma_end=1.0)
    stats_fast = train_compiled(b, pipe, 10, sigma_start=1.0, sigma_end=1.0)
    assert stats_env[:, 3].sum() > 0  # some time was spent with the pipe lost
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)


DISTURBED = make_disturbance(
    0.1,
    60.0,
    current_time_constant=20.0,
    current_speed_sd=0.03,
    current_direction_sd_deg=15.0,
    camera_noise=0.05,
    miss_prob=0.1,
    buried=[[3.0, 3.5]],
)


@pytest.mark.parametrize("kind", ["cacla", "supervised-skew", "sarsa"])
def test_compiled_path_equals_environment_path_with_disturbances(kind):
    # a current (varying), camera noise, misses and a buried stretch: the environment draws from
    # its np_random, the compiled loop from env_rng in the same state, in the same order
    pipe = builtin("paper-left")
    params = sim.PAPER_SIM._replace(disturbance=DISTURBED)
    a = make_agent(rng=np.random.default_rng(3), **KINDS[kind])
    b = make_agent(rng=np.random.default_rng(3), **KINDS[kind])
    env = PipelineFollowingEnv(pipe, 20, params=params)
    env.np_random = np.random.default_rng(11)
    env_rng = np.random.default_rng(11)
    stats_env = train(env, a, 8)
    stats_fast = train_compiled(b, pipe, 8, chunk=3, params=params, env_rng=env_rng)
    assert stats_env[:, 3].sum() > 0  # misses (and exploration) lost the pipe at times
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
    assert a.rng.standard_normal() == b.rng.standard_normal()
    assert env.np_random.standard_normal() == env_rng.standard_normal()
    # and the disturbances changed the numbers
    c = make_agent(rng=np.random.default_rng(3), **KINDS[kind])
    assert not np.allclose(train_compiled(c, pipe, 8), stats_fast)


class ScriptedEnv:
    """Visibility and rewards follow a script; observations are the state index."""

    def __init__(self, visible, rewards):
        self.visible, self.rewards = visible, rewards
        self.unwrapped = self
        self.params = type("P", (), {"dt": 0.05, "substeps": 20})()
        self.trail = []
        self.book = new_book()  # the environment's book: no distances travelled

    def reset(self, seed=None, options=None):
        self.t = 0
        return np.array([0.0]), {"pipe_in_view": self.visible[0], "progress_m": 0.0}

    def step(self, action):
        r = self.rewards[self.t]
        self.t += 1
        info = {"pipe_in_view": self.visible[self.t], "progress_m": float(self.t), "e_dist": 0.1 * self.t}
        return np.array([float(self.t)]), r, False, self.t == len(self.rewards), info


class Recorder:
    discount = 0.5

    def __init__(self):
        self.acts, self.updates = [], []

    def begin_episode(self, sigma):
        pass

    def act(self, obs, explore=True):
        self.acts.append(int(obs[0]))
        return 0.1 * obs[0]

    def update(self, obs, action, reward, next_obs, discount):
        self.updates.append((int(obs[0]), action, reward, int(next_obs[0]), discount))


def test_semi_markov_updates_while_the_pipe_is_lost_by_hand():
    from pipefollow.training.compiled import run_episode

    visible = [True, True, False, False, True, False, False, False]  # states s0 … s7
    rewards = [1.0, 2.0, -10.0, -10.0, 3.0, -10.0, -10.0]
    agent = Recorder()
    ep = run_episode(ScriptedEnv(visible, rewards), agent, learn=True, explore=True, sigma=0.3)
    g = 0.5
    assert agent.acts == [0, 1, 4]  # the agent acts only where the pipe is in view
    assert agent.updates == [
        (0, 0.0, 1.0, 1, g),  # ordinary one-step update
        (1, 0.1, 2.0 + g * -10.0 + g**2 * -10.0, 4, g**3),  # lost for two decisions, found again
        (4, 0.4, 3.0 + g * -10.0 + g**2 * -10.0, 7, g**3),  # lost until the time limit: bootstrap anyway
    ]
    assert ep.ret == sum(rewards)
    assert ep.pipe_in_view == pytest.approx(2 / 7)  # decisions ending with the pipe in view: s1, s4
    assert ep.n_in_view == 2 and ep.sum_e_dist2 == pytest.approx(0.1**2 + 0.4**2)
    assert ep.time_lost_s == pytest.approx(5.0)


def test_compiled_loop_refuses_a_custom_supervisor():
    from pipefollow.learners.cacla import Cacla
    from pipefollow.learners.cacla_act import CaclaParams

    agent = Cacla(CaclaParams(supervised=True), supervisor=lambda obs: 0.0)
    with pytest.raises(TypeError, match="heuristic only"):
        train_compiled(agent, builtin("paper-left"), 1)


def test_equivalence_with_a_cruise_start():
    pipe = builtin("paper-left")
    params = rd.sim_params(rd.parse("start_speed=cruise"))
    a = make_agent("cacla", skew_deg=22.5, rng=np.random.default_rng(1))
    b = make_agent("cacla", skew_deg=22.5, rng=np.random.default_rng(1))
    stats_env = train(PipelineFollowingEnv(pipe, 20, params=params), a, 8)
    stats_fast = train_compiled(b, pipe, 8, params=params)
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
    rest = train_compiled(make_agent("cacla", skew_deg=22.5, rng=np.random.default_rng(1)), pipe, 8)
    assert not np.array_equal(rest, stats_fast)  # the start speed changes the episodes


def test_the_compiled_loops_refuse_an_agent_they_cannot_run():
    from pipefollow.learners.heuristic import Heuristic
    from pipefollow.sim.suites import get_suite
    from pipefollow.training.random_pipes import train_random_compiled

    with pytest.raises(TypeError, match="no compiled training loop for Heuristic"):
        train_compiled(Heuristic(), builtin("paper-left"), 2)
    with pytest.raises(TypeError, match="no compiled training loop for Heuristic"):
        train_random_compiled(Heuristic(), get_suite("easy"), 2, pipe_rng=np.random.default_rng(0))
    noisy = sim.PAPER_SIM._replace(disturbance=make_disturbance(0.0, 0.0, camera_noise=0.05))
    with pytest.raises(ValueError, match="pass a seeded env_rng"):
        train_compiled(make_agent("cacla"), builtin("paper-left"), 2, params=noisy)
