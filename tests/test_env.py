import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import given, settings
from hypothesis import strategies as st

import pipefollow
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.envs.shell import SUMMARY_KEYS
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim import decision as sim
from pipefollow.sim.pipeline import Pipeline, random_pipeline
from pipefollow.training.compiled import run_episode


def test_check_env_passes():
    env = gym.make(pipefollow.ENV_ID, start_lateral_noise=0.3, start_heading_noise_deg=10.0)
    check_env(env.unwrapped)


def test_registered_id_makes_the_env():
    env = gym.make(pipefollow.ENV_ID, pipeline="paper-right", episode_seconds=5)
    obs, info = env.reset(seed=1)
    assert obs.shape == (4,)
    assert isinstance(env.unwrapped, PipelineFollowingEnv)
    assert env.unwrapped.pipeline.name == "paper-right"


def _episode(env, seed):
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    out = [obs]
    done = False
    while not done:
        obs, r, term, trunc, info = env.step(env.action_space.sample())
        out.append(np.concatenate([obs, [r], info["pose"]]))
        done = term or trunc
    return out


def test_same_seed_gives_identical_episode_and_other_seed_differs():
    env = PipelineFollowingEnv(start_lateral_noise=0.5, start_heading_noise_deg=20)
    a, b, c = _episode(env, 7), _episode(env, 7), _episode(env, 8)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not np.array_equal(a[0], c[0])


def test_nan_action_raises_and_out_of_range_is_clipped():
    env = PipelineFollowingEnv()
    env.reset()
    with pytest.raises(ValueError, match="NaN"):
        env.step(np.array([np.nan]))
    env.reset()
    clipped = env.step(np.array([5.0]))
    env.reset()
    limit = env.step(np.array([1.0]))
    np.testing.assert_array_equal(clipped[0], limit[0])
    assert clipped[4]["executed_action"] == 1.0


def test_truncates_after_episode_seconds_and_never_terminates():
    env = PipelineFollowingEnv(episode_seconds=7)
    env.reset()
    flags = [env.step([0.0])[2:4] for _ in range(7)]
    assert flags[-1] == (False, True)
    assert all(f == (False, False) for f in flags[:-1])


def test_info_has_the_contract_keys():
    env = PipelineFollowingEnv()
    _, info = env.reset()
    for key in ("pipe_in_view", "overridden", "e_dist", "e_angl", "progress_m", "pose"):
        assert key in info
    assert info["pose"].shape == (3,)


def test_reset_options_place_the_auv_and_unknown_options_fail():
    env = PipelineFollowingEnv()
    _, info = env.reset(options={"lateral_offset": 0.5, "heading_offset_deg": 0.0})
    # paper-left starts at the origin heading north: starboard is east (+y)
    np.testing.assert_allclose(info["pose"], [0.0, 0.5, 0.0], atol=1e-12)
    obs, _ = env.reset(options={"lateral_offset": 0.5})
    assert obs[2] == pytest.approx(-0.5)  # the pipe appears 0.5 m to port
    with pytest.raises(ValueError, match="unknown reset option"):
        env.reset(options={"bogus": 1})


def test_bad_constructor_arguments():
    with pytest.raises(ValueError, match="episode_seconds"):
        PipelineFollowingEnv(episode_seconds=0.5)
    with pytest.raises(ValueError, match="render_mode"):
        PipelineFollowingEnv(render_mode="ansi")


def test_render_draws_an_image():
    env = PipelineFollowingEnv(render_mode="rgb_array")
    env.reset()
    env.step([0.0])
    img = env.render()
    assert img.ndim == 3 and img.shape[2] == 3 and img.dtype == np.uint8
    assert img.std() > 0  # not a blank canvas


def test_heuristic_keeps_pipe_in_view_through_first_turn():
    env = PipelineFollowingEnv("paper-left")
    ep = run_episode(env, Heuristic())
    assert ep.pipe_in_view == 1.0
    assert ep.progress_m > 2.5  # the first turn is at 2 m


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    actions=st.lists(st.floats(-3, 3, allow_nan=False), min_size=1, max_size=40),
)
def test_random_actions_on_random_pipelines_keep_state_finite_and_bounded(seed, actions):
    pipe = random_pipeline(
        np.random.default_rng(seed), n_segments=4, length_range=(1.0, 6.0), turn_range_deg=(0.0, 150.0)
    )
    env = PipelineFollowingEnv(pipe, episode_seconds=len(actions))
    env.reset(seed=seed)
    for a in actions:
        obs, r, _, _, info = env.step([a])
        assert np.all(np.isfinite(env.state))
        assert np.isfinite(r)
        assert env.observation_space.contains(obs)
        u, v, yaw_rate = info["nu"]
        assert abs(u) < 1.0 and abs(v) < 1.0 and abs(yaw_rate) < 2.0
        assert r >= sim.PAPER_SIM.lost_reward


def test_lost_pipe_triggers_search_and_penalty():
    # a 1-m pipe north of the start; the AUV starts 1.5 m east of it, looking east: nothing in view
    pipe = Pipeline(np.array([[0.0, 0.0], [1.0, 0.0]]))
    env = PipelineFollowingEnv(pipe, episode_seconds=30)
    _, info = env.reset(options={"lateral_offset": 1.5, "heading_offset_deg": 90.0})
    assert not info["pipe_in_view"]
    history = []
    for _ in range(30):
        _, r, _, _, info = env.step([-1.0])
        history.append((r, info["overridden"], info["pipe_in_view"], info["pose"][2]))
    r, overridden, _, psi = history[0]
    assert overridden and r == -10.0
    assert info["executed_action"] in (-1.0, 1.0)
    # the search turns on the spot until the pipe is found again
    assert any(seen for _, _, seen, _ in history)
    for r, overridden, seen, _ in history:
        if overridden or not seen:
            assert r == -10.0


@pytest.mark.parametrize("action", [[0.1, 0.2], np.zeros((1, 1)), np.zeros(0), [[0.3]]])
def test_an_action_of_the_wrong_shape_is_refused(action):
    env = PipelineFollowingEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"action must have shape \(1,\)"):
        env.step(action)


@pytest.mark.parametrize("action", [[0.25], np.array([0.25], dtype=np.float32), 0.25, np.float64(0.25)])
def test_actions_of_shape_1_or_plain_numbers_are_the_same_action(action):
    env = PipelineFollowingEnv()
    env.reset(seed=0)
    ref = PipelineFollowingEnv()
    ref.reset(seed=0)
    np.testing.assert_array_equal(env.step(action)[0], ref.step([0.25])[0])


# the ids and their episodes in decisions, from the paper (§4.1: 20 s on the training pipes; §4.2:
# 60 s on the validation pipe) and the deep-RL guide's random-pipe regime (90 s), 1 s a decision
IDS = {
    "pipefollow/PipelineFollowing-v0": ("paper-left", 20, "state"),
    "pipefollow/PipelineFollowingImage-v0": ("paper-left", 20, "image"),
    "pipefollow/PipelineFollowingVision-v0": ("paper-left", 20, "state"),
    "pipefollow/PipelineFollowingRandom-v0": ("mixed-000", 90, "state"),
    "pipefollow/PipelineFollowingValidation-v0": ("paper-validation", 60, "state"),
}


@pytest.mark.parametrize("env_id", sorted(IDS))
def test_each_registered_id_ends_its_episode_where_its_time_limit_does(env_id):
    if env_id.endswith("Vision-v0"):
        pytest.importorskip("cv2")
    assert sorted(pipefollow.ENV_IDS) == sorted(IDS)
    pipe, steps, kind = IDS[env_id]
    assert gym.spec(env_id).max_episode_steps == steps
    env = gym.make(env_id)
    assert env.unwrapped.pipeline.name == pipe and env.observation_space.shape == (
        (96, 64, 1) if kind == "image" else (4,)
    )
    env.reset(seed=0)
    # the environment's own truncation (unwrapped) and gym.make's TimeLimit agree on the last step
    ends = [env.step([0.1])[3] for _ in range(steps)]
    assert ends == [False] * (steps - 1) + [True] and env.unwrapped.max_decisions == steps


def test_the_longest_episode_is_checked():
    from pipefollow.envs.env import MAX_EPISODE_SECONDS

    with pytest.raises(ValueError, match="episode_seconds must be from 1 to 86400"):
        PipelineFollowingEnv(episode_seconds=MAX_EPISODE_SECONDS + 1)


@pytest.mark.parametrize("seconds", [None, 7, 60])
def test_gym_make_keeps_the_envs_own_episode_length(seconds):
    kwargs = {} if seconds is None else {"episode_seconds": seconds}
    # an episode longer than the id's 20 steps needs max_episode_steps (the docstring says so)
    limit = {"max_episode_steps": seconds} if seconds == 60 else {}
    made = gym.make(pipefollow.ENV_ID, start_lateral_noise=0.5, **kwargs, **limit)
    assert isinstance(made, gym.wrappers.TimeLimit)
    check_env(made.unwrapped)
    direct = PipelineFollowingEnv(start_lateral_noise=0.5, **kwargs)
    a, b = _episode(made, seed=3), _episode(direct, seed=3)
    assert len(a) - 1 == (seconds or 20)  # decisions until truncation
    np.testing.assert_array_equal(np.array(a[1:]), np.array(b[1:]))


def test_a_longer_episode_than_the_ids_is_cut_by_its_time_limit_and_refused_by_make_vec():
    made = gym.make(pipefollow.ENV_ID, episode_seconds=60)  # Gymnasium's TimeLimit of the id: 20
    made.reset(seed=0)
    assert [made.step([0.0])[3] for _ in range(20)][-1]
    with pytest.raises(ValueError, match="pass max_episode_steps=60 with episode_seconds"):
        gym.make_vec(pipefollow.ENV_ID, num_envs=2, episode_seconds=60)
    vec = gym.make_vec(pipefollow.ENV_ID, num_envs=2, episode_seconds=60, max_episode_steps=60)
    assert vec.unwrapped.max_decisions == 60


def test_every_info_value_is_an_array_that_gymnasiums_vector_env_batches_with_its_dtype():
    env = PipelineFollowingEnv(episode_seconds=2)
    _, info = env.reset(seed=0)
    assert all(isinstance(v, np.ndarray) for v in info.values())
    assert info["pipe_in_view"].shape == () and info["pipe_in_view"].dtype == bool
    assert info["current"].shape == (2,)
    vec = gym.vector.SyncVectorEnv([lambda: PipelineFollowingEnv(episode_seconds=2) for _ in range(3)])
    _, batched = vec.reset(seed=0)
    for key, value in info.items():
        assert batched[key].dtype == value.dtype and batched[key].shape == (3, *value.shape), key
    vec.step(np.zeros((3, 1)))
    _, _, _, trunc, batched = vec.step(np.zeros((3, 1)))
    assert trunc.all() and batched["episode_rms_e_dist"].dtype == np.float64


def test_the_current_info_is_the_disturbances_current():
    from pipefollow.sim.disturbance import make_disturbance

    env = PipelineFollowingEnv(disturbance=make_disturbance(0.15, 60.0))
    _, info = env.reset(seed=0)
    np.testing.assert_allclose(info["current"], [0.15, np.pi / 3], rtol=1e-15)
    np.testing.assert_array_equal(PipelineFollowingEnv().reset()[1]["current"], [0.0, 0.0])


def test_float32_observations_are_the_float64_ones_rounded():
    check_env(gym.make(pipefollow.ENV_ID, obs_dtype="float32").unwrapped)
    env32 = PipelineFollowingEnv("random:hard", obs_dtype="float32", start_lateral_noise=0.5)
    env64 = PipelineFollowingEnv("random:hard", start_lateral_noise=0.5)
    assert env32.observation_space.dtype == np.float32 and env32.observation_space.low.dtype == np.float32
    o32, o64 = env32.reset(seed=4)[0], env64.reset(seed=4)[0]
    for t in range(20):
        assert o32.dtype == np.float32 and o32 in env32.observation_space
        np.testing.assert_array_equal(o32, o64.astype(np.float32))
        o32, o64 = env32.step([np.sin(t)])[0], env64.step([np.sin(t)])[0]
    with pytest.raises(ValueError, match="obs_dtype must be one of float64, float32, got 'int8'"):
        PipelineFollowingEnv(obs_dtype="int8")


def test_gym_make_takes_a_pipeline_of_points():
    env = gym.make(pipefollow.ENV_ID, pipeline=[[0, 0], [5, 0], [5, 5]])
    obs, _ = env.reset(seed=0)
    assert env.unwrapped.pipeline.length == 10.0
    # on the first point heading north along the first segment: the pipe runs up the frame's centre
    np.testing.assert_allclose(obs, [0.0, 3.0, 0.0, 0.0], atol=1e-12)
    _, info = env.reset(options={"pipeline": [[0, 0], [0, 4]], "lateral_offset": 0.5})
    np.testing.assert_allclose(info["pose"], [-0.5, 0.0, np.pi / 2], atol=1e-12)  # heading east, offset south
    with pytest.raises(ValueError, match="pipeline points: needs at least two distinct points, got 1"):
        PipelineFollowingEnv([[0, 0]])


def test_stepping_after_the_end_with_strict_reset_says_to_reset():
    from gymnasium.error import ResetNeeded

    env = PipelineFollowingEnv(episode_seconds=2, strict_reset=True)
    with pytest.raises(ResetNeeded, match=r"call reset\(\) before the first step"):
        env.step([0.0])
    env.reset(seed=0)
    env.step([0.0])
    assert env.step([0.0])[3]
    with pytest.raises(ResetNeeded, match=r"the episode has ended: call reset\(\)"):
        env.step([0.0])
    env.reset()
    assert not env.step([0.0])[3]


def test_stepping_after_the_end_warns_once_and_carries_on_as_gymnasiums_environments():
    from gymnasium.error import ResetNeeded

    env = PipelineFollowingEnv(episode_seconds=2)
    with pytest.raises(ResetNeeded, match=r"call reset\(\) before the first step"):
        env.step([0.0])  # before the first reset there is nothing to carry on
    env.reset(seed=0)
    env.step([0.0])
    *_, truncated, last = env.step([0.0])
    assert truncated and last["episode_progress_m"] == last["progress_m"]
    t_end = env.state[sim.TIME]
    with pytest.warns(UserWarning, match="after the episode's end"):
        _, r, terminated, truncated, info = env.step([0.0])
    assert truncated and not terminated and info["progress_m"] > last["progress_m"]
    for key in SUMMARY_KEYS:  # past the end the summary stays the episode's
        np.testing.assert_array_equal(info[key], last[key])
        assert info[key] is not last[key]
    assert env.state[sim.TIME] == t_end + 1.0 and np.isfinite(r)  # the simulation went on
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # once per episode: a second step past the end is silent
        assert env.step([0.0])[3]
    env.reset()
    assert not env.step([0.0])[3]
    env.step([0.0])
    with pytest.warns(UserWarning, match="after the episode's end"):  # warned again after a reset
        env.step([0.0])


def test_bad_reset_offsets_are_refused():
    env = PipelineFollowingEnv()
    with pytest.raises(ValueError, match="reset option lateral_offset must be a finite number, got nan"):
        env.reset(options={"lateral_offset": float("nan")})


@pytest.mark.parametrize("copier", ["pickle", "deepcopy"])
def test_pickle_and_deepcopy_after_render_continue_with_the_same_numbers(copier):
    import copy
    import pickle

    from pipefollow.sim.disturbance import make_disturbance

    env = PipelineFollowingEnv(
        "random:mixed", render_mode="rgb_array", disturbance=make_disturbance(0.0, 0.0, camera_noise=0.05)
    )
    env.reset(seed=2)
    env.step([0.3])
    env.render()
    twin = pickle.loads(pickle.dumps(env)) if copier == "pickle" else copy.deepcopy(env)
    for a in (0.1, -0.4, 0.8):
        mine, theirs = env.step([a]), twin.step([a])
        np.testing.assert_array_equal(mine[0], theirs[0])
        assert mine[1] == theirs[1]
    np.testing.assert_array_equal(twin.render(), env.render())  # the copy draws its own figure
    env.close()
    twin.close()
