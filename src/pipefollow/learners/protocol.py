"""What every learner module gives the layers above: one :class:`LearnerKind` record.

A learner module (``cacla``, ``sarsa``, ``actor_critic``) holds its update rules, its agent class,
its compiled episode loop and its policy-file fields, and names them in a module-level
``LEARNER = LearnerKind(...)``; :mod:`pipefollow.learners.registry` lists the records. Training,
policy files, the benchmark, experiment trials and the command line look a learner up there by
name (``--algorithm NAME``, ``algorithm = "NAME"``) or by its agent (``agent.algorithm``), so adding
a learner is one module and one registry entry.

An agent (an instance of ``agent_class``) has ``begin_episode(sigma)``, ``act(obs, explore)``,
``update(obs, action, reward, next_obs, discount) -> δ``, ``discount``, ``weights``, ``grid``,
``rng``, ``readings`` (the id of the readings it learns under), ``algorithm`` (its kind's name),
``name`` (a label) and ``supervised``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

# Options of the command line and experiment files, each with its off value; a learner names the
# ones it takes in ``LearnerKind.options``, and an option set for another learner is refused.
OPTIONS = {"skew_deg": 0.0, "supervised": False, "actor_update": "delta"}


@dataclass(frozen=True)
class LearnerKind:
    """One learner, as the layers above see it.

    Attributes:
        name: its name on the command line and in experiment files.
        title: its name in reports (``CACLA``).
        summary: one line for help texts (with the paper's equations).
        agent_class: the class of its agents.
        options: which of :data:`OPTIONS` it takes.
        step_sizes: experiment-file field → keyword of ``make`` (its step sizes and discount).
        make: ``make(readings, rng, **options_and_step_sizes) -> agent``, a fresh agent under the
            readings (a :class:`pipefollow.readings.Readings`, read by attribute).
        check: ``check(agent)`` raises ``TypeError`` if the compiled loop cannot run that agent.
        run: ``run(agent, tracks, run, env_rng, dz, stats, poses)`` runs the compiled episodes of
            :mod:`pipefollow.learners.episodes` (learning if ``run.learn``), writing ``stats`` rows
            (and ``poses`` unless empty).
        policy_fields: ``policy_fields(agent) -> dict`` of the arrays a policy file stores.
        from_policy: ``from_policy(data, version, seed) -> (agent, weights)`` from a policy file's
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
