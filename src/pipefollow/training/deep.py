"""Deep-RL baselines: PPO and SAC from Stable-Baselines3, trained on the batched vector environment.

Needs the optional extra ``deep`` (``pip install torch`` first, then ``pip install
'pipefollow[deep]'``); importing this module without it raises :class:`DeepExtraMissing`. After
training, the actor network is exported to a policy file of kind ``mlp``
(:class:`~pipefollow.learners.mlp.MLPPolicy`), which loads and runs without torch.

Default hyper-parameters (:data:`DEFAULTS`, docs/decisions.md): Stable-Baselines3's own defaults,
except a 64×64 network for both learners (SAC's default is 256×256), a rollout of 8 × 128 steps
for PPO, 1,000 random steps before SAC learns (a tenth of the paper's budget of 10,000 decisions),
and the discount: γ = 0.8 for PPO (the paper's γ_d; on 100 training-family pipes it beat 0.9, 0.95
and 0.99 in each of 3 seeds, by 0.1–2.1 in mean return), γ = 0.95 for SAC (above 0.8 by 1.1 in the
one seed measured). Rewards are dense (eq. 19) and a lost pipe costs −10 within a decision or two
of the action that lost it, so a horizon of 5–20 decisions suffices.

Determinism: with the same seed, a run draws the same numbers (``set_random_seed``, the vector
environment's per-sub-environment seeds and a single torch thread); torch on the CPU is
deterministic for these small dense networks in practice, but torch does not promise
bit-identical results across versions or machines.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pipefollow.learners.mlp import MLPPolicy

EXTRA_HINT = "PPO and SAC need the optional extra 'deep': pip install torch && pip install 'pipefollow[deep]'"


class DeepExtraMissing(ImportError):
    """Stable-Baselines3 or torch is not installed."""


try:
    import torch
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.utils import set_random_seed
    from stable_baselines3.common.vec_env import VecEnv, VecMonitor
except ImportError as e:  # pragma: no cover - exercised without the extra
    raise DeepExtraMissing(f"{EXTRA_HINT} ({e})") from e

from pipefollow.envs.shell import SUMMARY_KEYS  # noqa: E402
from pipefollow.envs.vector_env import PipelineFollowingVectorEnv  # noqa: E402  (after the extra's check)

ALGORITHMS = ("ppo", "sac")
DEFAULTS: dict[str, dict[str, Any]] = {
    "ppo": {
        "n_envs": 8,
        "n_steps": 128,
        "batch_size": 256,
        "n_epochs": 10,
        "learning_rate": 3e-4,
        "gamma": 0.8,
        "gae_lambda": 0.95,
        "clip_range": 0.2,
        "ent_coef": 0.0,
        "net_arch": [64, 64],
        "activation": "tanh",
    },
    "sac": {
        "n_envs": 1,
        "learning_rate": 3e-4,
        "buffer_size": 100_000,
        "batch_size": 256,
        "learning_starts": 1_000,
        "tau": 0.005,
        "gamma": 0.95,
        "train_freq": 1,
        "gradient_steps": 1,
        "net_arch": [64, 64],
        "activation": "relu",
    },
}
_ACTIVATIONS = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}


class SB3VecEnv(VecEnv):
    """Stable-Baselines3's ``VecEnv`` interface over :class:`PipelineFollowingVectorEnv`.

    Stable-Baselines3 resets a finished sub-environment within the step and reports its last
    observation as ``info["terminal_observation"]``; the vector environment's
    :meth:`~PipelineFollowingVectorEnv.reset_done` does that reset with the draws of its
    next-step autoreset.
    """

    def __init__(self, venv: PipelineFollowingVectorEnv) -> None:
        self.venv = venv
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)
        self._actions = np.zeros((venv.num_envs, 1))

    def reset(self):  # noqa: D102
        seeds = self._seeds
        seed = None if all(s is None for s in seeds) else [s for s in seeds]
        obs, _ = self.venv.reset(seed=seed)
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:  # noqa: D102
        self._actions = actions

    def step_wait(self):  # noqa: D102
        obs, rewards, terminated, truncated, info = self.venv.step(self._actions)
        done = terminated | truncated
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        if done.any():
            idx = np.flatnonzero(done)
            first = self.venv.reset_done()
            for k, i in enumerate(idx):
                infos[i]["terminal_observation"] = obs[i].copy()
                infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
                for key in SUMMARY_KEYS:
                    if key in info:
                        infos[i][key] = float(info[key][i])
                obs[i] = first[k]
        return obs, rewards, done, infos

    def close(self) -> None:  # noqa: D102
        self.venv.close()

    def get_attr(self, attr_name, indices=None):  # noqa: D102
        return [getattr(self.venv, attr_name) for _ in self._get_indices(indices)]

    def set_attr(self, attr_name, value, indices=None):  # noqa: D102
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name, *method_args, indices=None, **method_kwargs):  # noqa: D102
        raise NotImplementedError("the batched environment has no per-sub-environment methods")

    def env_is_wrapped(self, wrapper_class, indices=None):  # noqa: D102
        return [False for _ in self._get_indices(indices)]


def hyperparameters(algorithm: str, **overrides) -> dict[str, Any]:
    """The defaults of ``algorithm`` (:data:`DEFAULTS`) with ``overrides`` (unknown keys raise)."""
    if algorithm not in DEFAULTS:
        raise ValueError(f"algorithm must be one of {', '.join(ALGORITHMS)}, got {algorithm!r}")
    hp = dict(DEFAULTS[algorithm])
    unknown = sorted(set(overrides) - set(hp))
    if unknown:
        raise ValueError(f"unknown {algorithm} hyper-parameter(s): {', '.join(unknown)}")
    hp.update(overrides)
    return hp


def make_model(
    algorithm: str, env, hp: dict[str, Any], seed: int, policy: str = "MlpPolicy", **policy_kwargs
):
    """A Stable-Baselines3 model of ``algorithm`` on ``env`` (an SB3 VecEnv) with hyper-parameters ``hp``.

    ``policy`` is SB3's policy name (``"CnnPolicy"`` for image observations); ``policy_kwargs``
    are added to the network the hyper-parameters give (e.g. a ``features_extractor_class``).
    """
    kwargs = {k: v for k, v in hp.items() if k not in ("n_envs", "net_arch", "activation")}
    policy_kwargs = {
        "net_arch": list(hp["net_arch"]),
        "activation_fn": _ACTIVATIONS[hp["activation"]],
        **policy_kwargs,
    }
    cls = PPO if algorithm == "ppo" else SAC
    return cls(policy, env, seed=seed, policy_kwargs=policy_kwargs, device="cpu", verbose=0, **kwargs)


def _dense_layers(modules) -> tuple[list[np.ndarray], list[np.ndarray], list[str]]:
    """Weights, biases and activations of a ``Sequential`` of ``Linear`` layers and activations."""
    weights, biases, acts = [], [], []
    for m in modules:
        if isinstance(m, torch.nn.Linear):
            weights.append(m.weight.detach().cpu().double().numpy().copy())
            biases.append(m.bias.detach().cpu().double().numpy().copy())
            acts.append("identity")
        elif isinstance(m, torch.nn.Tanh | torch.nn.ReLU) and acts and acts[-1] == "identity":
            acts[-1] = "tanh" if isinstance(m, torch.nn.Tanh) else "relu"
        elif not isinstance(m, torch.nn.Identity | torch.nn.Flatten):
            raise ValueError(f"cannot export a layer of type {type(m).__name__}")
    return weights, biases, acts


def export_policy(model, algorithm: str) -> MLPPolicy:
    """The deterministic actor of a trained PPO or SAC model as an :class:`MLPPolicy`.

    PPO acts with its Gaussian's mean, clipped to the action space; SAC with the tanh of its
    Gaussian's mean, rescaled to the action space (as ``model.predict(obs, deterministic=True)``).
    """
    space = model.action_space
    if algorithm == "ppo":
        policy = model.policy
        if policy.squash_output or getattr(policy, "use_sde", False):
            raise ValueError("only PPO with a plain Gaussian policy can be exported")
        hidden = _dense_layers(policy.mlp_extractor.policy_net)
        head = _dense_layers([policy.action_net])
        output = "clip"
    elif algorithm == "sac":
        actor = model.actor
        if actor.use_sde:
            raise ValueError("only SAC without gSDE can be exported")
        hidden = _dense_layers(actor.latent_pi)
        head = _dense_layers([actor.mu])
        output = "tanh"
    else:
        raise ValueError(f"algorithm must be one of {', '.join(ALGORITHMS)}, got {algorithm!r}")
    weights, biases, acts = (hidden[i] + head[i] for i in range(3))
    return MLPPolicy(
        weights,
        biases,
        acts,
        output=output,
        action_low=space.low,
        action_high=space.high,
        trained_by=algorithm,
    )


class _Progress(BaseCallback):
    """Reports the steps done and collects the returns of finished episodes (from ``VecMonitor``)."""

    def __init__(self, progress: Callable[[int], None] | None) -> None:
        super().__init__()
        self.progress = progress
        self.returns: list[float] = []
        self.lengths: list[int] = []

    def _on_step(self) -> bool:
        for info in self.locals.get("infos", ()):
            ep = info.get("episode")
            if ep is not None:
                self.returns.append(float(ep["r"]))
                self.lengths.append(int(ep["l"]))
        if self.progress is not None:
            self.progress(self.num_timesteps)
        return True


@dataclass(frozen=True)
class DeepRun:
    """A finished training: the exported policy, episode returns, steps and wall time."""

    policy: MLPPolicy
    model: Any
    returns: list[float]
    steps: int
    wall_s: float
    hyperparameters: dict[str, Any]


def train_deep(
    algorithm: str,
    pipeline="random:mixed",
    *,
    steps: int,
    seconds: float = 90.0,
    seed: int = 0,
    params=None,
    disturbance=None,
    progress: Callable[[int], None] | None = None,
    randomization=None,
    camera: dict[str, Any] | None = None,
    **overrides,
) -> DeepRun:
    """Train PPO or SAC for ``steps`` environment steps (decisions) and export its actor.

    Args:
        algorithm: ``ppo`` or ``sac``.
        pipeline: the training pipeline spec (name, file, ``random[:FAMILY]``).
        steps: budget in environment steps, summed over the sub-environments.
        seconds: episode length (s).
        seed: seeds torch, numpy and the sub-environments (``seed + i``).
        params: the simulated system (default: the paper's), as for the environment.
        disturbance: disturbances replacing ``params.disturbance``, as for the environment.
        randomization: domain randomization, as for the vector environment (each sub-environment
            draws its episode's disturbances at its reset).
        camera: the environment's camera arguments (``camera``, ``water``, ``sensor``): the learner
            observes through them; None for the ideal camera.
        progress: called with the number of steps done.
        **overrides: hyper-parameters replacing :data:`DEFAULTS`.
    """
    hp = hyperparameters(algorithm, **overrides)
    torch.set_num_threads(1)
    set_random_seed(seed)
    kwargs: dict[str, Any] = {"episode_seconds": seconds}
    if params is not None:
        kwargs["params"] = params
    if disturbance is not None:
        kwargs["disturbance"] = disturbance
    if randomization is not None:
        kwargs["randomization"] = randomization
    kwargs.update(camera or {})
    venv = VecMonitor(SB3VecEnv(PipelineFollowingVectorEnv(hp["n_envs"], pipeline, **kwargs)))
    model = make_model(algorithm, venv, hp, seed)
    callback = _Progress(progress)
    t0 = time.perf_counter()
    model.learn(total_timesteps=steps, callback=callback)
    wall = time.perf_counter() - t0
    return DeepRun(
        export_policy(model, algorithm), model, callback.returns, int(model.num_timesteps), wall, hp
    )


def write_hyperparameters(path: str | Path, algorithm: str, hp: dict[str, Any], **run: Any) -> Path:
    """The run's settings as JSON (atomically): algorithm, hyper-parameters and ``run`` entries."""
    from pipefollow.files.atomic import write_text_atomic

    path = Path(path)
    write_text_atomic(
        path, json.dumps({"algorithm": algorithm, "hyperparameters": hp, **run}, indent=2) + "\n"
    )
    return path


STEPS = 100_000  # the budget of a training run in environment steps (decisions)


def result_text(result: dict[str, Any]) -> str:
    """A :func:`train_to_folder` summary in three lines: steps and time, mean returns, the files."""
    r = result["returns"]
    k = min(10, len(r))
    first = np.mean(r[:k]) if k else float("nan")
    last = np.mean(r[-k:]) if k else float("nan")
    return (
        f"{result['algorithm'].upper()}: {result['steps']} steps in {result['wall_s']:.1f} s; "
        f"mean return of the first {k} episodes {first:.2f}, of the last {k} {last:.2f}\n"
        f"policy: {result['policy']}\nhyper-parameters: {result['hyperparameters']}"
    )


def train_to_folder(
    algorithm: str,
    pipeline: str,
    out: str | Path,
    *,
    steps: int,
    seconds: float,
    seed: int,
    disturbance=None,
    progress: Callable[[int], None] | None = None,
    randomization=None,
    camera: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """:func:`train_deep`, then write ``policy.npz``, ``hyperparameters.json`` and ``learning_curve.csv``.

    Returns the summary: ``algorithm``, ``policy``, ``hyperparameters`` (its file),
    ``learning_curve``, ``returns`` (of the finished training episodes), ``steps``, ``wall_s``.
    ``camera`` (:func:`train_deep`) is recorded in ``hyperparameters.json`` (the water as its fields) and
    in the policy file's metadata (``trained_through``, as the paper's learners record it).
    """
    from pipefollow.files.atomic import write_text_atomic
    from pipefollow.training.outputs import csv_text
    from pipefollow.training.policy_files import save_policy, trained_through

    out = Path(out)
    run = train_deep(
        algorithm,
        pipeline,
        steps=steps,
        seconds=seconds,
        seed=seed,
        disturbance=disturbance,
        progress=progress,
        randomization=randomization,
        camera=camera,
    )
    seen = {k: v._asdict() if hasattr(v, "_asdict") else v for k, v in (camera or {}).items()}
    record = {"pipeline": str(pipeline), "seconds": seconds, "steps": run.steps, "seed": seed}
    hp_path = write_hyperparameters(
        out / "hyperparameters.json",
        algorithm,
        run.hyperparameters,
        **record,
        wall_s=run.wall_s,
        torch_version=torch.__version__,
        **({"observed_through": seen} if seen else {}),
    )
    through = {"trained_through": trained_through(camera)} if camera else {}  # as the paper's learners' files
    hyper = run.hyperparameters
    policy_path = save_policy(run.policy, out / "policy.npz", hyperparameters=hyper, **record, **through)
    curve = out / "learning_curve.csv"
    write_text_atomic(curve, csv_text(["episode", "return"], enumerate(run.returns)))
    return {
        "algorithm": algorithm,
        "policy": str(policy_path),
        "hyperparameters": str(hp_path),
        "learning_curve": str(curve),
        "returns": run.returns,
        "steps": run.steps,
        "wall_s": run.wall_s,
    }
