"""Continuous-state SARSA (eq. 3) with a one-step search over the actions (Santamaría et al.).

``Q(s, a) = Σ_ij W_ij φ_i(s) ψ_j(a)`` is linear in the 1,764 × 13 = 22,932 products of the RBF state
features φ and the action features ψ (paper §4.1). Because the features separate, Q over all
actions of the search grid costs one product ``q = Wφ`` (13 numbers) and a 21 × 13 product,
not 21 × 22,932 multiplications. The greedy action is the best of the 21-point grid −90°…90° in
9° steps; exploration adds σ·N(0, 1) to it (clipped, not snapped back to the grid).
"""

from __future__ import annotations

import json
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.learners.episodes import features_of
from pipefollow.learners.protocol import Agent, LearnerKind
from pipefollow.learners.rbf import (
    ACTION_GRID,
    STATE_GRID,
    RBFGrid,
    dim_activations,
    grid_features,
)
from pipefollow.learners.sums import dot, matvec
from pipefollow.sim import decision as sim
from pipefollow.sim import episode as ep
from pipefollow.sim.observation import observe


class SarsaParams(NamedTuple):
    """SARSA's step size, discount and search grid (paper §4, §4.1)."""

    alpha: float = 0.4  # step size α (paper §4)
    discount: float = 0.8  # discount factor γ_d (paper §4)
    n_search: int = 21  # actions of the one-step search: −90°…90° in 9° steps (paper §4.1)


PAPER_SARSA = SarsaParams()


@njit(cache=True)
def action_features(a, centres, width, normalized):
    """ψ(a): the action dimension's RBF activations."""
    out = np.empty(centres.shape[0])
    dim_activations(a, centres, width, normalized, out)
    return out


def search_table(p: SarsaParams, grid: RBFGrid = ACTION_GRID) -> tuple[np.ndarray, np.ndarray]:
    """The search grid's actions and their action features (n_search × n_action_features)."""
    actions = np.linspace(-1.0, 1.0, p.n_search)
    psi = np.array([grid.features(np.array([a])) for a in actions])
    return actions, psi


@njit(cache=True)
def greedy(W, phi, search_actions, search_psi):
    """Greedy action of the one-step search, and the action-weight vector ``q_j = W_j·φ``.

    Ties (e.g. untrained weights) go to the action nearest straight ahead, not to −90°.
    """
    q = matvec(W, phi)
    values = matvec(search_psi, q)
    best = 0
    for k in range(1, values.shape[0]):
        if values[k] > values[best] or (
            values[k] == values[best] and abs(search_actions[k]) < abs(search_actions[best])
        ):
            best = k
    return search_actions[best], q


@njit(cache=True)
def choose_with_q(W, phi, search_actions, search_psi, sigma, z):
    """Exploring action ``clip(greedy + σ z)`` (σ = 0: greedy), and ``q = Wφ`` it was chosen on."""
    a, q = greedy(W, phi, search_actions, search_psi)
    if sigma > 0.0:
        a = min(1.0, max(-1.0, a + sigma * z))
    return a, q


@njit(cache=True)
def choose(W, phi, search_actions, search_psi, sigma, z):
    """Exploring action ``clip(greedy + σ z)`` (σ = 0: greedy)."""
    return choose_with_q(W, phi, search_actions, search_psi, sigma, z)[0]


@njit(cache=True)
def update(W, phi, psi, reward, discount, phi_next, psi_next, alpha):
    """Eq. 3: ``W += α δ ψ φᵀ`` with ``δ = r + discount·Q(s', a') − Q(s, a)``. Returns δ.

    ``W`` is (action features × state features): row j holds the weights of action centre j.
    """
    return update_on(W, phi, psi, reward, discount, matvec(W, phi_next), psi_next, alpha)


@njit(cache=True)
def update_on(W, phi, psi, reward, discount, q_next, psi_next, alpha):
    """:func:`update` with ``q_next = W φ(s')`` given (the compiled loop has it from choosing a')."""
    q_sa = dot(psi, matvec(W, phi))
    v_next = dot(psi_next, q_next) if discount != 0.0 else 0.0
    delta = reward + discount * v_next - q_sa
    c = alpha * delta
    for j in range(psi.shape[0]):
        cj = c * psi[j]
        if cj != 0.0:
            for i in range(phi.shape[0]):
                W[j, i] += cj * phi[i]
    return delta


class Sarsa(Agent):
    """A SARSA agent on RBF state × action features.

    It works on any environment with a Box observation and a 1-D action in [-1, 1].

    The update picks the next action a' (on-policy, with the current σ) and :meth:`act` then
    returns that same action for that observation, as SARSA requires.
    """

    def __init__(
        self,
        params: SarsaParams = PAPER_SARSA,
        grid: RBFGrid = STATE_GRID,
        action_grid: RBFGrid = ACTION_GRID,
        rng: np.random.Generator | None = None,
        seed: int | None = None,
    ) -> None:
        super().__init__(params, grid, rng, seed)
        self.action_grid = action_grid
        # Q(s, a) = Σ_ji W_ji ψ_j(a) φ_i(s): one row of state weights per action centre
        self.weights = np.zeros((action_grid.n_features, grid.n_features))
        self.search_actions, self.search_psi = search_table(params, action_grid)
        ac, _, aw = action_grid.packed
        self._action_centres, self._action_width = ac, float(aw[0])
        self._action_normalized = action_grid.form == "normalized"

    algorithm = "sarsa"
    name = "SARSA"
    supervised = False

    def _psi(self, a: float) -> np.ndarray:
        return action_features(a, self._action_centres, self._action_width, self._action_normalized)

    def _choose(self, phi: np.ndarray, explore: bool) -> tuple[float, np.ndarray]:
        """The action for features ``phi`` and the ``W φ`` it was chosen on."""
        sigma = self.sigma if explore else 0.0
        z = self.rng.standard_normal() if sigma > 0.0 else 0.0
        return choose_with_q(self.weights, phi, self.search_actions, self.search_psi, sigma, z)

    def act(self, obs, explore: bool = True) -> float:
        """The action for ``obs``: the pending on-policy action if the last update chose one."""
        obs = np.asarray(obs, dtype=np.float64)
        if explore and self._pending is not None and np.array_equal(self._pending[0], obs):
            return self._pending[2]
        phi = self.features(obs)
        a, _ = self._choose(phi, explore)
        self._pending = (obs.copy(), phi, a) if explore else None
        return a

    def q_values(self, obs) -> np.ndarray:
        """Q(obs, a) over the search grid."""
        return matvec(self.search_psi, matvec(self.weights, self.features(obs)))

    def update(self, obs, action, reward: float, next_obs, discount: float) -> float:
        """Eq. 3 for ``obs, action → next_obs``; chooses a' at ``next_obs``. Returns δ."""
        obs = np.asarray(obs, dtype=np.float64)
        if self._pending is not None and np.array_equal(self._pending[0], obs):
            phi = self._pending[1]
        else:
            phi = self.features(obs)
        next_obs = np.asarray(next_obs, dtype=np.float64)
        phi_next = self.features(next_obs)
        if discount != 0.0:  # W φ(s') of choosing a' is the one the update needs, as in the compiled loop
            a_next, q_next = self._choose(phi_next, True)
        else:
            a_next, q_next = 0.0, np.zeros(self.weights.shape[0])
        delta = update_on(
            self.weights,
            phi,
            self._psi(float(action)),
            float(reward),
            float(discount),
            q_next,
            self._psi(a_next),
            self.params.alpha,
        )
        self._pending = (next_obs.copy(), phi_next, a_next)
        return delta


# ---------------------------------------------------------------------------------------------
# The compiled episodes (the protocol of pipefollow.sim.episode) and what the layers above need


class ActionSearch(NamedTuple):
    """SARSA's action side, grouped for the compiled loop: the search grid and the action features."""

    actions: np.ndarray  # (n_search,) actions of the one-step search
    psi: np.ndarray  # (n_search, action features) their features
    centres: np.ndarray  # action centres
    width: float  # their width
    normalized: bool  # the action grid's form


@njit(cache=True)
def episodes(W, alpha, discount, search, tracks, run, grid, rng, env_rng, dz, stats, poses):
    """SARSA's episodes in compiled code: the same numbers as its agent in the environment."""
    ps = sim.unpack_params(run.sim)
    decision_s = sim.decision_seconds(ps)
    nf = W.shape[1]
    s = np.empty(sim.STATE_SIZE)
    obs = np.empty(grid.slots.shape[0])  # the observation (pipefollow.sim.observation)
    phi, phi_pend, phi_next = np.empty(nf), np.empty(nf), np.empty(nf)
    psi, psi_next = np.empty(search.centres.shape[0]), np.empty(search.centres.shape[0])
    book = np.empty(ep.BOOK_SIZE)
    n = run.n_decisions
    for e in range(run.sigmas.shape[0]):
        sigma = run.sigmas[e]
        points, cum, start = ep.pipe_of(tracks, e)
        ep.start_episode(s, points, cum, start, ps, env_rng, dz, book, poses, e)
        has_next = False  # an on-policy action chosen by the last update for the current state
        a_next = a_p = 0.0
        for _ in range(n):
            visible = s[sim.IN_VIEW] != 0.0
            a = 0.0
            if visible:
                if has_next:
                    a = a_next
                    phi[:] = phi_next
                    has_next = False
                else:
                    observe(s, grid.slots, obs)
                    grid_features(obs, grid.centres, grid.offsets, grid.widths, grid.normalized, phi)
                    z = rng.standard_normal() if sigma > 0.0 else 0.0
                    a = choose(W, phi, search.actions, search.psi, sigma, z)
            r = ep.draw_and_decide(s, a, points, cum, ps, env_rng, dz, book, poses, e)
            end = ep.end_of(book, s, cum, ps, n)
            if run.learn:
                ep.carry(book, visible, r, discount)
                if visible:
                    phi_pend[:] = phi
                    a_p = a
                if ep.due(book, s[sim.IN_VIEW] != 0.0, end != ep.GOES_ON):
                    observe(s, grid.slots, obs)
                    grid_features(obs, grid.centres, grid.offsets, grid.widths, grid.normalized, phi_next)
                    z = rng.standard_normal() if sigma > 0.0 else 0.0
                    # W φ(s') of choosing a' is the one the update needs: W has not moved in between
                    a_next, q_next = choose_with_q(W, phi_next, search.actions, search.psi, sigma, z)
                    has_next = True
                    dim_activations(a_p, search.centres, search.width, search.normalized, psi)
                    dim_activations(a_next, search.centres, search.width, search.normalized, psi_next)
                    disc = ep.bootstrap(book, end)
                    update_on(W, phi_pend, psi, book[ep.ACC], disc, q_next, psi_next, alpha)
                    book[ep.PENDING] = 0.0
            if end == ep.PIPE_END:
                break
        ep.hold_poses(poses, e, book)
        ep.close_episode(stats, e, book, s[sim.PROGRESS_MAX], decision_s)


def check_compiled(agent: Sarsa) -> None:
    """Every SARSA agent runs in the compiled loop."""


def run_compiled(agent: Sarsa, tracks, run, env_rng, dz, stats, poses) -> None:
    """:func:`episodes` for ``agent``."""
    search = ActionSearch(agent.search_actions, agent.search_psi, agent._action_centres, agent._action_width,
                          agent._action_normalized)  # fmt: skip
    p = agent.params
    grid = features_of(agent.grid, agent.state)
    episodes(agent.weights, p.alpha, p.discount, search, tracks, run, grid, agent.rng, env_rng, dz, stats,
             poses)  # fmt: skip


def policy_fields(agent: Sarsa) -> dict:
    """The arrays of a policy file: parameters, state and action grids as JSON, the weights."""
    return {
        "params": np.array(json.dumps(agent.params._asdict())),
        "grid": np.array(json.dumps(agent.grid.to_dict())),
        "action_grid": np.array(json.dumps(agent.action_grid.to_dict())),
        "weights": agent.weights,
    }


def from_policy(data: dict, seed: int | None = None):
    """An agent and its weights from a policy file's arrays (see :func:`policy_fields`)."""
    params = json.loads(str(data["params"]))
    grid = RBFGrid.from_dict(json.loads(str(data["grid"])))
    weights = np.asarray(data["weights"], dtype=np.float64)
    action = RBFGrid.from_dict(json.loads(str(data["action_grid"])))
    agent = Sarsa(SarsaParams(**params), grid=grid, action_grid=action, seed=seed)
    agent.readings = str(data.get("readings", "default"))
    return agent, weights


def make(params: SarsaParams, grid: RBFGrid, action_grid: RBFGrid, rng: np.random.Generator | None = None, *,
         readings: str = "default") -> Sarsa:  # fmt: skip
    """A fresh SARSA agent with ``params`` on its state and action grids, under the readings ``readings``."""
    agent = Sarsa(params, grid=grid, action_grid=action_grid, rng=rng)
    agent.readings = readings
    return agent


LEARNER = LearnerKind(
    name="sarsa",
    title="SARSA",
    summary="SARSA with a one-step search over 21 actions (eq. 3)",
    agent_class=Sarsa,
    options=frozenset(),
    step_sizes={"alpha_q": "alpha", "discount": "discount"},
    make=make,
    check=check_compiled,
    run=run_compiled,
    policy_fields=policy_fields,
    from_policy=from_policy,
)
