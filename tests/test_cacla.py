"""CACLA's update equations against hand-computed single steps, and learning a small task."""

import math

import numpy as np
import pytest

from pipefollow.learners import cacla, cacla_act, cacla_update
from pipefollow.learners.cacla import Cacla
from pipefollow.learners.cacla_act import CaclaParams
from pipefollow.learners.cacla_update import A, G, K, V
from pipefollow.learners.exploration import skew_normal_from_normals
from pipefollow.learners.rbf import RBFGrid
from pipefollow.sim.pipeline import builtin
from pipefollow.training.agents import make_agent
from pipefollow.training.compiled import train_compiled

PHI = np.array([0.2, 0.5, 0.3])
PHI_NEXT = np.array([0.0, 0.4, 0.6])


def weights():
    w = np.zeros((4, 3))
    w[V] = [1.0, -2.0, 0.5]  # V(s) = 0.2 - 1.0 + 0.15 = -0.65; V(s') = -0.8 + 0.3 = -0.5
    w[A] = [0.5, 0.1, -0.2]  # A(s) = 0.1 + 0.05 - 0.06 = 0.09
    return w


def test_critic_and_actor_update_when_td_error_positive():
    w = weights()
    p = CaclaParams()
    delta = cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, p)
    # δ = r + γ V(s') − V(s) = 0.3 + 0.8·(−0.5) + 0.65 = 0.55
    assert delta == pytest.approx(0.55)
    np.testing.assert_allclose(w[V], weights()[V] + 0.4 * 0.55 * PHI)
    # actor moves towards the action taken: α_π (a − A(s)) φ = 0.2 · (0.6 − 0.09) φ
    np.testing.assert_allclose(w[A], weights()[A] + 0.2 * 0.51 * PHI)


def test_actor_unchanged_when_td_error_not_positive():
    w = weights()
    delta = cacla.update(w, PHI, 0.6, 0.0, -1.0, 0.8, PHI_NEXT, CaclaParams())
    assert delta == pytest.approx(-1.0 - 0.4 + 0.65)
    np.testing.assert_array_equal(w[A], weights()[A])
    np.testing.assert_allclose(w[V], weights()[V] + 0.4 * delta * PHI)


NORM2 = 0.2**2 + 0.5**2 + 0.3**2  # ‖φ‖² = 0.38


def test_skew_update_moves_gamma_itself_by_the_step_by_default():
    p = CaclaParams(skew=0.5)
    assert p.skew_step == cacla_update.STEP_GAMMA
    # δ > 0 and a > A(s): w_γ += Δγ φ/‖φ‖², so γ(s) = w_γ·φ grows by exactly Δγ = 0.5
    w = weights()
    cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, p)
    np.testing.assert_allclose(w[G], [0.1 / 0.38, 0.25 / 0.38, 0.15 / 0.38])
    assert w[G] @ PHI == pytest.approx(0.5)
    # δ < 0 and a > A(s): γ(s) falls by Δγ
    w = weights()
    cacla.update(w, PHI, 0.6, 0.0, -1.0, 0.8, PHI_NEXT, p)
    assert w[G] @ PHI == pytest.approx(-0.5)
    # from γ(s) = 0.75 < γ_max = 1 one more step is made (to 1.25; clipped where it is used) ...
    w = weights()
    w[G] = 0.75 * PHI / NORM2
    cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, p)
    assert w[G] @ PHI == pytest.approx(1.25)
    # ... and none past it
    before = w[G].copy()
    cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, p)
    np.testing.assert_array_equal(w[G], before)


def test_skew_update_sign_and_cap_with_the_weights_step():
    p = CaclaParams(skew=0.5, skew_step=cacla_update.STEP_WEIGHTS)
    # δ > 0 and a > A(s): the weights grow by Δγ φ, so γ(s) by Δγ‖φ‖² = 0.19
    w = weights()
    cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, p)
    np.testing.assert_allclose(w[G], 0.5 * PHI)
    assert w[G] @ PHI == pytest.approx(0.19)
    # δ > 0 and a < A(s): γ shrinks
    w = weights()
    cacla.update(w, PHI, -0.6, 0.0, 0.3, 0.8, PHI_NEXT, p)
    np.testing.assert_allclose(w[G], -0.5 * PHI)
    # δ < 0 and a > A(s): γ shrinks (explore away from the punished side)
    w = weights()
    cacla.update(w, PHI, 0.6, 0.0, -1.0, 0.8, PHI_NEXT, p)
    np.testing.assert_allclose(w[G], -0.5 * PHI)
    # at the cap γ(s) ≥ γ_max no further increase
    w = weights()
    w[G] = [2.0, 2.0, 2.0]  # γ(s) = 2 > 1
    cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, p)
    np.testing.assert_array_equal(w[G], [2.0, 2.0, 2.0])
    # ... but a decrease is still allowed
    cacla.update(w, PHI, -0.6, 0.0, 0.3, 0.8, PHI_NEXT, p)
    np.testing.assert_allclose(w[G], 2.0 - 0.5 * PHI)


def test_k_update_readings():
    w = weights()
    cacla.update(w, PHI, 0.6, 0.0, -1.0, 0.8, PHI_NEXT, CaclaParams(supervised=True))  # δ < 0
    np.testing.assert_allclose(w[K], 0.05 * PHI)  # every visit (default): w_k += Δk φ
    w = weights()
    p = CaclaParams(supervised=True, k_update=cacla_update.K_POSITIVE)
    cacla.update(w, PHI, 0.6, 0.0, -1.0, 0.8, PHI_NEXT, p)
    np.testing.assert_array_equal(w[K], 0.0)  # only when δ > 0
    cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, p)  # δ = 0.55
    np.testing.assert_allclose(w[K], 0.05 * PHI)
    w = weights()
    p = CaclaParams(supervised=True, k_step=cacla_update.STEP_GAMMA)
    cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, p)
    assert w[K] @ PHI == pytest.approx(0.05)  # k(s) itself moves by Δk


def test_supervised_actor_target_mixes_rl_and_supervisor_and_k_grows_to_cap():
    p = CaclaParams(supervised=True)
    w = weights()
    w[K] = [0.5, 0.5, 0.5]  # k(s) = 0.5
    a_rl, a_sup = 0.6, -0.4
    cacla.update(w, PHI, a_rl, a_sup, 0.3, 0.8, PHI_NEXT, p)  # δ = 0.55 > 0
    mu = 0.09
    expected = 0.2 * (0.5 * (a_rl - mu) + 0.5 * (a_sup - mu))  # eq. 12
    np.testing.assert_allclose(w[A], weights()[A] + expected * PHI)
    np.testing.assert_allclose(w[K], 0.5 + 0.05 * PHI)  # eq. 13: Δk = 0.05
    # δ ≤ 0: only the supervised part
    w = weights()
    w[K] = [0.5, 0.5, 0.5]
    cacla.update(w, PHI, a_rl, a_sup, -1.0, 0.8, PHI_NEXT, p)
    np.testing.assert_allclose(w[A], weights()[A] + 0.2 * 0.5 * (a_sup - mu) * PHI)
    # k(s) at the cap: no increment
    w = weights()
    w[K] = [1.0, 1.0, 1.0]
    cacla.update(w, PHI, a_rl, a_sup, 0.3, 0.8, PHI_NEXT, p)
    np.testing.assert_array_equal(w[K], [1.0, 1.0, 1.0])


def test_k_starts_at_zero_so_the_supervisor_acts_alone():
    w = weights()
    a, a_rl = cacla_act.act(w, PHI, 0.5, 1.3, 0.0, -0.7, CaclaParams(supervised=True))
    assert a == pytest.approx(-0.7)
    assert a_rl == pytest.approx(min(1.0, 0.09 + 0.5 * 1.3))


def test_act_gaussian_skew_and_deterministic():
    w = weights()
    p = CaclaParams()
    assert cacla_act.act(w, PHI, 0.0, 5.0, 5.0, 0.0, p)[0] == pytest.approx(0.09)  # σ = 0
    assert cacla_act.act(w, PHI, 0.2, -0.5, 9.0, 0.0, p)[0] == pytest.approx(0.09 - 0.1)
    assert cacla_act.act(w, PHI, 1.0, 3.0, 0.0, 0.0, p)[0] == 1.0  # clipped
    ps = CaclaParams(skew=0.5)
    w[G] = [1.0, 1.0, 1.0]  # γ(s) = 1
    z = skew_normal_from_normals(1.0, -0.4, 0.3)
    assert cacla_act.act(w, PHI, 0.2, -0.4, 0.3, 0.0, ps)[0] == pytest.approx(0.09 + 0.2 * z)


def test_semi_markov_discount_is_used_for_bootstrap():
    w = weights()
    delta = cacla.update(w, PHI, 0.0, 0.0, -10.0 - 8.0, 0.8**3, PHI_NEXT, CaclaParams())
    assert delta == pytest.approx(-18.0 + 0.512 * -0.5 + 0.65)


class Bandit:
    """One-step task: observe x ∈ [-1, 1], reward −(a − 0.5 x)²."""

    def __init__(self, seed):
        self.rng = np.random.default_rng(seed)

    def sample(self):
        return np.array([self.rng.uniform(-1, 1)])

    @staticmethod
    def reward(x, a):
        return -((a - 0.5 * x[0]) ** 2)


GRID_1D = RBFGrid((np.linspace(-1.0, 1.0, 9),))


def _learn_bandit(agent, steps=4000, seed=0):
    task = Bandit(seed)
    for t in range(steps):
        agent.begin_episode(max(0.05, 0.5 * (1 - t / steps)))
        x = task.sample()
        a = agent.act(x)
        agent.update(x, a, task.reward(x, a), x, 0.0)
    xs = np.linspace(-0.9, 0.9, 19)
    return max(abs(agent.act(np.array([x]), explore=False) - 0.5 * x) for x in xs)


@pytest.mark.parametrize(
    "params",
    [
        CaclaParams(),
        CaclaParams(skew=0.5),
        CaclaParams(supervised=True),
        CaclaParams(skew=0.25, supervised=True),
    ],
    ids=["cacla", "skew", "supervised", "supervised-skew"],
)
def test_learns_a_one_step_task(params):
    # supervisor deliberately imperfect: the learned action must still approach the optimum
    agent = Cacla(params, grid=GRID_1D, seed=3, supervisor=lambda x: 0.3 * x[0])
    err = _learn_bandit(agent)
    assert err < 0.1


def test_same_seed_gives_identical_weights():
    pipe = builtin("paper-left")
    runs = []
    for _ in range(2):
        agent = make_agent("cacla", skew_deg=22.5, supervised=True, rng=np.random.default_rng(11))
        stats = train_compiled(agent, pipe, 15)
        runs.append((agent.weights.copy(), stats))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    assert np.abs(runs[0][0]).sum() > 0


def test_make_agent_validation():
    with pytest.raises(ValueError, match="algorithm"):
        make_agent("qlearning")
    with pytest.raises(ValueError, match="supervised applies to algorithm cacla and ac only"):
        make_agent("sarsa", supervised=True)
    with pytest.raises(ValueError, match="skew_deg applies to algorithm cacla only"):
        make_agent("ac", skew_deg=22.5)
    assert make_agent("cacla", skew_deg=22.5).params.skew == pytest.approx(0.5)
    assert math.isclose(make_agent("cacla", skew_deg=45).params.skew, 1.0)


DELTA1 = math.sqrt(0.5)  # δ of γ = 1
SHIFT1 = DELTA1 * math.sqrt(2 / math.pi)  # mean of SkewNormal(γ = 1)
SD1 = math.sqrt(1 - SHIFT1**2)


@pytest.mark.parametrize(
    "sample, mean, sd",
    [
        (cacla.SAMPLE_LOCATION, SHIFT1, SD1),  # the paper's location/scale form
        (cacla.SAMPLE_CENTRED, 0.0, SD1),
        (cacla.SAMPLE_MOMENTS, 0.0, 1.0),
    ],
)
def test_skew_sample_readings_mean_and_sd(sample, mean, sd):
    w = weights()
    w[G] = [1.0, 1.0, 1.0]  # γ(s) = 1 → δ = 1/√2
    p = CaclaParams(skew=0.5, skew_sample=sample)
    rng = np.random.default_rng(0)
    sigma = 0.05  # small enough that no sample is clipped
    z = np.array(
        [
            (cacla_act.act(w, PHI, sigma, *rng.standard_normal(2), 0.0, p)[1] - 0.09) / sigma
            for _ in range(20000)
        ]
    )
    assert z.mean() == pytest.approx(mean, abs=4 * z.std() / math.sqrt(z.size))
    assert z.std() == pytest.approx(sd, rel=0.03)


def test_update_for_another_observation_than_the_last_act_uses_that_observation():
    agent = Cacla(seed=0)
    s1, s2, s3 = (np.array([x, 1.5, 0.0, 0.2]) for x in (-0.5, 0.5, 0.0))
    agent.act(s1)
    agent.update(s2, 0.3, -1.0, s3, 0.8)  # out of order: must learn about s2, not s1
    phi2 = agent.features(s2)
    expected = np.zeros_like(agent.weights)
    delta = -1.0  # all weights were zero
    expected[V] = 0.4 * delta * phi2
    np.testing.assert_allclose(agent.weights, expected)


def test_skew_update_sign_uses_the_clipped_mean():
    p = CaclaParams(skew=0.5)
    w = weights()
    w[A] = [5.0, 5.0, 5.0]  # A(s) = 5: every sample clips to 1
    cacla.update(w, PHI, 1.0, 0.0, 0.3, 0.8, PHI_NEXT, p)  # δ > 0, sample at the clip
    np.testing.assert_array_equal(w[G], 0.0)  # no side to prefer


def test_non_finite_observations_are_refused_before_learning():
    agent = Cacla(seed=0)
    s = np.array([0.1, 1.5, 0.0, 0.2])
    agent.act(s)
    with pytest.raises(ValueError, match="finite"):
        agent.update(s, 0.0, -1.0, np.array([np.nan, 1.0, 0.0, 0.2]), 0.8)
    np.testing.assert_array_equal(agent.weights, 0.0)
    with pytest.raises(ValueError, match="finite"):
        agent.act(np.array([0.1, np.inf, 0.0, 0.2]))
