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
while the pipe is lost are CACLA's.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numba import njit
from numba.np.unsafe.ndarray import to_fixed_tuple

from pipefollow.learners import cacla
from pipefollow.learners import episodes as ep
from pipefollow.learners.actor_agent import A, ActorAgent, K, V
from pipefollow.learners.cacla import CaclaParams, act, trust_step
from pipefollow.learners.heuristic import heuristic_action
from pipefollow.learners.protocol import LearnerKind
from pipefollow.learners.rbf import STATE_GRID, RBFGrid, features_if_finite, grid_features, state_grid
from pipefollow.learners.sums import dot
from pipefollow.sim import decision as sim
from pipefollow.sim import records

# The actor's step factor on (a − A(s)): eq. 9's δ, or δ with one of eq. 7's two terms (paper §2.1).
DELTA, POSITIVE, SIGN = 0, 1, 2  # δ (eq. 9); max(δ, 0): the max term alone; sgn(δ): the sign term alone
ACTOR_UPDATES = {"delta": DELTA, "positive": POSITIVE, "sign": SIGN}

# CACLA's record with the step factor: CACLA's compiled policy (``cacla.act``) and k(s) step
# (``cacla.trust_step``) read it by the same field names.
ActorCriticParams = NamedTuple(
    "ActorCriticParams", [*CaclaParams.__annotations__.items(), ("actor_update", int)]
)
ActorCriticParams.__new__.__defaults__ = (*CaclaParams(), DELTA)
ActorCriticParams.__doc__ = "The actor-critic's step sizes and options: CACLA's, and the actor's step factor."
PAPER_AC = ActorCriticParams()  # the paper's α_V = 0.4, α_π = 0.2, γ_d = 0.8, Δk = 0.05; eq. 9's δ
_N_PARAMS = records.size(PAPER_AC)


@njit(cache=True)
def unpack(a):
    """The record packed by ``records.pack``, inside compiled code (codes and flags as floats)."""
    return ActorCriticParams(*to_fixed_tuple(a, _N_PARAMS))


@njit(cache=True)
def step_factor(delta, p):
    """The actor's factor on (a − A(s)): δ (eq. 9), max(δ, 0) or sgn(δ) (each one of eq. 7's terms)."""
    if p.actor_update == POSITIVE:
        return max(delta, 0.0)
    if p.actor_update == SIGN:
        return float(np.sign(delta))
    return delta


@njit(cache=True)
def update(w, phi, a_rl, a_sup, reward, discount, phi_next, p):
    """One actor-critic update (eq. 9, or eq. 11 when supervised) from φ(s); returns δ.

    ``discount`` is γ_d^n for a transition of n decisions (semi-Markov, docs/design.md).
    """
    v = dot(w[V], phi)
    delta = reward + discount * dot(w[V], phi_next) - v  # eq. 4, pre-update critic
    mu = dot(w[A], phi)
    if p.supervised:
        k = min(p.k_max, max(0.0, dot(w[K], phi)))
        step = p.alpha_pi * (k * step_factor(delta, p) * (a_rl - mu) + (1.0 - k) * (a_sup - mu))  # eq. 11
    else:
        step = p.alpha_pi * step_factor(delta, p) * (a_rl - mu)  # eq. 9, Gaussian score, 1/σ² in α_π
    cv = p.alpha_v * delta  # eqs. 5-6
    for i in range(phi.shape[0]):
        w[V, i] += cv * phi[i]
        w[A, i] += step * phi[i]
    if p.supervised:
        trust_step(w, phi, delta, p)
    return delta


@njit(cache=True)
def act_packed(w, phi, sigma, z0, z1, a_sup, hp):
    """CACLA's policy (eq. 8; eq. 10 when supervised) with this learner's packed parameters."""
    return act(w, phi, sigma, z0, z1, a_sup, unpack(hp))


@njit(cache=True)
def act_heuristic_packed(w, phi, sigma, z0, z1, x1, y1, hp):
    """:func:`act_packed` with the paper's heuristic as supervisor, evaluated in compiled code."""
    p = unpack(hp)
    a_sup = heuristic_action(x1, y1) if p.supervised else 0.0
    a, a_rl = act(w, phi, sigma, z0, z1, a_sup, p)
    return a, a_rl, a_sup


@njit(cache=True)
def update_packed(w, phi, a_rl, a_sup, reward, discount, phi_next, hp):
    """:func:`update` with packed parameters: the cheap entry point from Python."""
    return update(w, phi, a_rl, a_sup, reward, discount, phi_next, unpack(hp))


@njit(cache=True)
def update_next_packed(w, phi, a_rl, a_sup, reward, discount, next_obs, grid, normalized, phi_next, hp):
    """φ(s') into ``phi_next`` and :func:`update`, in one call; ``(δ, False)`` if s' is not finite."""
    if not features_if_finite(next_obs, grid[0], grid[1], grid[2], normalized, phi_next):
        return 0.0, False
    return update(w, phi, a_rl, a_sup, reward, discount, phi_next, unpack(hp)), True


class ActorCritic(ActorAgent):
    """An actor-critic agent (eq. 9; eq. 11 when supervised) on CACLA's features and Gaussian policy.

    Args:
        params: step sizes and options (:data:`ActorCriticParams`, without skew).
        grid, rng, seed, supervisor: as for :class:`~pipefollow.learners.cacla.Cacla`.

    Raises:
        ValueError: ``params`` with a skew step (this learner explores with eq. 8 only).
    """

    algorithm = "ac"
    pack = staticmethod(records.pack)
    act_packed = staticmethod(act_packed)
    act_heuristic_packed = staticmethod(act_heuristic_packed)
    update_packed = staticmethod(update_packed)
    update_next_packed = staticmethod(update_next_packed)

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

    @property
    def name(self) -> str:
        """Short algorithm label."""
        name = "supervised actor-critic" if self.params.supervised else "actor-critic"
        factor = {POSITIVE: ", max(δ, 0)", SIGN: ", sgn(δ)"}.get(self.params.actor_update, "")
        return name + factor


@njit(cache=True)
def episodes(w, hp, tracks, run, grid, rng, env_rng, dz, stats, poses):
    """The actor-critic's episodes in compiled code: the same numbers as its agent in the environment."""
    p = unpack(hp)
    ps = sim.unpack_params(run.sim)
    decision_s = ps.dt * ps.substeps
    nf = w.shape[1]
    s = np.empty(sim.STATE_SIZE)
    phi, phi_pend, phi_next = np.empty(nf), np.empty(nf), np.empty(nf)
    book, totals = np.empty(ep.BOOK_SIZE), np.empty(ep.TALLY_SIZE)
    n = run.n_decisions
    for e in range(run.sigmas.shape[0]):
        sigma = run.sigmas[e]
        points, cum, start = ep.pipe_of(tracks, e)
        ep.start_episode(s, points, cum, start, ps, env_rng, dz, book, totals, poses, e)
        have_phi = False  # phi already holds φ(s) of the current state (computed for the last update)
        a_rl_p = a_sup_p = 0.0
        for t in range(n):
            visible = s[sim.IN_VIEW] != 0.0
            a = a_rl = a_sup = 0.0
            if visible:
                if not have_phi:
                    grid_features(s[:4], grid.centres, grid.offsets, grid.widths, grid.normalized, phi)
                z = rng.standard_normal() if sigma > 0.0 else 0.0
                a_sup = heuristic_action(s[sim.X1], s[sim.Y1]) if p.supervised else 0.0
                a, a_rl = act(w, phi, sigma, z, z, a_sup, p)  # CACLA's policy: the fields it reads agree
            have_phi = False
            r = ep.decide(s, a, points, cum, ps, env_rng, dz, totals, poses, e, t)
            if not run.learn:
                continue
            ep.carry(book, visible, r, p.discount)
            if visible:
                phi, phi_pend = phi_pend, phi  # keep φ(s) for the update; no copy
                a_rl_p, a_sup_p = a_rl, a_sup
            if ep.due(book, s[sim.IN_VIEW] != 0.0, t == n - 1):
                grid_features(s[:4], grid.centres, grid.offsets, grid.widths, grid.normalized, phi_next)
                update(w, phi_pend, a_rl_p, a_sup_p, book[ep.ACC], book[ep.DISC], phi_next, p)
                book[ep.PENDING] = 0.0
                phi, phi_next = phi_next, phi  # φ(s') is the next decision's φ(s)
                have_phi = True
        ep.close_episode(stats, e, s, totals, n, decision_s)


def run_compiled(agent: ActorCritic, tracks, run, env_rng, dz, stats, poses) -> None:
    """:func:`episodes` for ``agent``."""
    episodes(agent.weights, records.pack(agent.params), tracks, run, ep.features_of(agent.grid), agent.rng,
             env_rng, dz, stats, poses)  # fmt: skip


def from_policy(data: dict, version: int, seed: int | None = None):
    """An agent and its weights from a policy file's arrays (CACLA's fields)."""
    return cacla.from_policy(data, version, seed, agent_class=ActorCritic, params_class=ActorCriticParams)


def make(
    r,
    rng: np.random.Generator | None = None,
    *,
    supervised: bool = False,
    actor_update: str = "delta",
    **fields,
) -> ActorCritic:
    """A fresh actor-critic under the readings ``r`` (fields: those of ``CaclaParams`` but the skew's).

    ``actor_update``: ``delta`` (eq. 9), ``positive`` or ``sign`` (:func:`step_factor`).

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
    options=frozenset({"supervised", "actor_update"}),
    step_sizes=cacla.LEARNER.step_sizes,
    make=make,
    check=cacla.check_compiled,
    run=run_compiled,
    policy_fields=cacla.policy_fields,
    from_policy=from_policy,
)
