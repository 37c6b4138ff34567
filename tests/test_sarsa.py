"""SARSA (eq. 3) against a hand-computed step, the separable Q, and learning a small task."""

import numpy as np
import pytest

from pipefollow.learners import sarsa
from pipefollow.learners.rbf import ACTION_GRID, STATE_GRID, RBFGrid
from pipefollow.learners.sarsa import Sarsa, SarsaParams
from pipefollow.training.agents import make_agent


def test_update_matches_hand_computation():
    W = np.array([[1.0, 0.0], [0.5, -1.0], [0.0, 2.0]]).T.copy()  # (action × state) features
    phi = np.array([0.2, 0.3, 0.5])
    psi = np.array([0.75, 0.25])
    phi_n = np.array([0.0, 1.0, 0.0])
    psi_n = np.array([0.5, 0.5])
    # Q(s,a) = Σ W_ji ψ_j φ_i: Wφ = [0.35, 0.7]; · ψ = 0.2625 + 0.175 = 0.4375
    # Q(s',a') = [0.5, -1] · ψ' = -0.25; δ = 1 + 0.8·(−0.25) − 0.4375 = 0.3625
    W0 = W.copy()
    delta = sarsa.update(W, phi, psi, 1.0, 0.8, phi_n, psi_n, 0.4)
    assert delta == pytest.approx(0.3625)
    np.testing.assert_allclose(W, W0 + 0.4 * 0.3625 * np.outer(psi, phi))


def test_separable_q_equals_the_full_22932_feature_product():
    rng = np.random.default_rng(0)
    agent = Sarsa(rng=rng)
    agent.weights[:] = rng.normal(size=agent.weights.shape)
    obs = np.array([0.3, 1.7, -0.4, 0.2])
    phi = STATE_GRID.features(obs)
    for a, q in zip(agent.search_actions, agent.q_values(obs), strict=True):
        full = np.kron(phi, ACTION_GRID.features(np.array([a])))  # the 22,932 features
        assert full.size == 22932
        assert q == pytest.approx(full @ agent.weights.T.ravel(), rel=1e-12)


def test_greedy_picks_best_grid_action_and_exploration_is_clipped_not_snapped():
    agent = Sarsa(seed=0)
    agent.weights[12, :] = 1.0  # action centre +90°: Q largest at a = 1
    obs = np.array([0.0, 1.5, 0.0, 0.2])
    assert agent.act(obs, explore=False) == pytest.approx(1.0)
    phi = agent.features(obs)
    a = sarsa.choose(agent.weights, phi, agent.search_actions, agent.search_psi, 0.3, -0.5)
    assert a == pytest.approx(0.85)  # 1 − 0.15, not snapped to the 9° grid
    assert sarsa.choose(agent.weights, phi, agent.search_actions, agent.search_psi, 0.3, 2.0) == 1.0
    assert len(agent.search_actions) == 21
    np.testing.assert_allclose(np.diff(agent.search_actions) * 90, 9.0)


def test_update_chooses_next_action_that_act_then_returns():
    agent = Sarsa(seed=5)
    s, s2 = np.array([0.1, 2.0, 0.0, 0.1]), np.array([0.2, 2.5, 0.1, 0.2])
    a = agent.act(s)
    agent.update(s, a, -0.5, s2, 0.8)
    pending = agent._pending[2]
    assert agent.act(s2) == pending


def test_learns_a_one_step_task():
    grid = RBFGrid((np.linspace(-1.0, 1.0, 9),))
    agent = Sarsa(SarsaParams(alpha=0.4), grid=grid, seed=2)
    rng = np.random.default_rng(1)
    steps = 6000
    for t in range(steps):
        agent.begin_episode(max(0.05, 0.6 * (1 - t / steps)))
        x = np.array([rng.uniform(-1, 1)])
        a = agent.act(x)
        agent.update(x, a, -((a - 0.5 * x[0]) ** 2), x, 0.0)
    xs = np.linspace(-0.9, 0.9, 19)
    err = max(abs(agent.act(np.array([x]), explore=False) - 0.5 * x) for x in xs)
    assert err <= 0.1 + 1e-9  # the one-step search resolves 0.1 (9°)


def test_same_seed_gives_identical_weights():
    from pipefollow.sim.pipeline import builtin
    from pipefollow.training.compiled import train_compiled

    ws = []
    for _ in range(2):
        agent = make_agent("sarsa", rng=np.random.default_rng(4))
        train_compiled(agent, builtin("paper-left"), 10)
        ws.append(agent.weights.copy())
    np.testing.assert_array_equal(ws[0], ws[1])
