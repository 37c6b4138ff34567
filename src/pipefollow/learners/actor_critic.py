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
(:func:`~pipefollow.learners.cacla_update.step_factor`), CACLA's compiled loop and CACLA's agent class.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from pipefollow.learners import cacla
from pipefollow.learners.cacla import Cacla
from pipefollow.learners.cacla_act import PAPER_CACLA
from pipefollow.learners.cacla_update import (
    DELTA,
    K_EVERY,
    POSITIVE,
    REPEAT_ONCE,
    SAMPLE_LOCATION,
    SIGN,
    STEP_GAMMA,
    STEP_WEIGHTS,
)
from pipefollow.learners.protocol import LearnerKind
from pipefollow.learners.rbf import STATE_GRID, RBFGrid

# The actor's step factor on (a − A(s)) (cacla_update.step_factor): eq. 9's δ, or one of eq. 7's terms.
ACTOR_UPDATES = {"delta": DELTA, "positive": POSITIVE, "sign": SIGN}


class ActorCriticParams(NamedTuple):
    """The actor-critic's step sizes and options: CACLA's, and the actor's step factor.

    The fields up to ``critic_lambda`` are :class:`~pipefollow.learners.cacla_act.CaclaParams`'s, in
    its order and with its defaults, so that CACLA's compiled code reads the packed record
    (``cacla_act.unpack`` reads the fields it starts with) and the record itself by the same names.
    """

    alpha_v: float = PAPER_CACLA.alpha_v  # critic step size α_V (paper §4)
    alpha_pi: float = PAPER_CACLA.alpha_pi  # actor step size α_π (paper §4)
    discount: float = PAPER_CACLA.discount  # discount factor γ_d (paper §4)
    skew: float = 0.0  # always 0: this learner explores with eq. 8 only
    gamma_max: float = 1.0  # cap |γ(s)| ≤ γ_max, unused without skew
    supervised: bool = False  # supervised actor-critic (eqs. 10, 11, 13)
    delta_k: float = PAPER_CACLA.delta_k  # Δk per visit (paper §4.1)
    k_max: float = 1.0  # cap on k(s) (eq. 13)
    forgetting: float = 0.0  # per-update decay of w_k (Rosenstein & Barto); the paper uses none
    skew_sample: int = SAMPLE_LOCATION  # unused without skew
    skew_step: int = STEP_GAMMA  # unused without skew
    k_update: int = K_EVERY  # eq. 13: k(s) grows at every visit (default) or only when δ > 0
    k_step: int = STEP_WEIGHTS  # eq. 13 step: w_k by Δk·φ(s) (default) or k(s) by Δk (STEP_GAMMA)
    actor_repeats: int = REPEAT_ONCE  # CACLA+Var's repeats, not an option of this learner
    var_rate: float = 0.001  # β of CACLA+Var, unused without it
    critic_lambda: float = 0.0  # beyond the paper: λ of the critic's TD(λ) trace; 0 = eqs. 5-6 (TD(0))
    actor_update: int = DELTA  # the actor's step factor: eq. 9's δ (default), max(δ, 0) or sgn(δ)


PAPER_AC = ActorCriticParams()  # the paper's step sizes (CACLA's); eq. 9's δ


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


def make(params: ActorCriticParams, grid: RBFGrid, rng: np.random.Generator | None = None, *,
         readings: str = "default") -> ActorCritic:  # fmt: skip
    """A fresh actor-critic with ``params`` on ``grid``, built under the readings with id ``readings``."""
    return cacla.make(params, grid, rng, readings=readings, agent_class=ActorCritic)


LEARNER = LearnerKind(
    name="ac",
    title="actor-critic",
    summary="the general actor-critic (eq. 9; supervised: Rosenstein & Barto's eq. 11)",
    agent_class=ActorCritic,
    options=frozenset({"supervised", "actor_update", "critic_lambda"}),
    step_sizes={k: v for k, v in cacla.LEARNER.step_sizes.items() if k != "var_rate"},  # no CACLA+Var
    make=make,
    check=cacla.check_compiled,
    run=cacla.run_compiled,
    policy_fields=cacla.policy_fields,
    from_policy=from_policy,
)
