"""The agents' factory under the readings (:mod:`pipefollow.learners.registry` names the learners).

Every agent (a learner of the registry, :class:`~pipefollow.learners.heuristic.Heuristic`) has:

* ``begin_episode(sigma)``: set the exploration σ for the coming episode;
* ``act(obs, explore=True) -> float``: the action in [-1, 1];
* ``update(obs, action, reward, next_obs, discount) -> float``: learn from one (semi-Markov)
  transition, ``discount`` being γ_d^n for n decisions (0 for a terminal state);
* ``discount``: γ_d, and ``algorithm``, ``name``: labels.
"""

from __future__ import annotations

import numpy as np

from pipefollow import readings as rd
from pipefollow.learners import registry

ALGORITHMS = registry.NAMES


def make_agent(
    algorithm: str,
    *,
    skew_deg: float = 0.0,
    supervised: bool = False,
    rng: np.random.Generator | None = None,
    readings: rd.Readings = rd.DEFAULT,
    state: str = "paper",
    **params,
):
    """A fresh learner of the registry (``sarsa``, ``cacla``, ``ac``) under ``readings``.

    ``skew_deg`` is Δγ in degrees (CACLA), ``supervised`` adds the heuristic as supervisor (CACLA,
    actor-critic); ``state`` names what it observes (:mod:`pipefollow.sim.observation`: ``paper``,
    ``paper+drift``, …; its RBF grid); extra keyword arguments override fields of the learner's
    parameter record.

    The readings become the learner's parameter record and grids (:func:`pipefollow.readings.learner_inputs`);
    the learner's ``make`` receives those and the readings' id.

    Raises:
        ValueError: an unknown algorithm, an option it does not take, or an unknown option value.
    """
    from pipefollow.learners.options import check_value

    state = check_value("state", state)
    options = registry.options_for(algorithm, skew_deg=skew_deg, supervised=supervised, **params)
    inputs = rd.learner_inputs(algorithm, readings, state=state, **options)
    agent = registry.learner(algorithm).make(**inputs, rng=rng, readings=readings.id)
    agent.state = state
    return agent
