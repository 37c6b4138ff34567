import io

import gymnasium as gym
import numpy as np
import pytest
from matplotlib.colors import to_rgb

import pipefollow
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.envs.render import AUV_COLOR, CAMERA_COLOR, Scene
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim import decision as sim


def _run(env, decisions, seed=0):
    obs, _ = env.reset(seed=seed)
    agent = Heuristic()
    for _ in range(decisions):
        obs, *_ = env.step([agent.act(obs)])
    return env


def _pixel(scene, img, north, east):
    """The colour of the pixel at a map point (rows count from the top)."""
    px, py = scene.ax.transData.transform((east, north))
    h = img.shape[0]
    return img[int(round(h - py)), int(round(px))] / 255.0


def test_the_auv_and_its_footprint_are_drawn_where_the_state_says():
    env = _run(PipelineFollowingEnv("paper-left", render_mode="rgb_array"), 8)
    img = env.render()
    scene = env._scene
    s = env.state
    x, y, psi = s[sim.X], s[sim.Y], s[sim.PSI]
    # the hull's centre is AUV-coloured
    assert np.allclose(_pixel(scene, img, x, y), to_rgb(AUV_COLOR), atol=0.12)
    # the far edge of the footprint, 3 m ahead, is camera-coloured somewhere on its middle third
    cam = env.params.camera
    edge = [
        _pixel(
            scene,
            img,
            x + cam.depth * np.cos(psi) - lat * np.sin(psi),
            y + cam.depth * np.sin(psi) + lat * np.cos(psi),
        )
        for lat in np.linspace(-0.3, 0.3, 7)
    ]
    assert min(np.abs(np.array(edge) - to_rgb(CAMERA_COLOR)).max(axis=1)) < 0.15


def test_a_reused_figure_draws_the_same_frame_as_a_new_one():
    a = _run(PipelineFollowingEnv("paper-validation", 60, render_mode="rgb_array"), 5)
    a.render()  # an earlier frame on the same figure must leave no trace
    for _ in range(7):
        a.step([0.2])
    b = _run(PipelineFollowingEnv("paper-validation", 60, render_mode="rgb_array"), 5)
    for _ in range(7):
        b.step([0.2])
    first, fresh = a.render(), b.render()
    assert a._scene is not b._scene
    np.testing.assert_array_equal(first, fresh)


def test_the_blitted_frame_matches_a_full_redraw():
    env = _run(PipelineFollowingEnv("paper-left", render_mode="rgb_array"), 12)
    img = env.render().astype(float)
    buf = io.BytesIO()
    env._scene.fig.savefig(buf, format="rgba", dpi=env._scene.fig.dpi)  # draws everything anew
    full = np.frombuffer(buf.getvalue(), np.uint8).reshape(img.shape[0], img.shape[1], 4)[..., :3]
    assert np.mean(np.abs(img - full)) < 0.5  # antialiasing aside, the same picture


def test_a_new_pipeline_gets_a_new_figure():
    env = _run(PipelineFollowingEnv("paper-left", render_mode="rgb_array"), 2)
    env.render()
    first = env._scene
    env.reset(options={"pipeline": "paper-right"})
    env.render()
    assert env._scene is not first and env._scene.pipeline.name == "paper-right"


def test_human_mode_renders_through_pyplot_without_crashing():
    import matplotlib.pyplot as plt

    plt.switch_backend("Agg")  # headless, as in CI: no window, but the same code path

    env = gym.make(pipefollow.ENV_ID, render_mode="human", episode_seconds=3)
    assert not isinstance(env, gym.wrappers.HumanRendering)  # rendered natively
    env.reset(seed=0)
    for _ in range(3):
        env.step(np.array([0.1], dtype=np.float32))
    assert env.render() is None
    fig = env.unwrapped._scene.fig
    assert plt.fignum_exists(fig.number)
    env.close()
    assert not plt.fignum_exists(fig.number)


@pytest.mark.parametrize("size", [(5.0, 5.0)])
def test_scene_keeps_the_auv_in_view_when_it_leaves_the_pipe(size):
    env = _run(PipelineFollowingEnv("paper-left", render_mode="rgb_array"), 1)
    scene = Scene(env.pipeline, env.params, size=size)
    state = env.state.copy()
    state[sim.X], state[sim.Y] = 40.0, -30.0  # far away
    scene.update(state, np.array([[0.0, 0.0, 0.0], [40.0, -30.0, 0.0]])).rgb()
    lo_e, hi_e = scene.ax.get_xlim()
    lo_n, hi_n = scene.ax.get_ylim()
    assert lo_e < -30.0 - 3.0 and hi_n > 40.0 + 3.0  # the AUV and its footprint's reach
