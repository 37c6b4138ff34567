import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, VectorEnv

import pipefollow.envs  # noqa: F401  (registers the environment)
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.envs.shell import SUMMARY_KEYS
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
                for key in SUMMARY_KEYS:  # the episode's summary so far, at every step (NaN before it counts)
                    assert vinfo["_" + key][i]
                    np.testing.assert_allclose(vinfo[key][i], info[key], rtol=1e-12, equal_nan=True)
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
    assert not trunc.any() and np.all(rew == 0.0)
    assert np.isnan(info["episode_pipe_in_view"]).all()  # the new episodes' summaries: no decision yet
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


def assert_same_infos(native, reference):
    """Same keys, masks, dtypes and shapes; the same values wherever the reference's mask is set."""
    assert set(native) == set(reference), set(native) ^ set(reference)
    for key, value in reference.items():
        if key.startswith("_"):
            np.testing.assert_array_equal(native[key], value, err_msg=key)
        elif isinstance(value, dict):
            assert_same_infos(native[key], value)
        elif key == "final_obs":
            for i in np.flatnonzero(reference["_final_obs"]):
                np.testing.assert_allclose(native[key][i], value[i], rtol=0, atol=1e-12)
        else:
            mask = reference["_" + key]
            assert (native[key].dtype, native[key].shape) == (value.dtype, value.shape), key
            if value.dtype == bool:  # flags
                np.testing.assert_array_equal(native[key][mask], value[mask], err_msg=key)
            else:
                np.testing.assert_allclose(native[key][mask], value[mask], rtol=0, atol=1e-12, err_msg=key)


def assert_same_step(native_out, reference_out):
    *native, native_info = native_out
    *reference, reference_info = reference_out
    for a, b in zip(native, reference, strict=True):
        assert a.dtype == b.dtype and a.shape == b.shape
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
    assert_same_infos(native_info, reference_info)


@pytest.mark.parametrize("mode", list(AutoresetMode))
def test_every_autoreset_mode_equals_gymnasiums_sync_vector_env_of_single_environments(mode):
    from gymnasium.error import ResetNeeded

    kwargs = dict(
        pipeline="random:mixed", episode_seconds=4, start_lateral_noise=0.3,
        disturbance=make_disturbance(0.1, 45.0, camera_noise=0.05, miss_prob=0.05),
    )  # fmt: skip
    native = make_vec(3, autoreset_mode=mode, **kwargs)
    reference = gym.make_vec(
        ID, num_envs=3, vectorization_mode="sync", vector_kwargs={"autoreset_mode": mode}, **kwargs
    )
    assert native.autoreset_mode == mode and native.metadata["autoreset_mode"] == mode
    assert reference.metadata["autoreset_mode"] == mode
    assert_same_step(native.reset(seed=5), reference.reset(seed=5))
    rng = np.random.default_rng(0)
    ended = np.zeros(3, dtype=bool)
    ends = 0
    for t in range(15):
        if t == 2:  # sub-environment 1 starts again, out of step with the others
            mask = np.array([False, True, False])
            both = [e.reset(options={"reset_mask": mask}) for e in (native, reference)]
            assert_same_step(*both)
        act = rng.uniform(-1.2, 1.2, (3, 1)).astype(np.float32)
        if mode == AutoresetMode.DISABLED and ended.any():
            with pytest.raises(ResetNeeded, match=r"reset them with reset\(options=\{'reset_mask'"):
                native.step(act)
            both = [e.reset(options={"reset_mask": ended.copy()}) for e in (native, reference)]
            assert_same_step(*both)
        out = native.step(act)
        assert_same_step(out, reference.step(act))
        ended = out[3]
        ends += int(ended.sum())
        if mode == AutoresetMode.SAME_STEP and ended.any():
            assert set(out[4]["final_info"]) >= {"episode_pipe_in_view", "episode_progress_m", "current"}
    assert ends >= 8


def test_same_step_gives_the_last_observation_and_the_summary_of_the_single_environment():
    vec = make_vec(2, pipeline="random:easy", episode_seconds=3, autoreset_mode=AutoresetMode.SAME_STEP)
    singles = [PipelineFollowingEnv("random:easy", episode_seconds=3) for _ in range(2)]
    vec.reset(seed=9)
    for i, e in enumerate(singles):
        e.reset(seed=9 + i)
    act = np.array([[0.4], [-0.2]], dtype=np.float32)
    for _ in range(3):
        obs, rew, _, trunc, info = vec.step(act)
        single = [e.step(act[i]) for i, e in enumerate(singles)]
    assert trunc.all()
    for i, (o, r, _, tr, s_info) in enumerate(single):
        assert tr and rew[i] == r
        np.testing.assert_array_equal(info["final_obs"][i], o)
        for key in ("episode_pipe_in_view", "episode_progress_m", "episode_rms_e_dist", "pose"):
            np.testing.assert_array_equal(info["final_info"][key][i], s_info[key])
        np.testing.assert_array_equal(obs[i], singles[i].reset()[0])  # already the next episode's start


def test_info_keys_and_values_are_those_of_the_single_environment():
    dist = make_disturbance(0.2, 30.0)
    vec = make_vec(2, disturbance=dist, episode_seconds=2)
    single = PipelineFollowingEnv(disturbance=dist, episode_seconds=2)
    _, v_info = vec.reset(seed=0)
    _, s_info = single.reset(seed=0)
    assert {k for k in v_info if not k.startswith("_")} == set(s_info)
    for key, value in s_info.items():
        assert isinstance(value, np.ndarray) and v_info[key].shape == (2, *value.shape), key
        assert v_info[key].dtype == value.dtype, key
    # the current: 0.2 m/s towards 30° in both
    np.testing.assert_allclose(v_info["current"], [[0.2, np.radians(30.0)]] * 2, rtol=1e-15)
    vec.step(np.zeros((2, 1)))
    single.step([0.0])
    _, _, _, trunc, v_info = vec.step(np.zeros((2, 1)))
    s_info = single.step([0.0])[4]
    assert trunc.all() and "episode_rms_e_dist" in s_info
    assert {k for k in v_info if not k.startswith("_")} == set(s_info)


def test_autoreset_mode_is_chosen_as_gymnasium_make_vec_passes_arguments():
    vec = gym.make_vec(ID, num_envs=2, autoreset_mode="SameStep")
    assert vec.autoreset_mode == AutoresetMode.SAME_STEP == vec.metadata["autoreset_mode"]
    assert PipelineFollowingVectorEnv.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP  # not shared
    # Gymnasium passes vector_kwargs to its own vector wrappers only; for a vector entry point it refuses them
    with pytest.raises(gym.error.Error, match="vector_kwargs"):
        gym.make_vec(ID, num_envs=2, vector_kwargs={"autoreset_mode": AutoresetMode.SAME_STEP})
    sync = gym.make_vec(
        ID, num_envs=2, vectorization_mode="sync", vector_kwargs={"autoreset_mode": "Disabled"}
    )
    assert sync.autoreset_mode == AutoresetMode.DISABLED
    with pytest.raises(ValueError, match="autoreset_mode must be one of 'NextStep', 'SameStep', 'Disabled'"):
        make_vec(2, autoreset_mode="same-step")
    with pytest.raises(TypeError, match=r"unknown argument\(s\) \['episode_secs'\]"):
        make_vec(2, episode_secs=5)


def test_reset_mask_is_checked_as_gymnasium_checks_it():
    from gymnasium.error import ResetNeeded

    vec = make_vec(3)
    with pytest.raises(ResetNeeded, match="call reset"):
        vec.step(np.zeros((3, 1)))
    with pytest.raises(ValueError, match="first reset must reset every sub-environment"):
        vec.reset(options={"reset_mask": np.array([True, False, False])})
    vec.reset(seed=0)
    with pytest.raises(TypeError, match="reset_mask must be a numpy bool array"):
        vec.reset(options={"reset_mask": [True, False, True]})
    with pytest.raises(ValueError, match=r"must have shape \(3,\)"):
        vec.reset(options={"reset_mask": np.ones(2, dtype=bool)})
    with pytest.raises(ValueError, match="marks no sub-environment"):
        vec.reset(options={"reset_mask": np.zeros(3, dtype=bool)})
    with pytest.raises(ValueError, match=r"unknown reset option\(s\) \['bogus'\]; allowed: .*reset_mask"):
        vec.reset(options={"bogus": 1})


def test_pickle_and_deepcopy_continue_with_the_same_numbers():
    import copy
    import pickle

    vec = make_vec(3, pipeline="random:hard", episode_seconds=3, start_heading_noise_deg=10,
                   disturbance=make_disturbance(0.0, 0.0, camera_noise=0.05))  # fmt: skip
    vec.reset(seed=1)
    vec.step(np.full((3, 1), 0.3))
    copies = [pickle.loads(pickle.dumps(vec)), copy.deepcopy(vec)]
    act = np.linspace(-1, 1, 3)[:, None]
    for _ in range(5):  # across an autoreset: the pipes and the noise come from the copied generators
        out = vec.step(act)
        for c in copies:
            assert_same_step(c.step(act), out)


def test_points_as_pipeline_and_float32_observations():
    vec = make_vec(2, pipeline=[[0, 0], [5, 0], [5, 5]], obs_dtype="float32")
    assert [p.length for p in vec.unwrapped.pipelines] == [10.0, 10.0]
    obs, _ = vec.reset(seed=0)
    assert obs.dtype == np.float32 == vec.observation_space.dtype and obs in vec.observation_space
    ref = make_vec(2, pipeline=[[0, 0], [5, 0], [5, 5]])
    ref.reset(seed=0)
    a = np.full((2, 1), 0.1)
    np.testing.assert_array_equal(vec.step(a)[0], ref.step(a)[0].astype(np.float32))
    two = make_vec(2, pipeline=[[[0, 0], [5, 0]], [[0, 0], [0, 5]]])  # one list of points each
    assert [p.start_heading for p in two.unwrapped.pipelines] == [0.0, np.pi / 2]
