"""The environments with the vision camera and the image observation."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.envs.vector_env import PipelineFollowingVectorEnv
from pipefollow.sim.pipeline import Pipeline
from pipefollow.sim.reward import LOST_REWARD, reward

STRAIGHT = Pipeline(np.array([[0.0, 0.0], [40.0, 0.0]]), name="straight")


def heuristic(obs):
    return [math.atan2(obs[0], obs[1]) / (0.5 * math.pi)]


def test_image_observation_with_the_ideal_camera_leaves_the_dynamics_alone():
    plain = PipelineFollowingEnv("paper-validation", 30.0)
    pixels = PipelineFollowingEnv("paper-validation", 30.0, observation="image")
    assert pixels.observation_space == gym.spaces.Box(0, 255, (96, 64, 1), np.uint8)  # H × W × channel
    obs, _ = plain.reset(seed=1)
    img, info = pixels.reset(seed=1)
    assert img.shape == (96, 64, 1) and img.dtype == np.uint8
    np.testing.assert_array_equal(img[..., 0], pixels._vision.image)  # the rendered image, row 0 far
    for _ in range(30):
        a = heuristic(obs)
        obs, r, _, _, _ = plain.step(a)
        img, r_img, _, _, info = pixels.step(a)
        assert r_img == r and np.array_equal(info["pose"], plain.state[8:11])
    assert img.std() > 5.0  # a picture, not a blank


def test_vision_camera_in_clear_water_reads_a_straight_pipe_like_the_ideal_camera():
    env = PipelineFollowingEnv(STRAIGHT, 20.0, start_lateral_noise=0.5, camera="vision", water="clear")
    obs, info = env.reset(seed=3)
    for _ in range(20):
        assert info["detected"] and info["true_pipe_in_view"]
        s = env.state
        truth = env._vision.truth
        assert abs(obs[0] - truth[1]) < 0.05 and abs(obs[2] - truth[3]) < 0.05
        assert obs[3] == s[3]  # v_x is the vehicle's own
        obs, r, _, _, info = env.step(heuristic(obs))


@pytest.mark.parametrize("reward_from", ["truth", "detected"])
def test_reward_comes_from_the_source_it_is_told(reward_from):
    env = PipelineFollowingEnv(
        STRAIGHT, 20.0, start_lateral_noise=0.5, camera="vision", reward_from=reward_from
    )
    obs, info = env.reset(seed=4)
    a_prev = 0.0
    for _ in range(10):
        obs, r, _, _, info = env.step(heuristic(obs))
        assert info["detected"]
        if reward_from == "truth":
            expected = reward(
                obs[3], info["true_e_dist"], info["true_e_angl"], info["executed_action"], a_prev
            )
        else:
            expected = reward(obs[3], info["e_dist"], info["e_angl"], info["executed_action"], a_prev)
        assert r == pytest.approx(expected, abs=1e-12)
        a_prev = info["executed_action"]


def test_a_pipe_the_detector_cannot_see_is_a_lost_pipe():
    # turbidity 3/m: a veil and nothing else; the true camera sees the pipe all along
    env = PipelineFollowingEnv(STRAIGHT, 10.0, camera="vision", water={"turbidity": 3.0})
    env.reset(seed=0)
    for _ in range(10):
        _, r, _, _, info = env.step([0.0])
        assert r == LOST_REWARD and not info["detected"] and info["true_pipe_in_view"]
        assert info["overridden"]  # the search flies every decision


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"camera": "stereo"}, "camera must be one of ideal, vision, vision-raw; got 'stereo'"),
        ({"observation": "pixels"}, "observation must be one of state, image"),
        ({"reward_from": "detected"}, "needs camera='vision'"),
        ({"camera": "vision", "water": {"turbidity": math.nan}}, "water setting turbidity"),
        ({"camera": "vision", "water": "murky"}, "water preset 'murky'"),
        ({"water": "turbid"}, "water='turbid' has no effect on the ideal camera's state observation"),
        ({"water": {"burial": 0.5}, "camera": "ideal"}, "has no effect"),
    ],
)
def test_bad_camera_arguments_are_one_line_errors(kwargs, message):
    with pytest.raises(ValueError, match=message):
        PipelineFollowingEnv(**kwargs)


@pytest.mark.parametrize("kwargs", [{"camera": "vision"}, {"observation": "image"}])
def test_gymnasium_checker_passes(kwargs):
    check_env(gym.make("pipefollow/PipelineFollowing-v0", **kwargs).unwrapped, skip_render_check=True)


def test_vector_env_with_the_vision_camera_equals_single_environments():
    kwargs = {"episode_seconds": 5.0, "camera": "vision", "water": "moderate", "start_lateral_noise": 0.4}
    vec = PipelineFollowingVectorEnv(3, "random:medium", **kwargs)
    singles = [PipelineFollowingEnv("random:medium", **kwargs) for _ in range(3)]
    obs, infos = vec.reset(seed=10)
    single_obs = [e.reset(seed=10 + i)[0] for i, e in enumerate(singles)]
    ended = [False] * len(singles)  # the single environment's episode has ended: next-step autoreset
    for _ in range(7):  # across an autoreset
        assert np.array_equal(obs, np.array(single_obs))
        actions = np.array([heuristic(o)[0] for o in obs])
        obs, rewards, _, truncated, infos = vec.step(actions)
        stepped = []
        for i, e in enumerate(singles):
            if ended[i]:
                (o, _), ended[i] = e.reset(), False
                assert rewards[i] == 0.0
            else:
                o, r, _, ended[i], info = e.step([actions[i]])
                assert rewards[i] == r and infos["detected"][i] == info["detected"]
            stepped.append(o)
        single_obs = stepped


def test_vector_env_image_observations():
    vec = PipelineFollowingVectorEnv(2, "paper-left", observation="image")
    obs, _ = vec.reset(seed=0)
    assert obs.shape == (2, 96, 64, 1) and obs.dtype == np.uint8
    assert vec.observation_space.shape == (2, 96, 64, 1)


def test_render_shows_the_camera_image_beside_the_map():
    plain = PipelineFollowingEnv("paper-left", render_mode="rgb_array")
    vision = PipelineFollowingEnv("paper-left", render_mode="rgb_array", camera="vision")
    plain.reset(seed=0)
    vision.reset(seed=0)
    a, b = plain.render(), vision.render()
    assert b.shape[0] == a.shape[0] and b.shape[1] > a.shape[1]
    panel = b[:, a.shape[1] :]
    assert (panel[..., 0] > 200).any() and (panel[..., 1] < 60).any()  # the red detection line
    plain.close()
    vision.close()


HOOK = math.radians(135.0)
SHARP = Pipeline(
    np.array([[0.0, 0.0], [6.0, 0.0], [6.0 + 10.0 * math.cos(HOOK), 10.0 * math.sin(HOOK)]]), name="hook"
)


def run_heuristic(env, seed, steps):
    obs, info = env.reset(seed=seed)
    out = [(obs.copy(), info["pipe_in_view"].copy())]
    for _ in range(steps):
        obs, r, _, _, info = env.step(heuristic(obs))
        out.append((obs.copy(), info["pipe_in_view"].copy(), r, info["pose"].copy()))
    return out


def test_the_tracked_camera_is_deterministic_and_leaves_the_frames_to_the_seed():
    # the same seed gives the same episode; the tracker's navigation draws from a spawned generator,
    # so the first frames of the tracked and the raw camera are the same images
    a = run_heuristic(PipelineFollowingEnv(SHARP, 20.0, camera="vision"), 3, 20)
    b = run_heuristic(PipelineFollowingEnv(SHARP, 20.0, camera="vision"), 3, 20)
    for x, y in zip(a, b, strict=True):
        for u, v in zip(x, y, strict=True):
            np.testing.assert_array_equal(u, v)
    tracked = PipelineFollowingEnv(SHARP, 20.0, camera="vision")
    raw = PipelineFollowingEnv(SHARP, 20.0, camera="vision-raw")
    tracked.reset(seed=5)
    raw.reset(seed=5)
    np.testing.assert_array_equal(tracked._vision.image, raw._vision.image)
    tracked.step([0.0])
    raw.step([0.0])
    np.testing.assert_array_equal(tracked._vision.image, raw._vision.image)
    assert 0.0 <= float(tracked._info()["track_confidence"]) <= 1.0 and "track_confidence" not in raw._info()


def test_the_raw_camera_observes_each_frames_detection_as_it_is():
    env = PipelineFollowingEnv(STRAIGHT, 10.0, start_lateral_noise=0.3, camera="vision-raw")
    obs, info = env.reset(seed=2)
    for _ in range(10):
        obs, _, _, _, info = env.step(heuristic(obs))
        det = env._vision.detection
        if det.found:
            assert (obs[0], obs[1], obs[2]) == (det.x1, det.y1, det.x2)


def test_the_hook_is_followed_round_its_corner_with_the_vision_camera():
    # 135° to starboard after 6 m: both vision cameras keep the pipe in view as the exact camera
    # does (the detector joins the leg after the corner; before, it reported the first leg up to
    # the corner only and the raw camera kept the pipe in view at 0.63 of the decisions)
    seen = {}
    for camera in ("ideal", "vision", "vision-raw"):
        steps = run_heuristic(PipelineFollowingEnv(SHARP, 30.0, camera=camera), 0, 30)
        seen[camera] = np.mean([s[1] for s in steps[1:]])  # the exact camera's: the pipe truly in view
    assert seen["ideal"] >= 0.95 and seen["vision"] >= 0.85 and seen["vision-raw"] >= 0.85
