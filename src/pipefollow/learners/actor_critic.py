"""The paper's reference learners: the general actor-critic of eq. 9 and Rosenstein & Barto's eq. 11.

CACLA (:mod:`pipefollow.learners.cacla`) is built on them (paper §2.1–2.2); this learner keeps
everything of CACLA but the actor's update, so the two differ only in the terms the paper argues
for:

* eq. 9, ``φ += α_π δ ∇_φ ln π(a, s; φ)`` with the Gaussian policy of eq. 8, whose score is
  ``∇_φ ln π = (a − A(s))/σ² ∇_φ A(s)``: the actor moves towards the executed action in proportion
  to δ, away from it when δ < 0. As in eq. 11, whose first part the paper calls "identical to
  (9)", the constant 1/σ² is taken into the step size: ``w_A += α_π δ (a − A(s)) φ(s)``;
* eq. 11 (supervised, Rosenstein & Barto 2004): ``w_A += α_π [k δ (a^RL − A(s)) + (1 − k)(a^SUP −
  A(s))] φ(s)``, the executed action ``k a^RL + (1 − k) a^SUP`` (eq. 10) and k(s) as in supervised
  CACLA (eq. 13).

CACLA's eq. 7 replaces δ by ``max(sgn δ, 0)``: no update when δ ≤ 0 (the max term) and a step
that does not scale with δ (the sign term). To tell the two apart, ``actor_update`` replaces δ by
``max(δ, 0)`` (the max term alone, ``positive``) or ``sgn δ`` (the sign term alone, ``sign``).
The critic (eqs. 5–6), the Gaussian exploration (eq. 8), the features and the semi-Markov updates
while the pipe is lost are CACLA's: this learner runs CACLA's update with its own step factor
(:func:`~pipefollow.learners.actor_agent.step_factor`), CACLA's compiled loop and CACLA's agent class.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.learners import cacla
from pipefollow.learners.actor_agent import DELTA, POSITIVE, SIGN
from pipefollow.learners.cacla import Cacla, CaclaParams
from pipefollow.learners.protocol import LearnerKind
from pipefollow.learners.rbf import STATE_GRID, RBFGrid, state_grid

# The actor's step factor on (a − A(s)) (actor_agent.step_factor): eq. 9's δ, or one of eq. 7's terms.
ACTOR_UPDATES = {"delta": DELTA, "positive": POSITIVE, "sign": SIGN}

# CACLA's record with the step factor after CACLA's fields: CACLA's compiled code reads its packed
# form (``cacla.unpack`` reads the fields it starts with) and the record itself by the same names.
ActorCriticParams = NamedTuple(
    "ActorCriticParams", [*CaclaParams.__annotations__.items(), ("actor_update", int)]
)
ActorCriticParams.__new__.__defaults__ = (*CaclaParams(), DELTA)
ActorCriticParams.__doc__ = "The actor-critic's step sizes and options: CACLA's, and the actor's step factor."
PAPER_AC = ActorCriticParams()  # the paper's α_V = 0.4, α_π = 0.2, γ_d = 0.8, Δk = 0.05; eq. 9's δ


@njit(cache=True)
def update(w, phi, a_rl, a_sup, reward, discount, phi_next, p):
    """One actor-critic update (eq. 9, or eq. 11 when supervised) from φ(s); returns δ.

    CACLA's update (critic, k(s)) with the record's step factor; ``discount`` is γ_d^n for a
    transition of n decisions (semi-Markov, docs/design.md).
    """
    return cacla.update(w, phi, a_rl, a_sup, reward, discount, phi_next, p, p.actor_update)


class ActorCritic(Cacla):
    """An actor-critic agent (eq. 9; eq. 11 when supervised): CACLA's agent with another actor step.

    Args:
        params: step sizes and options (:data:`ActorCriticParams`, without skew).
        grid, rng, seed, supervisor: as for :class:`~pipefollow.learners.cacla.Cacla`.

    Raises:
        ValueError: ``params`` with a skew step (this learner explores with eq. 8 only).
    """

    algorithm = "ac"

    def __init__(
        self,
        params: ActorCriticParams = PAPER_AC,
        grid: RBFGrid = STATE_GRID,
        rng: np.random.Generator | None = None,
        seed: int | None = None,
        supervisor: Callable[[np.ndarray], float] | None = None,
    ) -> None:
        if params.skew != 0.0:
            raise ValueError(f"the actor-critic explores with eq. 8 only: skew must be 0, got {params.skew}")
        super().__init__(params, grid, rng, seed, supervisor)

    @staticmethod
    def rule(params) -> int:
        """The actor's step factor: the record's ``actor_update``."""
        return int(params.actor_update)

    @property
    def name(self) -> str:
        """Short algorithm label."""
        name = "supervised actor-critic" if self.params.supervised else "actor-critic"
        factor = {POSITIVE: ", max(δ, 0)", SIGN: ", sgn(δ)"}.get(self.params.actor_update, "")
        return name + factor


def from_policy(data: dict, seed: int | None = None):
    """An agent and its weights from a policy file's arrays (CACLA's fields)."""
    return cacla.from_policy(data, seed, agent_class=ActorCritic, params_class=ActorCriticParams)


def make(
    r,
    rng: np.random.Generator | None = None,
    *,
    supervised: bool = False,
    actor_update: str = "delta",
    **fields,
) -> ActorCritic:
    """A fresh actor-critic under the readings ``r`` (fields: those of ``CaclaParams`` but the skew's).

    ``actor_update``: ``delta`` (eq. 9), ``positive`` or ``sign`` (:func:`.actor_agent.step_factor`).

    Raises:
        ValueError: an unknown ``actor_update``.
    """
    if actor_update not in ACTOR_UPDATES:
        raise ValueError(f"actor_update must be one of {', '.join(ACTOR_UPDATES)}, got {actor_update!r}")
    base = cacla.params_under(r, 0.0, supervised=supervised, **fields)
    params = ActorCriticParams(*base, actor_update=ACTOR_UPDATES[actor_update])
    agent = ActorCritic(params, grid=state_grid(r.rbf, r.rbf_width), rng=rng)
    agent.readings = r.id
    return agent


LEARNER = LearnerKind(
    name="ac",
    title="actor-critic",
    summary="the general actor-critic (eq. 9; supervised: Rosenstein & Barto's eq. 11)",
    agent_class=ActorCritic,
    options=frozenset({"supervised", "actor_update", "critic_lambda"}),
    step_sizes=cacla.LEARNER.step_sizes,
    make=make,
    check=cacla.check_compiled,
    run=cacla.run_compiled,
    policy_fields=cacla.policy_fields,
    from_policy=from_policy,
)
