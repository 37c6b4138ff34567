"""Exploration noise (eqs. 8, 14) against scipy and the skew-normal's known moments.

The samples are the learners' own: a CACLA agent's exploring actions, its generator drawing the
standard normals as the compiled training loop does (tests/test_learner_contract.py checks that
the two paths give the same numbers).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy import integrate, stats

from pipefollow.learners.cacla import Cacla
from pipefollow.learners.cacla_act import CaclaParams
from pipefollow.learners.cacla_update import A, G
from pipefollow.learners.exploration import (
    linear_sigma,
    skew_normal_from_normals,
    skew_normal_pdf,
    skew_step_to_gamma,
)
from pipefollow.learners.sums import dot

N_SAMPLES = 100_000
OBS = np.array([0.3, 1.2, 0.1, -0.2])  # any state: A(s) and γ(s) are set through the weights


def exploring_cacla(mu: float, gamma: float | None, sigma: float, seed: int) -> tuple[Cacla, float, float]:
    """A CACLA agent whose actor gives ``mu`` and skew head ``gamma`` (None: Gaussian) at :data:`OBS`.

    Returns the agent (exploring with ``sigma``) and A(s), γ(s) as the agent computes them.
    """
    skewed = gamma is not None
    params = CaclaParams(skew=0.5 if skewed else 0.0, gamma_max=max(1.0, abs(gamma or 0.0)))
    agent = Cacla(params, rng=np.random.default_rng(seed))
    phi = agent.features(OBS)
    agent.weights[A] = mu / phi.sum()
    agent.weights[G] = (gamma or 0.0) / phi.sum()
    agent.begin_episode(sigma)
    return agent, dot(agent.weights[A], phi), dot(agent.weights[G], phi)


def draw_actions(agent: Cacla, n: int) -> np.ndarray:
    """``n`` exploring actions of ``agent`` at :data:`OBS`."""
    return np.array([agent.act(OBS) for _ in range(n)])


def draw_z(gamma: float | None, n: int = N_SAMPLES, seed: int = 12345) -> np.ndarray:
    """The exploration's standard sample ``z = (a − A(s))/σ`` of ``n`` unclipped actions."""
    sigma = 0.1  # |a| ≤ 1 unless z beyond ±9: no action is clipped
    agent, mu, _ = exploring_cacla(0.0, gamma, sigma, seed)
    return (draw_actions(agent, n) - mu) / sigma


def numpy_skew_normal_z(rng: np.random.Generator, gamma: float, n: int) -> np.ndarray:
    """The same sampler in plain NumPy: per sample u0 then v, in one interleaved stream."""
    u = rng.standard_normal(2 * n).reshape(n, 2)
    u0, v = u[:, 0], u[:, 1]
    delta = gamma / np.sqrt(1.0 + gamma**2)
    u1 = delta * u0 + np.sqrt(1.0 - delta**2) * v
    return np.where(u0 >= 0.0, u1, -u1)


# --- σ schedule -------------------------------------------------------------------------------


def test_linear_sigma_endpoints_and_midpoint():
    assert linear_sigma(0, 2001) == 1.0
    assert linear_sigma(2000, 2001) == 0.01
    assert linear_sigma(1000, 2001) == pytest.approx(0.505, abs=1e-15)
    assert linear_sigma(2, 5, 0.8, 0.2) == pytest.approx(0.5, abs=1e-15)
    assert linear_sigma(0, 1) == 1.0
    assert linear_sigma(0, 1, 0.3, 0.1) == 0.3


def test_linear_sigma_is_linear_and_decreasing():
    sig = np.array([linear_sigma(e, 11) for e in range(11)])
    assert_allclose(sig, np.linspace(1.0, 0.01, 11), rtol=0, atol=1e-15)
    assert np.all(np.diff(sig) < 0)


@pytest.mark.parametrize("episode, n", [(-1, 10), (10, 10), (0, 0)])
def test_linear_sigma_rejects_bad_episodes(episode, n):
    with pytest.raises(ValueError):
        linear_sigma(episode, n)


# --- density (eq. 14) -------------------------------------------------------------------------


@pytest.mark.parametrize(
    "mu, sigma, gamma",
    [(0.0, 1.0, 0.0), (0.0, 1.0, 0.5), (0.3, 0.2, -1.0), (-0.5, 2.0, 3.0), (0.1, 0.05, -0.25)],
)
def test_pdf_integrates_to_one(mu, sigma, gamma):
    lo, hi = mu - 40 * sigma, mu + 40 * sigma
    total, err = integrate.quad(skew_normal_pdf, lo, hi, args=(mu, sigma, gamma), points=[mu], limit=200)
    assert total == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize(
    "mu, sigma, gamma",
    [(0.0, 1.0, 0.0), (0.0, 1.0, 0.5), (0.3, 0.2, -1.0), (-0.5, 2.0, 3.0), (0.1, 0.05, -0.25)],
)
def test_pdf_equals_scipy_skewnorm(mu, sigma, gamma):
    x = np.linspace(mu - 6 * sigma, mu + 6 * sigma, 101)
    expected = stats.skewnorm.pdf(x, a=gamma, loc=mu, scale=sigma)
    assert_allclose(skew_normal_pdf(x, mu, sigma, gamma), expected, rtol=1e-12, atol=1e-300)


def test_pdf_formula_as_printed():
    # eq. 14 with the integral done by quad: 1/(σπ) e^{−(x−μ)²/(2σ²)} ∫_{−∞}^{γ(x−μ)/σ} e^{−t²/2} dt
    mu, sigma, gamma, x = 0.2, 0.6, 1.5, 0.05
    integral, _ = integrate.quad(lambda t: math.exp(-0.5 * t * t), -np.inf, gamma * (x - mu) / sigma)
    expected = math.exp(-((x - mu) ** 2) / (2 * sigma**2)) * integral / (sigma * math.pi)
    value = skew_normal_pdf(x, mu, sigma, gamma)
    assert isinstance(value, float)
    assert value == pytest.approx(expected, rel=1e-10)


def test_pdf_with_zero_skew_is_gaussian():
    x = np.linspace(-4, 4, 81)
    assert_allclose(skew_normal_pdf(x, 0.1, 0.7, 0.0), stats.norm.pdf(x, 0.1, 0.7), rtol=1e-13)


def test_pdf_broadcasts():
    gammas = np.array([[-1.0], [0.0], [2.0]])
    x = np.linspace(-1, 1, 5)
    assert skew_normal_pdf(x, 0.0, 1.0, gammas).shape == (3, 5)


@pytest.mark.parametrize("sigma", [0.0, -1.0, np.inf, np.nan])
def test_pdf_rejects_bad_sigma(sigma):
    with pytest.raises(ValueError, match="sigma"):
        skew_normal_pdf(0.0, 0.0, sigma, 1.0)


# --- the learners' samples (eqs. 8, 14) ---------------------------------------------------------


@pytest.mark.parametrize("gamma", [-1.0, 0.25, 0.5, 1.0, 3.0])
def test_skew_normal_moments(gamma):
    z = draw_z(gamma)
    n = z.size
    delta = gamma / math.sqrt(1 + gamma**2)
    mean, var = delta * math.sqrt(2 / math.pi), 1 - 2 * delta**2 / math.pi
    p_pos = 0.5 + math.atan(gamma) / math.pi
    assert abs(z.mean() - mean) < 4.5 * math.sqrt(var / n)
    sq = (z - z.mean()) ** 2
    assert abs(z.var() - var) < 4.5 * sq.std() / math.sqrt(n)
    assert abs(np.mean(z > 0) - p_pos) < 4.5 * math.sqrt(p_pos * (1 - p_pos) / n)


@pytest.mark.parametrize("gamma", [None, 0.0])
def test_gaussian_and_zero_skew_exploration_is_standard_normal(gamma):
    z = draw_z(gamma, seed=7)
    assert stats.kstest(z, stats.norm.cdf).pvalue > 1e-3
    assert abs(z.mean()) < 4.5 / math.sqrt(N_SAMPLES)
    assert abs(z.var() - 1.0) < 4.5 * math.sqrt(2.0 / N_SAMPLES)


@pytest.mark.parametrize("gamma", [0.5, -0.5])
def test_skew_normal_distribution_matches_scipy(gamma):
    z = draw_z(gamma, seed=99)
    assert stats.kstest(z, stats.skewnorm(a=gamma).cdf).pvalue > 1e-3
    # and the test has power: the sample is clearly not N(0, 1)
    assert stats.kstest(z, stats.norm.cdf).pvalue < 1e-6


@pytest.mark.parametrize("gamma", [1.0, -1.0])
def test_skew_shifts_the_mean_action_by_sigma_delta_root_two_over_pi(gamma):
    # the paper's location/scale form: A(s) is the location, the mean lies σ δ √(2/π) beside it
    sigma = 0.15
    agent, mu, g = exploring_cacla(0.05, gamma, sigma, 31)
    a = draw_actions(agent, N_SAMPLES)
    assert np.all(np.abs(a) < 1.0)  # none clipped
    shift = sigma * stats.skewnorm(a=g).mean()
    assert shift == pytest.approx(sigma * g / math.sqrt(1 + g * g) * math.sqrt(2 / math.pi), rel=1e-12)
    assert abs(a.mean() - mu - shift) < 4.5 * sigma * stats.skewnorm(a=g).std() / math.sqrt(a.size)
    assert stats.kstest(a, stats.skewnorm(a=g, loc=mu, scale=sigma).cdf).pvalue > 1e-3


@pytest.mark.parametrize("gamma", [0.0, 0.5, -1.0])
def test_skew_action_is_the_numpy_skew_normal_bit_for_bit(gamma):
    # two standard normals per action, u0 then v, clip(A(s) + σ z) (eq. 14)
    agent, mu, g = exploring_cacla(-0.6, gamma, 0.8, 2024)
    rng_numpy = np.random.default_rng(2024)
    a = draw_actions(agent, 5_000)
    assert np.array_equal(a, np.clip(mu + 0.8 * numpy_skew_normal_z(rng_numpy, g, 5_000), -1.0, 1.0))
    assert a.min() == -1.0 and a.max() == 1.0
    assert agent.rng.bit_generator.state == rng_numpy.bit_generator.state  # the streams stay in step


def test_gaussian_action_is_the_clipped_eq8_sample_with_one_normal_each():
    agent, mu, _ = exploring_cacla(0.7, None, 1.0, 11)
    rng_numpy = np.random.default_rng(11)
    a = draw_actions(agent, 5_000)
    assert np.array_equal(a, np.clip(mu + 1.0 * rng_numpy.standard_normal(5_000), -1.0, 1.0))
    assert a.min() == -1.0 and a.max() == 1.0
    assert agent.rng.bit_generator.state == rng_numpy.bit_generator.state


@pytest.mark.parametrize("gamma", [None, 0.5])
def test_no_exploration_draws_nothing(gamma):
    agent, _, _ = exploring_cacla(1.5, gamma, 0.0, 17)
    state = agent.rng.bit_generator.state
    assert agent.act(OBS) == 1.0  # clip(A(s)), σ = 0
    agent.begin_episode(0.5)
    assert agent.act(OBS, explore=False) == 1.0
    assert agent.rng.bit_generator.state == state


def test_small_sigma_stays_near_the_mean():
    agent, mu, _ = exploring_cacla(0.3, 1.0, 0.01, 19)
    a = draw_actions(agent, 1_000)
    assert np.all(np.abs(a - mu) < 0.06)
    assert np.mean(a > mu) > 0.6  # skewed to the right for γ = 1 (P = 3/4)


def test_skew_normal_from_normals():
    g = 1.0
    d = 1 / math.sqrt(2)
    assert skew_normal_from_normals(g, 0.5, -0.2) == pytest.approx(d * 0.5 + d * -0.2, abs=1e-15)
    assert skew_normal_from_normals(g, -0.5, -0.2) == pytest.approx(-(d * -0.5 + d * -0.2), abs=1e-15)
    assert skew_normal_from_normals(0.0, -0.5, 0.3) == -0.3


# --- Δγ in degrees ----------------------------------------------------------------------------


def test_skew_step_to_gamma():
    assert skew_step_to_gamma(11.25) == 0.25
    assert skew_step_to_gamma(22.5) == 0.5
    assert skew_step_to_gamma(45) == 1.0
    assert skew_step_to_gamma(0) == 0.0


@pytest.mark.parametrize("step", [-1.0, np.nan, np.inf])
def test_skew_step_to_gamma_rejects_bad_steps(step):
    with pytest.raises(ValueError, match="skew step"):
        skew_step_to_gamma(step)
