"""The registered ids in the RL clients' own standard patterns, unchanged (extra 'deep').

TorchRL's PPO tutorial (evaluation rollouts inside a collector's loop, on the same environment), the image id
through Gymnasium's image wrappers, Stable-Baselines3's ``CnnPolicy`` and TorchRL's
``ToTensorImage``, Stable-Baselines3's ``SubprocVecEnv`` from a fresh interpreter, and CleanRL's
``make_env`` of its ``gym-v1.1`` branch as it stands.
"""

from __future__ import annotations

import json
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest

import pipefollow.envs  # noqa: F401 (registers the ids)
from pipefollow.envs.env import PipelineFollowingEnv

pytestmark = pytest.mark.deep

ID = "pipefollow/PipelineFollowing-v0"
IMAGE_ID = "pipefollow/PipelineFollowingImage-v0"
RANDOM_ID = "pipefollow/PipelineFollowingRandom-v0"


def _torch():
    torch = pytest.importorskip("torch")
    torch.set_num_threads(1)
    return torch


def _collector_class():
    pytest.importorskip("torchrl")
    with warnings.catch_warnings():  # torchrl 0.14 warns about its own deprecated classes on import
        warnings.simplefilter("ignore", DeprecationWarning)
        from torchrl.collectors import Collector  # SyncDataCollector's name since torchrl 0.14
    return Collector


def replay(actions, **kwargs):
    """The observations a direct environment gives for ``actions`` from its (seedless) reset."""
    env = PipelineFollowingEnv(**kwargs)
    obs = [env.reset()[0]]
    for a in actions:
        obs.append(env.step(a)[0])
    return np.array(obs)


# ---------------------------------------------------------------- TorchRL


def _tutorial_env_and_policy(torch, **kwargs):
    """The PPO tutorial's environment (a ``StepCounter`` on ``GymEnv``) and a deterministic policy."""
    from tensordict.nn import TensorDictModule
    from torchrl.envs import GymEnv, StepCounter, TransformedEnv

    env = TransformedEnv(GymEnv(ID, obs_dtype="float32", **kwargs), StepCounter())
    torch.manual_seed(0)
    net = torch.nn.Sequential(torch.nn.Linear(4, 1), torch.nn.Tanh())
    return env, TensorDictModule(net, in_keys=["observation"], out_keys=["action"])


def test_torchrls_ppo_tutorial_pattern_a_collector_and_evaluation_rollouts_on_the_same_env():
    torch = _torch()
    Collector = _collector_class()
    env, policy = _tutorial_env_and_policy(torch)
    collector = Collector(
        env, policy, frames_per_batch=25, total_frames=75, split_trajs=False, device="cpu",
        auto_register_policy_transforms=False,
    )  # fmt: skip
    batches, evaluations = [], []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for data in collector:  # the tutorial's loop: after each batch, an evaluation rollout
            batches.append(data.clone())
            with torch.no_grad():
                evaluations.append(env.rollout(1000, policy))
    collector.shutdown()
    # each evaluation ran the id's whole 20-step episode on the collector's environment ...
    want = replay(evaluations[0]["action"].numpy(), obs_dtype="float32")
    for rollout in evaluations:
        assert rollout.batch_size == (20,) and rollout["next", "truncated"][-1].item()
        np.testing.assert_array_equal(rollout["observation"].numpy(), want[:-1])
        np.testing.assert_array_equal(rollout["next", "observation"].numpy(), want[1:])
    # ... so the collector's next step came after that episode's end: the environment warned and
    # carried on, truncated, and the collector reset it (ResetNeeded stopped the tutorial before)
    past_end = [w for w in caught if "after the episode's end" in str(w.message)]
    assert len(past_end) == 2 and all(w.category is UserWarning for w in past_end)
    ends = [b["next", "truncated"].reshape(-1).nonzero().reshape(-1).tolist() for b in batches]
    assert ends == [[19], [0, 20], [0, 20]]
    np.testing.assert_array_equal(batches[0]["observation"][:20].numpy(), want[:-1])


def test_torchrls_tutorial_pattern_stops_at_the_end_with_strict_reset():
    torch = _torch()
    Collector = _collector_class()
    from gymnasium.error import ResetNeeded

    env, policy = _tutorial_env_and_policy(torch, strict_reset=True)
    collector = Collector(
        env, policy, frames_per_batch=25, total_frames=75, split_trajs=False, device="cpu",
        auto_register_policy_transforms=False,
    )  # fmt: skip
    with pytest.raises(ResetNeeded, match="the episode has ended"):
        for _ in collector:
            with torch.no_grad():
                env.rollout(1000, policy)
    collector.shutdown()


def test_torchrl_takes_the_image_id_and_its_to_tensor_image_makes_it_channel_first():
    torch = _torch()
    pytest.importorskip("torchrl")
    from gymnasium.vector import AutoresetMode
    from torchrl.envs import GymEnv, GymWrapper, ToTensorImage, TransformedEnv
    from torchrl.envs.utils import check_env_specs

    raw = GymEnv(IMAGE_ID, episode_seconds=3)
    check_env_specs(raw)
    assert raw.observation_spec["observation"].shape == (96, 64, 1)
    to_tensor = ToTensorImage(in_keys=["observation"])
    td = raw.reset()
    image = td["observation"].numpy()
    moved = to_tensor(td.clone())["observation"]  # channel first, scaled to [0, 1]
    assert moved.shape == (1, 96, 64) and moved.dtype == torch.float32
    np.testing.assert_allclose(moved[0].numpy(), image[..., 0] / np.float32(255.0), rtol=1e-6)
    env = TransformedEnv(raw, to_tensor)
    assert env.rollout(3)["observation"].shape == (3, 1, 96, 64)
    disabled = AutoresetMode.DISABLED
    vec = GymWrapper(gym.make_vec(IMAGE_ID, num_envs=2, episode_seconds=3, autoreset_mode=disabled))
    check_env_specs(vec)
    assert vec.rollout(4, break_when_any_done=False)["observation"].shape == (2, 4, 96, 64, 1)


# ---------------------------------------------------------------- Gymnasium's image wrappers


def test_gymnasiums_image_wrappers_on_the_image_id():
    pytest.importorskip("cv2")  # ResizeObservation resizes with OpenCV
    from gymnasium.wrappers import FrameStackObservation, GrayscaleObservation, ResizeObservation

    env = gym.make(IMAGE_ID)
    assert env.observation_space == gym.spaces.Box(0, 255, (96, 64, 1), np.uint8)
    # the image is grey already: Gymnasium's GrayscaleObservation, for RGB images, says so
    with pytest.raises(ValueError, match="requires an image with 3 channels, got shape"):
        GrayscaleObservation(env)
    stacked = FrameStackObservation(ResizeObservation(env, (84, 84)), 4)
    assert stacked.observation_space.shape == (4, 84, 84, 1)
    obs, _ = stacked.reset(seed=0)
    frames = [obs]
    for _ in range(3):
        frames.append(stacked.step([0.2])[0])
    assert all(f in stacked.observation_space for f in frames)
    # the stack is the last four images, oldest first, each the environment's own image resized
    import cv2

    direct = PipelineFollowingEnv(observation="image")
    images = [direct.reset(seed=0)[0]] + [direct.step([0.2])[0] for _ in range(3)]
    want = [cv2.resize(im, (84, 84), interpolation=cv2.INTER_AREA)[..., None] for im in images]
    np.testing.assert_array_equal(frames[-1], np.stack(want))
    for k in range(4):  # before the fourth image the stack is padded with the first (padding "reset")
        np.testing.assert_array_equal(frames[0][k], want[0])


# ---------------------------------------------------------------- Stable-Baselines3


def test_stable_baselines3_cnn_policy_on_the_image_id_and_on_the_batched_image_env():
    _torch()
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecMonitor, VecTransposeImage

    from pipefollow.envs.vector_env import PipelineFollowingVectorEnv
    from pipefollow.training.deep import SB3VecEnv, hyperparameters, make_model

    venv = make_vec_env(IMAGE_ID, n_envs=2, seed=0, env_kwargs={"episode_seconds": 4})
    model = PPO("CnnPolicy", venv, n_steps=8, batch_size=16, n_epochs=1, device="cpu", seed=0)
    assert isinstance(model.get_env(), VecTransposeImage)  # SB3 moved the channel first itself
    assert model.observation_space.shape == (1, 96, 64)
    model.learn(16)
    obs = PipelineFollowingEnv(observation="image").reset(seed=0)[0]
    action, _ = model.predict(obs, deterministic=True)  # the environment's own (H, W, 1) image
    assert action.shape == (1,)
    # the project's path (examples/ppo_pixels.py): the batched environment through SB3VecEnv
    batched = PipelineFollowingVectorEnv(2, "random:mixed", episode_seconds=4, observation="image")
    hp = hyperparameters("ppo", n_envs=2, n_steps=8, batch_size=16, n_epochs=1)
    model = make_model("ppo", VecMonitor(SB3VecEnv(batched)), hp, seed=0, policy="CnnPolicy")
    model.learn(32)
    assert model.observation_space.shape == (1, 96, 64) and len(model.ep_info_buffer) == 8  # 2 × 16 steps
    assert {e["l"] for e in model.ep_info_buffer} == {4}


SUBPROC = """
import json
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import SubprocVecEnv

venv = make_vec_env("pipefollow.envs:ENV", n_envs=2, seed=5, vec_env_cls=SubprocVecEnv)
obs = venv.reset()
steps = 0
while True:
    obs, rewards, dones, infos = venv.step([[0.3], [-0.3]])
    steps += 1
    if dones.any():
        break
last = [i["terminal_observation"].tolist() for i in infos]
summary = [float(i["episode_pipe_in_view"]) for i in infos]
print(json.dumps({"steps": steps, "dones": dones.tolist(), "last": last, "summary": summary}))
venv.close()
"""


@pytest.mark.parametrize("env_id", [ID, "pipefollow/PipelineFollowingValidation-v0"])
def test_stable_baselines3_subproc_vec_env_from_a_fresh_interpreter(env_id, tmp_path):
    # the worker processes import nothing by themselves: the id's module prefix registers the ids
    pytest.importorskip("stable_baselines3")
    code = SUBPROC.replace("ENV", env_id)
    run = [sys.executable, "-c", code]
    res = subprocess.run(run, capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    out = json.loads(res.stdout.strip().splitlines()[-1])
    steps = gym.spec(env_id).max_episode_steps
    assert out["steps"] == steps and out["dones"] == [True, True]
    for i, a in enumerate((0.3, -0.3)):
        env = gym.make(env_id)
        env.reset(seed=5 + i)
        for _ in range(steps):
            last, *_, info = env.step([a])
        np.testing.assert_array_equal(out["last"][i], last)
        assert out["summary"][i] == float(info["episode_pipe_in_view"])


# ---------------------------------------------------------------- CleanRL


def cleanrl_make_env(env_id, idx, capture_video, run_name, gamma):
    """CleanRL's ``make_env`` of ``cleanrl/ppo_continuous_action.py``, branch gym-v1.1 (d32feb3), verbatim."""

    def thunk():
        if capture_video and idx == 0:
            env = gym.make(env_id, render_mode="rgb_array")
            env = gym.wrappers.RecordVideo(env, f"videos/{run_name}")
        else:
            env = gym.make(env_id)
        env = gym.wrappers.FlattenObservation(env)  # deal with dm_control's Dict observation space
        env = gym.wrappers.RecordEpisodeStatistics(env)
        env = gym.wrappers.ClipAction(env)
        env = gym.wrappers.NormalizeObservation(env)
        env = gym.wrappers.TransformObservation(env, lambda obs: np.clip(obs, -10, 10), env.observation_space)
        env = gym.wrappers.NormalizeReward(env, gamma=gamma)
        env = gym.wrappers.TransformReward(env, lambda reward: np.clip(reward, -10, 10))
        return env

    return thunk


class SameModelSyncVectorEnv(gym.vector.SyncVectorEnv):
    """CleanRL's ``cleanrl_utils/same_model_vector_env.py`` (gym-v1.1, d32feb3): same-step autoreset."""

    def step(self, actions):
        from copy import deepcopy

        observations, infos = [], {}
        for i, action in enumerate(gym.vector.utils.iterate(self.action_space, actions)):
            (_env_obs, self._rewards[i], self._terminations[i], self._truncations[i], env_info) = self.envs[
                i
            ].step(action)
            if self._terminations[i] or self._truncations[i]:
                infos = self._add_info(infos, {"final_obs": _env_obs, "final_info": env_info}, i)
                _env_obs, env_info = self.envs[i].reset()
            observations.append(_env_obs)
            infos = self._add_info(infos, env_info, i)
        self._observations = gym.vector.utils.concatenate(
            self.single_observation_space, observations, self._observations
        )
        return (
            deepcopy(self._observations) if self.copy else self._observations,
            np.copy(self._rewards),
            np.copy(self._terminations),
            np.copy(self._truncations),
            infos,
        )


@pytest.mark.parametrize("env_id", [RANDOM_ID, IMAGE_ID])
def test_cleanrls_own_make_env_takes_the_id_as_its_env_id(env_id):
    full = f"pipefollow.envs:{env_id}"  # CleanRL's --env-id
    envs = SameModelSyncVectorEnv([cleanrl_make_env(full, i, False, "test", 0.99) for i in range(2)])
    steps = gym.spec(env_id).max_episode_steps
    envs.reset(seed=1)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, size=(steps, 2, 1)).astype(np.float32)
    for t in range(steps):
        _, _, term, trunc, infos = envs.step(actions[t])
        assert ("final_info" in infos) == (t == steps - 1)  # CleanRL's loop reads the episodes here
    assert trunc.all() and not term.any()
    episode = infos["final_info"]["episode"]
    for i in range(2):
        env = gym.make(env_id)
        env.reset(seed=1 + i)
        ret = sum(env.step(actions[t, i])[1] for t in range(steps))
        assert int(episode["l"][i]) == steps and float(episode["r"][i]) == pytest.approx(ret, abs=1e-9)
    assert infos["final_info"]["episode_progress_m"].shape == (2,)
