"""``sensor="sonar"`` with ``observation="image"``: the camera's image observed, the sonar's episode.

The agent observes the camera image (the frames of ``observation="image"`` alone) while the sonar
writes the observation slots that decide the pipe in view, the search and the −10: rewards,
in-view and terminations are ``sensor="sonar"``'s with the state observation, for the same actions.
"""

import numpy as np
import pytest

from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.sim.suites import get_suite, min_length_for

pytest.importorskip("cv2")

PIPE = get_suite("heldout").pipe(3, min_length_for(60.0))


def _episode(**kwargs):
    env = PipelineFollowingEnv(PIPE, 60.0, **kwargs)
    obs, info = env.reset(seed=5)
    observations, rewards, in_view, sonar, ends = [obs], [], [], [], []
    for t in range(60):
        obs, r, terminated, truncated, info = env.step([0.5 * np.sin(t / 5)])  # the same actions for all
        observations.append(obs)
        rewards.append(r)
        in_view.append(bool(info["pipe_in_view"]))
        sonar.append(bool(info.get("sonar_in_view", False)))
        ends.append((terminated, truncated))
        if terminated or truncated:
            break
    return observations, np.array(rewards), np.array(in_view), np.array(sonar), ends


def test_the_image_is_the_cameras_and_the_episode_the_sonars():
    img, r_img, view_img, sonar_img, ends_img = _episode(sensor="sonar", observation="image", water="turbid")
    state, r_state, view_state, _, ends_state = _episode(sensor="sonar", water="turbid")
    camera, r_camera, _, _, _ = _episode(observation="image", water="turbid")
    assert img[0].shape == (96, 64, 1) and img[0].dtype == np.uint8
    np.testing.assert_array_equal(img[0], camera[0])  # the camera's first frame: its draws come first
    np.testing.assert_array_equal(r_img, r_state)  # the sonar's episode, whatever the agent observes
    np.testing.assert_array_equal(view_img, view_state)
    assert ends_img == ends_state
    np.testing.assert_array_equal(view_img, sonar_img)  # in view is the sonar's view of the footprint
    assert (~view_img).any() and np.all(r_img[~view_img] == -10.0)  # a pipe the sonar lost: −10
    assert not np.allclose(r_img, r_camera)  # not the exact camera's episode
