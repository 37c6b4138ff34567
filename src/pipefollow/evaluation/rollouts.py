"""Rollouts of a controller as a Minari dataset, for offline RL and behaviour cloning.

One episode per pipe of a suite, through the Gymnasium environment wrapped in Minari's
``DataCollector``: observations, actions, rewards, terminations, truncations and the infos of
every step. Deterministic (σ = 0) by default; with ``sigma > 0`` a learner explores as in training
(Gaussian or skew-normal around its actor, from its seeded generator), which gives the spread of
actions that offline learners need. Needs the optional extra ``rollouts`` (``minari``).

The dataset is written under ``folder/<dataset id>`` (Minari's layout: ``data/`` and
``metadata.json``) and is read back with ``minari.load_dataset(id)`` once
``MINARI_DATASETS_PATH`` names ``folder``. The dataset recovers its environment
(``recover_environment()``, also with ``eval_env=True``): reset with an episode's seed and pipe
(its metadata's ``seed`` and ``options``, :func:`episode_reset`), it runs that episode again.
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


def _environment(first: Pipeline, seconds: float, params, camera: dict | None = None):
    """The environment the rollouts run in, made by ``gym.make`` so that the dataset keeps its spec.

    Its keyword arguments are plain numbers and names (the first pipe's points, the episode's
    seconds, the disturbance as its user-unit table, the camera, sensor and water's fields), so
    Minari stores the spec as JSON and
    ``recover_environment()`` makes the same environment again; each episode's pipe is its reset
    option, which Minari stores with its seed. A simulation other than the paper's besides its
    disturbance (another reading) has no such form: the environment is then built directly and the
    dataset cannot recover it.
    """
    import gymnasium as gym

    import pipefollow.envs  # noqa: F401 (registers the ids)
    from pipefollow import ENV_ID
    from pipefollow.envs.env import PipelineFollowingEnv
    from pipefollow.envs.shell import make_setup
    from pipefollow.sim import decision as sim
    from pipefollow.sim.disturbance import disturbance_from_dict, to_dict

    params = sim.PAPER_SIM if params is None else params
    kwargs = {"pipeline": first.points.tolist(), "episode_seconds": float(seconds)}
    for key, value in (camera or {}).items():  # a Water record as the dict of its fields
        kwargs[key] = dict(value._asdict()) if hasattr(value, "_asdict") else value
    table = to_dict(params.disturbance)
    if params._replace(disturbance=sim.PAPER_SIM.disturbance) != sim.PAPER_SIM or (
        disturbance_from_dict(table) != params.disturbance
    ):
        return PipelineFollowingEnv(**kwargs, params=params)
    if params.disturbance != sim.PAPER_SIM.disturbance:
        kwargs["disturbance"] = table
    decisions = make_setup(seconds).max_decisions  # the episode's, for gym.make's TimeLimit
    return gym.make(ENV_ID, **kwargs, max_episode_steps=decisions)


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
    camera: dict | None = None,
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
        camera: the environment's camera arguments (``camera``, ``water``, ``sensor``), kept in the
            dataset's spec; None for the ideal camera.

    Returns:
        The dataset's folder.
    """
    try:
        import minari
    except ImportError as e:
        raise RolloutsExtraMissing(
            "rollouts need the optional extra 'rollouts' (pip install 'pipefollow[rollouts]')"
        ) from e
    from pipefollow.training.compiled import run_episode

    folder = Path(folder).resolve()  # Minari joins relative paths twice
    folder.mkdir(parents=True, exist_ok=True)
    env = _environment(pipes[0], seconds, params, camera)
    import gc
    import warnings

    # Minari's advice for datasets published on its server (an author e-mail, ...) does not apply
    # to a local one; and Minari 0.5 removes its temporary folders itself but leaves
    # TemporaryDirectory objects that warn when collected. Both are silenced for Minari's calls alone.
    with _datasets_path(folder), warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=UserWarning, module=r"minari\.")
        warnings.simplefilter("ignore", ResourceWarning)
        collector = minari.DataCollector(env, record_infos=True)  # the same info keys at every step
        recorded = _array_actions(collector)
        for k, pipe in enumerate(pipes):
            options = {"pipeline": pipe.points.tolist()}  # plain numbers: Minari stores the options
            run_episode(recorded, agent, explore=sigma > 0, sigma=sigma, seed=seed + k, options=options)
        collector.create_dataset(
            dataset_id=dataset_id,
            eval_env=env.spec,  # the same environment: reset it with an episode's seed and pipe
            algorithm_name=getattr(agent, "name", type(agent).__name__),
            description=description or f"{len(pipes)} episodes of {seconds:g} s, σ = {sigma:g}",
        )
        collector.close()
        del collector, recorded
        gc.collect()
    return folder / dataset_id


def episode_reset(dataset, index: int) -> dict:
    """The keyword arguments of ``reset`` that start episode ``index`` of a rollouts dataset again.

    Minari keeps each episode's seed and its reset options (the pipe's points);
    ``env.reset(**episode_reset(dataset, k))`` on ``dataset.recover_environment()`` then gives that
    episode's observations for its actions.
    """
    (meta,) = dataset.storage.get_episode_metadata([dataset.episode_indices[index]])
    options = dict(meta.get("options", {}))
    if "pipeline" in options:  # Minari gives the points back as an array
        options["pipeline"] = np.asarray(options["pipeline"], dtype=np.float64).tolist()
    return {"seed": int(meta["seed"]), "options": options}
