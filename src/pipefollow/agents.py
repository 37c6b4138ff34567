"""The agents' common interface and a factory.

Every agent (:class:`~pipefollow.cacla.Cacla`, :class:`~pipefollow.sarsa.Sarsa`,
:class:`~pipefollow.heuristic.Heuristic`) has:

* ``begin_episode(sigma)``: set the exploration σ for the coming episode;
* ``act(obs, explore=True) -> float``: the action in [-1, 1];
* ``update(obs, action, reward, next_obs, discount) -> float``: learn from one (semi-Markov)
  transition, ``discount`` being γ_d^n for n decisions (0 for a terminal state);
* ``discount``: γ_d, and ``algorithm``, ``name``: labels.
"""

from __future__ import annotations

import numpy as np

from pipefollow.cacla import Cacla, CaclaParams
from pipefollow.exploration import skew_step_to_gamma
from pipefollow.sarsa import Sarsa, SarsaParams

ALGORITHMS = ("sarsa", "cacla")


def make_agent(
    algorithm: str,
    *,
    skew_deg: float = 0.0,
    supervised: bool = False,
    rng: np.random.Generator | None = None,
    **params,
) -> Cacla | Sarsa:
    """A fresh learner: ``sarsa`` or ``cacla`` (with ``skew_deg`` Δγ in degrees and ``supervised``).

    Extra keyword arguments override fields of :class:`CaclaParams` / :class:`SarsaParams`.
    """
    if algorithm == "sarsa":
        if skew_deg or supervised:
            raise ValueError("skew and supervision apply to CACLA only")
        return Sarsa(SarsaParams(**params), rng=rng)
    if algorithm == "cacla":
        return Cacla(CaclaParams(skew=skew_step_to_gamma(skew_deg), supervised=supervised, **params), rng=rng)
    raise ValueError(f"algorithm must be one of {', '.join(ALGORITHMS)}, got {algorithm!r}")
