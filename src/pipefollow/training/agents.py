"""The agents' common interface and a factory.

Every agent (:class:`~pipefollow.learners.cacla.Cacla`, :class:`~pipefollow.learners.sarsa.Sarsa`,
:class:`~pipefollow.learners.heuristic.Heuristic`) has:

* ``begin_episode(sigma)``: set the exploration σ for the coming episode;
* ``act(obs, explore=True) -> float``: the action in [-1, 1];
* ``update(obs, action, reward, next_obs, discount) -> float``: learn from one (semi-Markov)
  transition, ``discount`` being γ_d^n for n decisions (0 for a terminal state);
* ``discount``: γ_d, and ``algorithm``, ``name``: labels.
"""

from __future__ import annotations

import numpy as np

from pipefollow import readings as rd
from pipefollow.learners.cacla import Cacla
from pipefollow.learners.sarsa import Sarsa, SarsaParams

ALGORITHMS = ("sarsa", "cacla")


def make_agent(
    algorithm: str,
    *,
    skew_deg: float = 0.0,
    supervised: bool = False,
    rng: np.random.Generator | None = None,
    readings: rd.Readings = rd.DEFAULT,
    **params,
) -> Cacla | Sarsa:
    """A fresh learner: ``sarsa`` or ``cacla`` (with ``skew_deg`` Δγ in degrees and ``supervised``).

    ``readings`` fixes the open points (RBF form and widths, the skew and k(s) rules); extra
    keyword arguments override fields of :class:`~pipefollow.learners.cacla.CaclaParams` /
    :class:`~pipefollow.learners.sarsa.SarsaParams`.
    """
    grid = rd.state_grid(readings)
    if algorithm == "sarsa":
        if skew_deg or supervised:
            raise ValueError("skew and supervision apply to CACLA only")
        agent = Sarsa(SarsaParams(**params), grid=grid, action_grid=rd.action_grid(readings), rng=rng)
        agent.readings = readings.id
        return agent
    if algorithm == "cacla":
        params = rd.cacla_params(readings, skew_deg, supervised=supervised, **params)
        agent = Cacla(params, grid=grid, rng=rng)
        agent.readings = readings.id
        return agent
    raise ValueError(f"algorithm must be one of {', '.join(ALGORITHMS)}, got {algorithm!r}")
