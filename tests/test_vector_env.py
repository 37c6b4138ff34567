import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, VectorEnv

import pipefollow  # noqa: F401  (registers the environment)
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.envs.vector_env import PipelineFollowingVectorEnv
from pipefollow.sim.disturbance import make_disturbance

ID = "pipefollow/PipelineFollowing-v0"


def make_vec(n, **kwargs):
    return gym.make_vec(ID, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)


def run_both(n, steps, seed, pipelines=None, **kwargs):
    """The vector env and n single envs (seeds seed + i) under the same actions; all outputs."""
    vec = make_vec(n, pipeline=pipelines or "paper-left", **kwargs)
    singles = [
        PipelineFollowingEnv(
            pipelines[i] if isinstance(pipelines, list) else (pipelines or "paper-left"), **kwargs
        )
        for i in range(n)
    ]
    rng = np.random.default_rng(seed)
    v_obs, _ = vec.reset(seed=seed)
    s_obs = np.array([e.reset(seed=seed + i)[0] for i, e in enumerate(singles)])
    np.testing.assert_array_equal(v_obs, s_obs)
    pending = np.zeros(n, dtype=bool)  # next-step autoreset: single env i resets at this step
    resets = 0
    for _ in range(steps):
        a = rng.uniform(-1, 1, size=(n, 1)).astype(np.float32)
        vo, vr, vte, vtr, vinfo = vec.step(a)
        for i, e in enumerate(singles):
            if pending[i]:
                o, r, te, tr = e.reset()[0], 0.0, False, False
                resets += 1
            else:
                o, r, te, tr, info = e.step(a[i])
                assert vinfo["pipe_in_view"][i] == info["pipe_in_view"]
                assert vinfo["progress_m"][i] == pytest.approx(info["progress_m"], abs=1e-12)
                if tr:
                    assert vinfo["_episode_progress_m"][i]
                    assert vinfo["episode_pipe_in_view"][i] == pytest.approx(info["episode_pipe_in_view"])
            np.testing.assert_allclose(vo[i], o, rtol=0, atol=1e-12)
            assert abs(vr[i] - r) <= 1e-12
            assert (vte[i], vtr[i]) == (te, tr)
            pending[i] = te or tr
    return resets


def test_make_vec_gives_the_native_vector_env_with_batched_spaces():
    vec = make_vec(3, pipeline="paper-right", episode_seconds=5)
    assert isinstance(vec, VectorEnv) and isinstance(vec.unwrapped, PipelineFollowingVectorEnv)
    assert vec.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    assert vec.observation_space.shape == (3, 4) and vec.action_space.shape == (3, 1)
    assert vec.single_observation_space == PipelineFollowingEnv().observation_space
    obs, info = vec.reset(seed=1)
    assert obs.shape == (3, 4) and obs in vec.observation_space
    assert info["pipe_in_view"].dtype == bool and info["_pipe_in_view"].all()
    assert info["pose"].shape == (3, 3)
    for _ in range(5):
        obs, rew, term, trunc, info = vec.step(vec.action_space.sample())
        assert obs.shape == (3, 4) and rew.shape == (3,) and term.dtype == bool
    assert trunc.all() and info["_episode_rms_e_dist"].all()
    obs, rew, term, trunc, info = vec.step(vec.action_space.sample())  # the autoreset step
    assert not trunc.any() and np.all(rew == 0.0) and "episode_progress_m" not in info
    np.testing.assert_array_equal(obs, vec.reset(seed=1)[0])  # a fixed pipe: the same start


def test_one_sub_environment_equals_the_single_environment():
    assert run_both(1, 70, seed=3, pipelines="random:hard", episode_seconds=20) == 3


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(pipelines="random:mixed", episode_seconds=15),
        dict(pipelines=["paper-left", "random:easy", "paper-validation"], episode_seconds=10,
             start_lateral_noise=0.3, start_heading_noise_deg=10),
        dict(pipelines="random", episode_seconds=12,
             disturbance=make_disturbance(0.1, 45.0, camera_noise=0.05, miss_prob=0.05)),
    ],
)  # fmt: skip
def test_n_sub_environments_equal_n_single_environments_across_autoresets(kwargs):
    pipelines = kwargs.pop("pipelines")
    n = len(pipelines) if isinstance(pipelines, list) else 4
    resets = run_both(n, 40, seed=11, pipelines=pipelines, **kwargs)
    assert resets >= n * 2


def test_reset_done_resets_at_once_with_the_autoreset_draws():
    a = make_vec(2, pipeline="random:mixed", episode_seconds=3)
    b = make_vec(2, pipeline="random:mixed", episode_seconds=3)
    a.reset(seed=5), b.reset(seed=5)
    act = np.zeros((2, 1), dtype=np.float32)
    for _ in range(3):
        a.step(act), b.step(act)
    first = a.unwrapped.reset_done()
    np.testing.assert_array_equal(first, b.step(act)[0])  # b autoresets on this step
    np.testing.assert_array_equal(a.step(act)[0], b.step(act)[0])


def test_gymnasium_vector_api_checks_and_bad_input():
    from gymnasium.utils.env_checker import data_equivalence

    vec = make_vec(4, pipeline="random:easy")
    obs1, _ = vec.reset(seed=42)
    obs2, _ = vec.reset(seed=42)
    assert data_equivalence(obs1, obs2)
    assert not np.array_equal(obs1[0], obs1[1]) or len({p.name for p in vec.unwrapped.pipelines}) == 4
    obs3, _ = vec.reset(seed=[7, 8, 9, 10])
    np.testing.assert_array_equal(obs3[0], PipelineFollowingEnv("random:easy").reset(seed=7)[0])
    with pytest.raises(ValueError, match="expected 4 actions"):
        vec.step(np.zeros((3, 1)))
    with pytest.raises(ValueError, match="NaN"):
        vec.step(np.full((4, 1), np.nan))
    with pytest.raises(ValueError, match="2 specs for 3"):
        make_vec(3, pipeline=["paper-left", "paper-right"])
    with pytest.raises(ValueError, match="episode_seconds"):
        make_vec(2, episode_seconds=0.1)
    vec.close()


def test_gymnasium_vector_wrappers_read_its_episodes():
    from gymnasium.wrappers.vector import RecordEpisodeStatistics

    vec = RecordEpisodeStatistics(make_vec(2, pipeline="random:easy", episode_seconds=5))
    vec.reset(seed=0)
    total = np.zeros(2)
    for t in range(7):
        obs, rew, term, trunc, info = vec.step(np.full((2, 1), 0.2, dtype=np.float32))
        total += rew
        if t == 4:
            assert trunc.all() and info["_episode"].all()
            np.testing.assert_allclose(info["episode"]["r"], total)
            np.testing.assert_array_equal(info["episode"]["l"], [5, 5])
    assert len(vec.return_queue) == 2 and not trunc.any()


def test_make_vec_takes_the_registered_upper_bound_and_refuses_a_shorter_limit():
    import gymnasium as gym

    env = gym.make_vec("pipefollow/PipelineFollowing-v0", num_envs=2, vectorization_mode="vector_entry_point")
    assert env.max_decisions == 20
    env.close()
    with pytest.raises(ValueError, match="max_episode_steps 5 is shorter than the episodes"):
        gym.make_vec(
            "pipefollow/PipelineFollowing-v0",
            num_envs=2,
            vectorization_mode="vector_entry_point",
            max_episode_steps=5,
        )
