"""Rollouts of a controller as a Minari dataset, for offline RL and behaviour cloning.

One episode per pipe of a suite, through the Gymnasium environment wrapped in Minari's
``DataCollector``: observations, actions, rewards, terminations, truncations and the infos of
every step. Deterministic (σ = 0) by default; with ``sigma > 0`` a learner explores as in training
(Gaussian or skew-normal around its actor, from its seeded generator), which gives the spread of
actions that offline learners need. Needs the optional extra ``rollouts`` (``minari``).

The dataset is written under ``folder/<dataset id>`` (Minari's layout: ``data/`` and
``metadata.json``) and is read back with ``minari.load_dataset(id)`` once
``MINARI_DATASETS_PATH`` names ``folder``.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from pipefollow.files.paper_training import TEST_EPISODE_SECONDS
from pipefollow.sim.pipeline import Pipeline


class RolloutsExtraMissing(ImportError):
    """Minari is not installed."""


@contextmanager
def _datasets_path(folder: Path):
    """Minari keeps datasets under ``$MINARI_DATASETS_PATH``: point it at ``folder`` meanwhile."""
    old = os.environ.get("MINARI_DATASETS_PATH")
    os.environ["MINARI_DATASETS_PATH"] = str(folder)
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("MINARI_DATASETS_PATH", None)
        else:
            os.environ["MINARI_DATASETS_PATH"] = old


def _array_infos(env):
    """``env`` with infos Minari can store: the keys every step has (each already an array).

    Minari keeps the infos as arrays with one row per step (the reset's included), so the episode
    summary and end reason that only the last step has (:data:`~pipefollow.envs.shell.LAST_STEP_KEYS`)
    are left out.
    """
    import gymnasium as gym

    from pipefollow.envs.shell import LAST_STEP_KEYS

    def per_step(info):
        return {k: v for k, v in info.items() if k not in LAST_STEP_KEYS}

    class ArrayInfos(gym.Wrapper):
        def reset(self, **kwargs):
            obs, info = self.env.reset(**kwargs)
            return obs, per_step(info)

        def step(self, action):
            obs, reward, terminated, truncated, info = self.env.step(action)
            return obs, reward, terminated, truncated, per_step(info)

    return ArrayInfos(env)


def _array_actions(env):
    """``env`` taking actions as arrays of the action space's dtype before Minari records them."""
    import gymnasium as gym

    class ArrayActions(gym.ActionWrapper):
        def action(self, action):
            return np.asarray(action, dtype=self.action_space.dtype).reshape(self.action_space.shape)

    return ArrayActions(env)


def record_rollouts(
    agent,
    pipes: Sequence[Pipeline],
    folder: str | os.PathLike,
    dataset_id: str,
    *,
    seconds: float = TEST_EPISODE_SECONDS,
    params=None,
    sigma: float = 0.0,
    seed: int = 0,
    description: str = "",
) -> Path:
    """Run ``agent`` once on each pipe and write the episodes as the Minari dataset ``dataset_id``.

    Args:
        agent: a controller with ``begin_episode`` and ``act`` (heuristic, LOS, a loaded policy).
        pipes: one episode per pipe, in order.
        folder: where the dataset folder is made.
        dataset_id: Minari's id, ``namespace/name-vN`` (e.g. ``pipefollow/heldout-heuristic-v0``).
        seconds: episode length.
        params: the simulation's parameters (readings, disturbances); the paper's by default.
        sigma: exploration σ of a learner (0: deterministic).
        seed: seed of episode ``k``'s environment: ``seed + k``.
        description: a line for the dataset's metadata.

    Returns:
        The dataset's folder.
    """
    try:
        import minari
    except ImportError as e:
        raise RolloutsExtraMissing(
            "rollouts need the optional extra 'rollouts' (pip install 'pipefollow[rollouts]')"
        ) from e
    from pipefollow.envs.env import PipelineFollowingEnv
    from pipefollow.training.compiled import run_episode

    folder = Path(folder).resolve()  # Minari joins relative paths twice
    folder.mkdir(parents=True, exist_ok=True)
    kwargs = {} if params is None else {"params": params}
    env = PipelineFollowingEnv(pipes[0], seconds, **kwargs)
    import gc
    import warnings

    # Minari's advice for datasets published on its server (an author e-mail, an evaluation
    # environment's spec: this one is made here, not by gym.make) does not apply to a local one;
    # and Minari 0.5 removes its temporary folders itself but leaves TemporaryDirectory objects
    # that warn when collected. Both are silenced for Minari's calls alone.
    with _datasets_path(folder), warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=UserWarning, module=r"minari\.")
        warnings.simplefilter("ignore", ResourceWarning)
        collector = minari.DataCollector(_array_infos(env), record_infos=True)
        recorded = _array_actions(collector)
        for k, pipe in enumerate(pipes):
            options = {"pipeline": pipe.points.tolist()}  # plain numbers: Minari stores the options
            run_episode(recorded, agent, explore=sigma > 0, sigma=sigma, seed=seed + k, options=options)
        collector.create_dataset(
            dataset_id=dataset_id,
            algorithm_name=getattr(agent, "name", type(agent).__name__),
            description=description or f"{len(pipes)} episodes of {seconds:g} s, σ = {sigma:g}",
        )
        collector.close()
        del collector, recorded
        gc.collect()
    return folder / dataset_id
