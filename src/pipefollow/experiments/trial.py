"""The unit of work: ``run_trial(config, seed) -> TrialResult``, a pure function of its inputs."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.experiments.config import TrialConfig
from pipefollow.experiments.schema import learner_values
from pipefollow.learners.heuristic import Heuristic
from pipefollow.learners.registry import agent_options
from pipefollow.sim.disturbance import NO_DISTURBANCE, disturbance_from_dict
from pipefollow.sim.pipe_names import resolve_training
from pipefollow.sim.suites import Suite, min_length_for
from pipefollow.training.agents import make_agent
from pipefollow.training.compiled import run_episode
from pipefollow.training.phases import agent_rng, phase_sigmas, sim_under, train_phases


@dataclass(frozen=True)
class TrialResult:
    """What one trial produced.

    Attributes:
        trial: the trial's name.
        seed: its seed.
        stats: (episodes, 4) per training episode: return, pipe_in_view, progress_m, time_lost_s.
        phase: (episodes,) index of the training phase of each episode.
        sigma: (episodes,) exploration σ of each episode.
        weights: the learned weights (the policy; with the config it rebuilds the agent).
        evaluation: controller → (return, pipe_in_view, progress_m, time_lost_s) of one deterministic
            episode on the evaluation pipeline: ``learned`` (as executed, with the supervisor for
            supervised agents), ``actor`` (supervised agents' pure actor) and ``heuristic``.
        poses: controller → (n, 3) poses of those evaluation episodes.
        evaluation_pipeline: name of the evaluation pipeline.
        wall_seconds: time the trial took.
    """

    trial: str
    seed: int
    stats: np.ndarray
    phase: np.ndarray
    sigma: np.ndarray
    weights: np.ndarray
    evaluation: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)
    poses: dict[str, np.ndarray] = field(default_factory=dict)
    evaluation_pipeline: str = ""
    wall_seconds: float = 0.0


def build_agent(config: TrialConfig, rng: np.random.Generator | None = None, phase=None):
    """A fresh agent for ``config`` under its readings: the values of its learner's options.

    :func:`~pipefollow.learners.registry.agent_options` reads them, as for ``pipefollow train``;
    with a ``phase``, those it sets (its ``learner`` table) in place of the trial's.
    """
    values = agent_options(config.algorithm, learner_values(config, phase), strict=False)
    return make_agent(config.algorithm, rng=rng, readings=config.reading, **values)


def phase_params(config: TrialConfig) -> list:
    """The learner's parameter record of each phase: None for a phase without a ``learner`` table."""
    rng = np.random.default_rng(0)  # the records only: the agents built here draw nothing
    return [build_agent(config, rng, ph).params if ph.learner else None for ph in config.phases]


class ActorOnly:
    """A supervised agent's pure actor, clip(A(s)), as a deterministic controller."""

    name = "actor"

    def __init__(self, agent) -> None:
        self.agent = agent

    def begin_episode(self, sigma: float) -> None:  # noqa: D102
        pass

    def act(self, obs, explore: bool = False) -> float:  # noqa: D102
        return self.agent.actor(obs)


def training_camera(config: TrialConfig) -> dict | None:
    """The environment's camera arguments a trial trains through, or None: the compiled loops."""
    if not config.train_through_sensor:
        return None
    return {"camera": config.camera, "water": config.water, "sensor": config.sensor}


def run_trial(config: TrialConfig, seed: int) -> TrialResult:
    """Train the learner of ``config`` with ``seed`` and evaluate it deterministically.

    Training runs the learner's compiled loops, or through the trial's camera and sensor in the
    environment with ``train_through_sensor`` (:func:`training_camera`).
    """
    t0 = time.perf_counter()
    agent = build_agent(config, agent_rng(seed))
    disturbance = disturbance_from_dict(config.disturbance) if config.disturbance else NO_DISTURBANCE
    params = sim_under(config.reading, disturbance)
    stats = train_phases(
        agent,
        [(ph.pipeline, ph.episodes) for ph in config.phases],
        seed=seed,
        readings=config.reading,
        disturbance=disturbance,
        randomization=config.randomization,
        episode_seconds=config.episode_seconds,
        sigma_start=config.sigma_start,
        sigma_end=config.sigma_end,
        phase_params=phase_params(config),
        camera=training_camera(config),
    )
    phase = [np.full(ph.episodes, i) for i, ph in enumerate(config.phases)]
    schedule = (config.reading, config.sigma_start, config.sigma_end)
    sigma = [phase_sigmas(ph.episodes, *schedule) for ph in config.phases]
    eval_name = config.evaluate_on or config.phases[-1].pipeline
    eval_seconds = config.evaluate_seconds if config.evaluate_on else config.episode_seconds
    eval_pipe = resolve_training(eval_name)
    if isinstance(eval_pipe, Suite):  # trained on random pipes only: the family's first pipe
        eval_pipe = eval_pipe.pipe(0, min_length_for(eval_seconds))
    env = PipelineFollowingEnv(
        eval_pipe, eval_seconds, params=params, camera=config.camera, water=config.water, state=agent.state,
        sensor=config.sensor,
    )  # fmt: skip
    controllers = {"learned": agent, "heuristic": Heuristic()}
    if agent.supervised:
        controllers["actor"] = ActorOnly(agent)
    evaluation, poses = {}, {}
    for name, controller in controllers.items():  # the same seed: the same disturbances, if any
        ep = run_episode(env, controller, seed=seed)
        evaluation[name] = ep.as_row()
        poses[name] = ep.poses
    return TrialResult(
        trial=config.name,
        seed=seed,
        stats=np.concatenate(stats),
        phase=np.concatenate(phase),
        sigma=np.concatenate([np.asarray(s, dtype=np.float64) for s in sigma]),
        weights=agent.weights.copy(),
        evaluation=evaluation,
        poses=poses,
        evaluation_pipeline=eval_name,
        wall_seconds=time.perf_counter() - t0,
    )
