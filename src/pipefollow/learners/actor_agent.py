"""What the actor-critic learners (CACLA, the general actor-critic) share: the actor's step, one agent class.

The two differ in the actor's step factor on (a − A(s)) only (paper §2.1; :func:`step_factor`).
:class:`ActorAgent` holds the weights (rows :data:`V`, :data:`A`, :data:`G`, :data:`K`: critic,
actor mean, skew, supervisor trust), draws the exploration's standard normals, caches the features
of the last update's next state (the usual next action's state) and calls its learner's compiled
entry points, so the agent and the compiled loops run the very same code.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numba import njit

from pipefollow.learners.heuristic import heuristic_action
from pipefollow.learners.protocol import Agent
from pipefollow.learners.rbf import STATE_GRID, RBFGrid
from pipefollow.learners.sums import dot

V, A, G, K = 0, 1, 2, 3  # rows of the weight matrix: critic, actor, skew, supervisor trust

# The actor's step factor on (a − A(s)) (paper §2.1): eq. 9's δ; max(δ, 0), eq. 7's max term alone;
# sgn(δ), its sign term alone; both terms, max(sgn δ, 0): CACLA's eq. 7, no step at all when δ ≤ 0.
DELTA, POSITIVE, SIGN, SIGN_AND_MAX = 0, 1, 2, 3


@njit(cache=True)
def clip1(x):
    """Clip to the action range [-1, 1]."""
    return min(1.0, max(-1.0, x))


@njit(cache=True)
def step_factor(delta, rule):
    """The actor's factor on (a − A(s)) under ``rule``: δ, max(δ, 0), sgn(δ) or max(sgn δ, 0)."""
    if rule == POSITIVE:
        return max(delta, 0.0)
    if rule == SIGN:
        return float(np.sign(delta))
    if rule == SIGN_AND_MAX:
        return 1.0 if delta > 0.0 else 0.0
    return delta


class ActorAgent(Agent):
    """An agent with a critic and a linear actor on RBF features; any Gymnasium env with a Box observation.

    A subclass names its learner (``algorithm``), its label (``name``), its parameter record, the
    actor's step (``rule(params)``, a code of :func:`step_factor`) and its compiled entry points:
    ``pack`` (record → array), ``act_packed`` and ``act_heuristic_packed`` (the policy),
    ``update_packed`` and ``update_next_packed`` (the update, taking the step's code and the running
    variance of δ, ``td_var``, that CACLA+Var updates, and the critic's TD(λ) trace ``critic_trace``).

    Args:
        params: step sizes and options (a record with ``discount``, ``supervised`` and ``skew``).
        grid: the RBF grid of the observation (default: the paper's 1,764-feature grid).
        rng: generator for exploration noise (or ``seed``).
        supervisor: ``obs -> a_sup`` for a supervised agent (default: the paper's heuristic).
    """

    algorithm = ""

    def __init__(
        self,
        params,
        grid: RBFGrid = STATE_GRID,
        rng: np.random.Generator | None = None,
        seed: int | None = None,
        supervisor: Callable[[np.ndarray], float] | None = None,
    ) -> None:
        super().__init__(params, grid, rng, seed)
        self.weights = np.zeros((4, grid.n_features))
        self.td_var = np.ones(1)  # running variance of δ of CACLA+Var (var_0 = 1), updated in place
        self.critic_trace = np.zeros(grid.n_features)  # the critic's TD(λ) trace, zero at an episode's start
        self._packed = self.pack(params)
        self._rule = self.rule(params)
        self._draws = 2 if params.skew > 0.0 else 1  # skew-normal samples take two standard normals
        self.default_supervisor = supervisor is None  # the compiled training loop knows only this one
        if supervisor is None:

            def supervisor(obs):
                return heuristic_action(float(obs[0]), float(obs[1]))

        self.supervisor = supervisor
        self._phi_cache: tuple[bytes, np.ndarray] | None = None  # φ(s') of the last update

    def begin_episode(self, sigma: float) -> None:
        """Set the exploration σ for the coming episode; forget any pending action and the critic's trace."""
        super().begin_episode(sigma)
        self.critic_trace[:] = 0.0

    @property
    def supervised(self) -> bool:
        """Whether a supervisor shares the actions (eq. 10)."""
        return bool(self.params.supervised)

    def _cached_features(self, obs, key: bytes) -> np.ndarray:
        """φ(obs), reusing φ(s') of the last update when ``obs`` is that s' (the usual case)."""
        cache = self._phi_cache
        if cache is not None and cache[0] == key:
            return cache[1]
        phi = self.features(obs)
        self._phi_cache = (key, phi)
        return phi

    def act(self, obs, explore: bool = True) -> float:
        """Executed action for ``obs``; with ``explore`` it samples with the current ``sigma``."""
        key = _key(obs)
        phi = self._cached_features(obs, key)
        sigma = self.sigma if explore else 0.0
        z0 = z1 = 0.0
        if sigma > 0.0:
            z0 = z1 = self.rng.standard_normal()
            if self._draws == 2:
                z1 = self.rng.standard_normal()
        if self.default_supervisor:
            x = np.asarray(obs, dtype=np.float64)
            a, a_rl, a_sup = self.act_heuristic_packed(
                self.weights, phi, sigma, z0, z1, x[0], x[1], self._packed
            )
        else:
            a_sup = self.supervisor(obs) if self.params.supervised else 0.0
            a, a_rl = self.act_packed(self.weights, phi, sigma, z0, z1, a_sup, self._packed)
        self._pending = (key, phi, a_rl, a_sup)
        return a

    def actor(self, obs) -> float:
        """The pure actor's deterministic action clip(A(s)), without the supervisor."""
        return clip1(dot(self.weights[A], self.features(obs)))

    def update(self, obs, action, reward: float, next_obs, discount: float) -> float:
        """Learn from ``obs`` → ``next_obs``; ``discount`` is γ_d^n (0 if terminal). Returns δ.

        Uses the learner's own action of the last :meth:`act` call on ``obs``; without one,
        ``action`` is taken as the learner's action.
        """
        key = _key(obs)
        if self._pending is not None and self._pending[0] == key:
            _, phi, a_rl, a_sup = self._pending
        else:
            phi = self._cached_features(obs, key)
            a_rl = float(action)
            a_sup = self.supervisor(obs) if self.params.supervised else 0.0
        self._pending = None
        next_obs = np.asarray(next_obs, dtype=np.float64)
        next_key = next_obs.tobytes()
        cache = self._phi_cache
        w, r, d, hp, rule = self.weights, float(reward), float(discount), self._packed, self._rule
        if cache is not None and cache[0] == next_key:
            return self.update_packed(
                w, phi, a_rl, a_sup, r, d, cache[1], hp, rule, self.td_var, self.critic_trace
            )
        if next_obs.shape != (self.grid.ndim,):
            raise ValueError(f"next_obs must have {self.grid.ndim} entries, got shape {next_obs.shape}")
        phi_next = np.empty(self.grid.n_features)
        grid, normalized = self.grid.packed, self.grid.form == "normalized"
        state = (self.td_var, self.critic_trace)
        delta, finite = self.update_next_packed(w, phi, a_rl, a_sup, r, d, next_obs, grid, normalized,
                                                phi_next, hp, rule, *state)  # fmt: skip
        if not finite:
            raise ValueError(f"next_obs must be finite, got {next_obs}")
        self._phi_cache = (next_key, phi_next)
        return delta


def _key(obs) -> bytes:
    """An observation's identity for the caches: its float64 bytes."""
    return np.asarray(obs, dtype=np.float64).tobytes()
