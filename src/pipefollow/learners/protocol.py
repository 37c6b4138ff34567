"""What every learner module gives the layers above: one :class:`LearnerKind` record.

A learner module (``cacla``, ``sarsa``, ``actor_critic``) holds its update rules, its agent class,
its compiled episode loop and its policy-file fields, and names them in a module-level
``LEARNER = LearnerKind(...)``; :mod:`pipefollow.learners.registry` lists the records. Training,
policy files, the benchmark, experiment trials and the command line look a learner up there by
name (``--algorithm NAME``, ``algorithm = "NAME"``) or by its agent (``agent.algorithm``), so adding
a learner is one module and one registry entry.

An agent (an instance of ``agent_class``) has ``begin_episode(sigma)``, ``act(obs, explore)``,
``update(obs, action, reward, next_obs, discount) -> δ``, ``discount``, ``weights``, ``grid``,
``rng``, ``state`` (the named state it observes, :mod:`pipefollow.sim.observation`), ``readings``
(the id of the readings it learns under), ``algorithm`` (its kind's name),
``name`` (a label) and ``supervised``; :class:`Agent` gives the parts every learner's agent shares.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np


def option_code(option: str, codes: Mapping[str, int], value: str) -> int:
    """The code of an option given by name (``actor_repeats``: ``once`` → ``REPEAT_ONCE``).

    Raises:
        ValueError: a name that is not in ``codes`` (``actor_repeats must be one of once, var, got …``).
    """
    if value not in codes:
        raise ValueError(f"{option} must be one of {', '.join(codes)}, got {value!r}")
    return codes[value]


@dataclass(frozen=True)
class LearnerKind:
    """One learner, as the layers above see it.

    Attributes:
        name: its name on the command line and in experiment files.
        title: its name in reports (``CACLA``).
        summary: one line for help texts (with the paper's equations).
        agent_class: the class of its agents.
        options: which switches of :data:`pipefollow.learners.options.LEARNER_OPTIONS` it takes.
        step_sizes: experiment-file field → keyword of ``make`` (its step sizes and discount).
        make: ``make(params, grid, rng, *, readings, ...) -> agent``, a fresh agent with its
            parameter record, its RBF state grid (SARSA: and ``action_grid``) and the id of the
            readings they were built under (kept for the policy file); the layers above build
            them from the readings (:func:`pipefollow.readings.learner_inputs`).
        check: ``check(agent)`` raises ``TypeError`` if the compiled loop cannot run that agent.
        run: ``run(agent, tracks, run, env_rng, dz, stats, poses)`` runs the compiled episodes of
            the protocol of :mod:`pipefollow.sim.episode` (learning if ``run.learn``), writing ``stats`` rows
            (and ``poses`` unless empty).
        policy_fields: ``policy_fields(agent) -> dict`` of the arrays a policy file stores.
        from_policy: ``from_policy(data, seed) -> (agent, weights)`` from a policy file's
            arrays (``KeyError``, ``ValueError`` or ``TypeError`` when they do not fit); the agent
            carries its readings' id, and the caller checks and copies ``weights`` into it.
    """

    name: str
    title: str
    summary: str
    agent_class: type
    options: frozenset[str]
    step_sizes: Mapping[str, str]
    make: Callable
    check: Callable
    run: Callable
    policy_fields: Callable
    from_policy: Callable


class Agent:
    """What every learner's agent shares: its record, its RBF state grid, its generator and σ.

    Args:
        params: the learner's parameter record (with ``discount``).
        grid: the RBF grid of the observation (:class:`~pipefollow.learners.rbf.RBFGrid`).
        rng: generator for exploration noise (or ``seed``).
        seed: seed of a new generator when ``rng`` is None.
    """

    algorithm = ""

    def __init__(self, params, grid, rng: np.random.Generator | None = None, seed: int | None = None) -> None:
        self.params = params
        self.grid = grid
        self.readings = "default"  # id of the readings it learns under (set by the learner's make)
        self.state = "paper"  # the named state it observes (pipefollow.sim.observation); grid fits it
        self.rng = rng if rng is not None else np.random.default_rng(seed)
        self.sigma = 1.0
        self._pending = None

    @property
    def discount(self) -> float:
        """The discount factor γ_d."""
        return self.params.discount

    def retune(self, params) -> None:
        """Take the parameter record ``params`` from the next episode on (a training phase's options).

        Only fields that keep the weights' meaning may differ (the step sizes and the options of
        :data:`~pipefollow.learners.options.PHASE_OPTIONS`); the weights are kept.
        """
        self.params = params
        self._pending = None

    def begin_episode(self, sigma: float) -> None:
        """Set the exploration σ for the coming episode and forget any pending action."""
        self.sigma = float(sigma)
        self._pending = None

    def features(self, obs) -> np.ndarray:
        """φ(obs)."""
        return self.grid.features(obs)
