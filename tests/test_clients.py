"""RL clients no one here wrote, on both environments: TorchRL, CleanRL's wrappers and PPO loop,
Stable-Baselines3, and the code for them in the guide docs/guides/deep-rl.md (extra 'deep' and torchrl)."""

import math
import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import pipefollow
from pipefollow.envs.env import PipelineFollowingEnv

pytestmark = pytest.mark.deep

ID = pipefollow.ENV_ID
README = Path(__file__).resolve().parents[1] / "docs" / "guides" / "deep-rl.md"
SECTION = "## Using pipefollow with Stable-Baselines3, TorchRL and CleanRL"


def _torch():
    torch = pytest.importorskip("torch")
    torch.set_num_threads(1)
    return torch


def readme_blocks() -> list[str]:
    """The python code blocks of the guide's section on RL clients, up to the next section or the end."""
    text = README.read_text(encoding="utf-8")
    start = text.index(SECTION)
    end = text.find("\n## ", start + len(SECTION))
    end = len(text) if end < 0 else end
    return re.findall(r"```python\n(.*?)```", text[start:end], flags=re.S)


def readme_namespace(word: str) -> dict:
    """Run the README block that mentions ``word``; its names."""
    (block,) = [b for b in readme_blocks() if word in b]
    ns: dict = {"__name__": "readme"}
    exec(compile(block, f"docs/guides/deep-rl.md ({word})", "exec"), ns)
    return ns


# ---------------------------------------------------------------- TorchRL


def heuristic_like(torch):
    """A deterministic policy in torch whose numbers numpy reproduces exactly (one product, clipped)."""
    from tensordict.nn import TensorDictModule

    def act(obs):
        return (0.8 * obs[..., :1]).clamp(-1.0, 1.0).to(torch.float32)

    return TensorDictModule(act, in_keys=["observation"], out_keys=["action"])


def reference_rollout(pipelines, steps, seconds):
    """The same policy on single environments, reset when an episode ends: the expected rollout."""
    out = []
    for pipe in pipelines:
        env = PipelineFollowingEnv(pipe, episode_seconds=seconds)
        obs, _ = env.reset(seed=0)
        rows = []
        for _ in range(steps):
            a = np.clip(0.8 * obs[:1], -1.0, 1.0).astype(np.float32)
            nxt, r, _, trunc, _ = env.step(a)
            rows.append((obs, a, r, nxt, trunc))
            obs = env.reset()[0] if trunc else nxt
        out.append(rows)
    return out


def assert_rollout_equals(td, expected):
    for i, rows in enumerate(expected):
        for t, (obs, a, r, nxt, trunc) in enumerate(rows):
            np.testing.assert_allclose(td["observation"][i, t].numpy(), obs, rtol=0, atol=1e-12)
            np.testing.assert_array_equal(td["action"][i, t].numpy(), a)
            assert td["next", "reward"][i, t].item() == np.float32(r)  # TorchRL's rewards are float32
            np.testing.assert_allclose(td["next", "observation"][i, t].numpy(), nxt, rtol=0, atol=1e-12)
            assert bool(td["next", "truncated"][i, t]) == trunc


PIPES = ["paper-left", "paper-right", [[0, 0], [4, 0], [4, -4], [8, -4]]]


def test_torchrl_gym_env_on_the_single_environment_checks_and_rolls_out_its_numbers():
    torch = _torch()
    pytest.importorskip("torchrl")
    from torchrl.envs import GymEnv
    from torchrl.envs.utils import check_env_specs

    for dtype in ("float64", "float32"):
        env = GymEnv(ID, pipeline="paper-right", episode_seconds=5, obs_dtype=dtype)
        check_env_specs(env)
        assert env.observation_spec["observation"].dtype == getattr(torch, dtype)
    env = GymEnv(ID, pipeline="paper-right", episode_seconds=5)
    env.auto_register_info_dict()  # the infos as entries of the rollout
    check_env_specs(env)
    td = env.rollout(12, heuristic_like(torch), break_when_any_done=False)
    assert_rollout_equals(td.unsqueeze(0), reference_rollout(["paper-right"], 12, 5))
    assert td["next", "current"].shape == (12, 2) and td["next", "pipe_in_view"].dtype == torch.bool


@pytest.mark.parametrize("mode", [AutoresetMode.SAME_STEP, AutoresetMode.DISABLED])
def test_torchrl_gym_wrapper_on_the_vector_environment_checks_and_rolls_out_its_numbers(mode):
    torch = _torch()
    pytest.importorskip("torchrl")
    from torchrl.envs import GymWrapper
    from torchrl.envs.utils import check_env_specs

    env = GymWrapper(gym.make_vec(ID, num_envs=3, pipeline=PIPES, episode_seconds=5, autoreset_mode=mode))
    check_env_specs(env)
    td = env.rollout(12, heuristic_like(torch), break_when_any_done=False)
    assert td.batch_size == (3, 12)
    assert_rollout_equals(td, reference_rollout(PIPES, 12, 5))  # across two resets per AUV


def test_torchrl_refuses_next_step_autoreset_as_it_documents():
    pytest.importorskip("torchrl")
    from torchrl.envs import GymWrapper

    with pytest.raises(RuntimeError, match="must be one of SAME_STEP or DISABLED"):
        GymWrapper(gym.make_vec(ID, num_envs=2))


@pytest.mark.slow
def test_torchrl_gym_env_with_num_envs_batches_the_single_environments_infos():
    torch = _torch()
    pytest.importorskip("torchrl")
    from torchrl.envs import GymEnv
    from torchrl.envs.utils import check_env_specs

    # Gymnasium's AsyncVectorEnv: its worker processes import pipefollow through the id's module prefix
    env = GymEnv(f"pipefollow:{ID}", num_envs=2, pipeline="random:easy", episode_seconds=5)
    try:
        check_env_specs(env)
        td = env.rollout(8, break_when_any_done=False)
        assert td.batch_size == (2, 8) and td["next", "current"].shape == (2, 8, 2)
        assert td["next", "truncated"][:, 4].all() and not td["next", "truncated"][:, 5].any()
        assert td["next", "pose"].dtype == torch.float64
    finally:
        env.close()


# ---------------------------------------------------------------- CleanRL


def cleanrl_ppo(envs, read_episodes, *, seed=0, num_steps=64, iterations=3, gamma=0.8):
    """CleanRL's ``ppo_continuous_action.py`` loop, shortened: rollouts, GAE, clipped PPO updates.

    Returns the actions sent to ``envs`` (steps, n, 1), the episodes ``read_episodes(infos)``
    found as (env index, return, length), and the last losses.
    """
    torch = _torch()
    from torch import nn
    from torch.distributions.normal import Normal

    torch.manual_seed(seed)
    n = envs.num_envs
    obs_dim = int(np.prod(envs.single_observation_space.shape))
    act_dim = int(np.prod(envs.single_action_space.shape))

    def mlp(out, std):
        layers = [nn.Linear(obs_dim, 64), nn.Tanh(), nn.Linear(64, 64), nn.Tanh(), nn.Linear(64, out)]
        for layer, gain in zip(layers[::2], (math.sqrt(2), math.sqrt(2), std), strict=True):
            nn.init.orthogonal_(layer.weight, gain)
            nn.init.constant_(layer.bias, 0.0)
        return nn.Sequential(*layers)

    critic, actor_mean = mlp(1, 1.0), mlp(act_dim, 0.01)
    actor_logstd = nn.Parameter(torch.zeros(1, act_dim))
    params = [*critic.parameters(), *actor_mean.parameters(), actor_logstd]
    optimizer = torch.optim.Adam(params, lr=3e-4, eps=1e-5)

    def policy(x, action=None):
        mean = actor_mean(x)
        dist = Normal(mean, torch.exp(actor_logstd.expand_as(mean)))
        if action is None:
            action = dist.sample()
        return action, dist.log_prob(action).sum(1), dist.entropy().sum(1), critic(x).flatten()

    obs_buf = torch.zeros((num_steps, n, obs_dim))
    act_buf = torch.zeros((num_steps, n, act_dim))
    logp_buf, rew_buf, done_buf, val_buf = (torch.zeros((num_steps, n)) for _ in range(4))
    sent, episodes = [], []
    next_obs, _ = envs.reset(seed=seed)
    next_obs, next_done = torch.Tensor(next_obs), torch.zeros(n)
    for _ in range(iterations):
        for step in range(num_steps):
            obs_buf[step], done_buf[step] = next_obs, next_done
            with torch.no_grad():
                action, logp, _, value = policy(next_obs)
            act_buf[step], logp_buf[step], val_buf[step] = action, logp, value
            sent.append(action.numpy().copy())
            next_obs, reward, term, trunc, infos = envs.step(action.numpy())
            rew_buf[step] = torch.tensor(reward).view(-1)
            next_obs, next_done = torch.Tensor(next_obs), torch.Tensor(np.logical_or(term, trunc))
            episodes += read_episodes(infos)
        with torch.no_grad():  # GAE(λ = 0.95)
            next_value = critic(next_obs).flatten()
            adv = torch.zeros_like(rew_buf)
            last = 0.0
            for t in reversed(range(num_steps)):
                nonterminal = 1.0 - (next_done if t == num_steps - 1 else done_buf[t + 1])
                nxt = next_value if t == num_steps - 1 else val_buf[t + 1]
                delta = rew_buf[t] + gamma * nxt * nonterminal - val_buf[t]
                adv[t] = last = delta + gamma * 0.95 * nonterminal * last
            returns = adv + val_buf
        b = dict(
            obs=obs_buf.reshape(-1, obs_dim), act=act_buf.reshape(-1, act_dim), logp=logp_buf.reshape(-1),
            adv=adv.reshape(-1), ret=returns.reshape(-1),
        )  # fmt: skip
        for _ in range(2):
            for idx in np.array_split(np.random.default_rng(seed).permutation(num_steps * n), 4):
                _, logp, entropy, value = policy(b["obs"][idx], b["act"][idx])
                ratio = (logp - b["logp"][idx]).exp()
                a = b["adv"][idx]
                a = (a - a.mean()) / (a.std() + 1e-8)
                pg_loss = torch.max(-a * ratio, -a * ratio.clamp(0.8, 1.2)).mean()
                v_loss = 0.5 * ((value - b["ret"][idx]) ** 2).mean()
                loss = pg_loss - 0.0 * entropy.mean() + 0.5 * v_loss
                optimizer.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(params, 0.5)
                optimizer.step()
    return np.array(sent), episodes, (pg_loss.detach().item(), v_loss.detach().item())


def replayed_returns(actions, seed, next_step=False, **kwargs):
    """The raw returns of the episodes the actions make on single environments (seeds seed + i).

    With ``next_step`` the action after an episode's end resets instead (next-step autoreset).
    """
    out = []
    for i in range(actions.shape[1]):
        env = PipelineFollowingEnv(**kwargs)
        env.reset(seed=seed + i)
        total, length, pending = 0.0, 0, False
        for a in actions[:, i]:
            if pending:
                env.reset()
                pending = False
                continue
            _, r, _, trunc, _ = env.step(a)
            total, length = total + r, length + 1
            if trunc:
                out.append((i, total, length))
                total, length = 0.0, 0
                if next_step:
                    pending = True
                else:
                    env.reset()
    return sorted(out)


def test_cleanrl_make_env_from_the_readme_with_its_ppo_loop_reads_every_episode():
    make_env = readme_namespace("def make_env")["make_env"]
    envs = gym.vector.SyncVectorEnv(
        [make_env(f"pipefollow:{ID}", i, False, "test", 0.8) for i in range(2)],
        autoreset_mode=AutoresetMode.SAME_STEP,
    )

    def read(infos):  # CleanRL's own lines
        if "final_info" not in infos:
            return []
        over = np.nonzero(infos["final_info"]["_episode"])[0]
        ep = infos["final_info"]["episode"]
        return [(int(i), float(ep["r"][i]), int(ep["l"][i])) for i in over]

    actions, episodes, losses = cleanrl_ppo(envs, read, seed=3)
    assert len(actions) == 192 and len(episodes) == 2 * 9  # 192 decisions per AUV, 20 per episode
    assert all(np.isfinite(losses))
    got = sorted(episodes)
    want = replayed_returns(np.clip(actions, -1, 1), 3, pipeline="random:mixed")
    assert [(i, n) for i, _, n in got] == [(i, n) for i, _, n in want]
    np.testing.assert_allclose([r for _, r, _ in got], [r for _, r, _ in want], rtol=0, atol=1e-9)


def test_cleanrl_wrapper_chain_on_the_vector_environment_reads_every_episode():
    from gymnasium.wrappers import vector as vw

    # Gymnasium's vector observation wrappers take next-step (the default) or disabled autoreset
    envs = gym.make_vec(ID, num_envs=3, pipeline="random:mixed", obs_dtype="float32")
    envs = vw.RecordEpisodeStatistics(envs)
    envs = vw.ClipAction(envs)
    envs = vw.NormalizeObservation(envs)
    envs = vw.TransformObservation(envs, lambda obs: np.clip(obs, -10, 10))
    envs = vw.NormalizeReward(envs, gamma=0.8)
    envs = vw.TransformReward(envs, lambda reward: np.clip(reward, -10, 10))

    def read(infos):  # the statistics of the wrapper around the vector environment
        if "episode" not in infos:
            return []
        ep = infos["episode"]
        return [(int(i), float(ep["r"][i]), int(ep["l"][i])) for i in np.nonzero(infos["_episode"])[0]]

    actions, episodes, _ = cleanrl_ppo(envs, read, seed=5, num_steps=40, iterations=3)
    assert len(episodes) == 3 * 5  # 120 steps per AUV, 21 per episode with its autoreset step
    got = sorted(episodes)
    want = replayed_returns(
        np.clip(actions, -1, 1), 5, next_step=True, pipeline="random:mixed", obs_dtype="float32"
    )
    assert [(i, n) for i, _, n in got] == [(i, n) for i, _, n in want]
    np.testing.assert_allclose([r for _, r, _ in got], [r for _, r, _ in want], rtol=0, atol=1e-9)


# ---------------------------------------------------------------- Stable-Baselines3 and the README


def test_stable_baselines3_checks_the_single_environment():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.env_checker import check_env

    check_env(PipelineFollowingEnv(start_lateral_noise=0.3), warn=True)
    check_env(PipelineFollowingEnv("random:mixed", obs_dtype="float32"), warn=True)


def test_the_readmes_stable_baselines3_lines_train():
    pytest.importorskip("stable_baselines3")
    _torch()
    ns = readme_namespace("stable_baselines3")
    model = ns["model"]
    assert model.num_timesteps == 1024
    episodes = list(model.ep_info_buffer)  # SB3's Monitor: 20 decisions per episode
    assert len(episodes) == 4 * 12 and {e["l"] for e in episodes} == {20}
    assert all(-200.0 <= e["r"] <= 10.0 for e in episodes)  # 20 decisions of −10 … +0.5


def test_the_readmes_stable_baselines3_lines_run_in_a_fresh_interpreter(tmp_path):
    # in a fresh process nothing else has imported Gymnasium: the block's own imports must register
    pytest.importorskip("stable_baselines3")
    import subprocess
    import sys

    (block,) = [b for b in readme_blocks() if "stable_baselines3" in b]
    short = block.replace("total_timesteps=1024", "total_timesteps=128")
    code = "import torch\ntorch.set_num_threads(1)\n" + short
    run = [sys.executable, "-c", code]
    res = subprocess.run(run, capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]


def test_the_readmes_torchrl_lines_roll_out():
    torch = _torch()
    pytest.importorskip("torchrl")
    ns = readme_namespace("torchrl")
    rollout = ns["rollout"]
    assert rollout.batch_size == (8, 50)
    assert rollout["observation"].dtype == torch.float32
    assert rollout["next", "truncated"].sum() == 8 * 2  # two 20-s episodes per AUV
    reset = ns["env"].reset()
    assert reset["observation"].dtype == torch.float32 and reset["observation"].shape == (4,)
