import numpy as np
import pytest
from PIL import Image

from pipefollow.envs import animation
from pipefollow.envs.animation import Recorder, check_animation_path, write_animation
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.files.output_paths import OutputError
from pipefollow.learners.heuristic import Heuristic
from pipefollow.training.compiled import run_episode


@pytest.fixture(scope="module")
def episode():
    env = PipelineFollowingEnv("paper-left", episode_seconds=6)
    recorder = Recorder(env)
    stats = run_episode(recorder, Heuristic(), seed=0)
    return env, recorder.frames, stats


def test_the_recorder_keeps_the_episode_it_wraps(episode):
    env, frames, stats = episode
    plain = run_episode(PipelineFollowingEnv("paper-left", episode_seconds=6), Heuristic(), seed=0)
    assert stats.ret == plain.ret
    assert len(frames) == 7  # the start and six decisions
    assert frames[0].reward is None and frames[-1].total == pytest.approx(plain.ret)
    np.testing.assert_array_equal([f.state[8:10] for f in frames], plain.poses[:, :2])


@pytest.mark.slow  # ≈ 6 s; a GIF is also written in test_cli.py::test_evaluate_animates_the_first_episode
def test_a_gif_has_one_frame_per_decision_and_shows_the_motion(episode, tmp_path):
    env, frames, _ = episode
    path = write_animation(env.pipeline, frames, tmp_path / "ep.gif", fps=4, hold_seconds=1.0)
    assert path.read_bytes()[:6] in (b"GIF87a", b"GIF89a")
    with Image.open(path) as im:
        assert im.size == (500, 500)
        assert im.n_frames >= len(frames)  # Pillow merges only identical neighbours (the hold)
        im.seek(0)
        first = np.asarray(im.convert("RGB"), dtype=float)
        assert im.info["duration"] == 250  # 4 frames per second
        im.seek(len(frames) - 1)
        last = np.asarray(im.convert("RGB"), dtype=float)
        assert im.info["duration"] == 250 * 5  # the last frame is held for another second
    assert np.abs(first - last).mean() > 0.5
    assert [p.name for p in tmp_path.iterdir()] == ["ep.gif"]  # no temporary file left


def test_mp4_without_ffmpeg_is_refused_before_any_work(monkeypatch, tmp_path):
    from matplotlib import animation as mpl_animation

    monkeypatch.setattr(mpl_animation.writers, "is_available", lambda name: False)
    with pytest.raises(OutputError, match=r"--animate '.*ep.mp4': .mp4 needs ffmpeg on the PATH"):
        check_animation_path(tmp_path / "ep.mp4")


def test_other_suffixes_are_refused(tmp_path):
    with pytest.raises(OutputError, match=r"'.avi' is not a known file type; use one of .gif, .mp4"):
        check_animation_path(tmp_path / "ep.avi")


def test_a_failed_write_leaves_nothing(episode, tmp_path, monkeypatch):
    from matplotlib import animation as mpl_animation

    env, frames, _ = episode
    calls = []

    def failing(self, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt

    monkeypatch.setattr(mpl_animation.PillowWriter, "grab_frame", failing)
    with pytest.raises(KeyboardInterrupt):
        write_animation(env.pipeline, frames, tmp_path / "ep.gif")
    assert list(tmp_path.iterdir()) == []


def test_suffixes_known():
    assert animation.ANIMATION_SUFFIXES == ("gif", "mp4")


@pytest.mark.slow  # renders and detects every frame of an animation (≈ 20 s)
def test_with_the_vision_camera_each_frame_shows_the_camera_panel_beside_the_view(tmp_path):
    pytest.importorskip("cv2")
    env = PipelineFollowingEnv("paper-left", episode_seconds=3, camera="vision")
    recorder = Recorder(env)
    run_episode(recorder, Heuristic(), seed=0)
    frames = recorder.frames
    assert all(f.camera.shape == (animation.PANEL_HEIGHT, 64 * 5, 3) for f in frames)  # 5 px a pixel
    # the last frame's panel is the camera's image at the end of the episode, scaled 5×
    grey = np.repeat(np.repeat(env._vision.image, 5, axis=0), 5, axis=1)
    plain = (frames[-1].camera == grey[..., None]).all(axis=-1)
    assert plain.mean() > 0.95  # all but the drawn detection and truth lines
    path = write_animation(env.pipeline, frames, tmp_path / "ep.gif", fps=4, hold_seconds=0.0)
    with Image.open(path) as im:
        assert im.size == (500 + 320, 500)  # the 500-px Fig. 2 view, then the panel
        im.seek(len(frames) - 1)
        right = np.asarray(im.convert("RGB"), dtype=float)[:480, 500:]
    # the GIF's palette keeps the panel's picture: close to the image's grey levels on average
    assert np.abs(right.mean(axis=-1)[plain] - grey[plain]).mean() < 6.0
    # without the vision camera no panel is kept and the view is alone (the test above: 500 × 500)
    assert Recorder(PipelineFollowingEnv("paper-left", episode_seconds=3))._panel() is None
