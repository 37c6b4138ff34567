"""Exploration noise (eqs. 8, 14) against scipy and the skew-normal's known moments."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit
from numpy.testing import assert_allclose
from scipy import integrate, stats

from pipefollow.learners.exploration import (
    gaussian_action,
    linear_sigma,
    skew_normal_action,
    skew_normal_from_normals,
    skew_normal_pdf,
    skew_normal_z,
    skew_step_to_gamma,
)

N_SAMPLES = 200_000


@njit
def draw_z(rng, gamma, n):
    out = np.empty(n)
    for i in range(n):
        out[i] = skew_normal_z(rng, gamma)
    return out


@njit
def draw_actions(rng, mu, sigma, gamma, n, skewed):
    out = np.empty(n)
    for i in range(n):
        out[i] = skew_normal_action(rng, mu, sigma, gamma) if skewed else gaussian_action(rng, mu, sigma)
    return out


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


# --- sampler ----------------------------------------------------------------------------------


@pytest.mark.parametrize("gamma", [-1.0, 0.25, 0.5, 1.0, 3.0])
def test_skew_normal_moments(gamma):
    z = draw_z(np.random.default_rng(12345), gamma, N_SAMPLES)
    n = z.size
    delta = gamma / math.sqrt(1 + gamma**2)
    mean, var = delta * math.sqrt(2 / math.pi), 1 - 2 * delta**2 / math.pi
    p_pos = 0.5 + math.atan(gamma) / math.pi
    assert abs(z.mean() - mean) < 4.5 * math.sqrt(var / n)
    sq = (z - z.mean()) ** 2
    assert abs(z.var() - var) < 4.5 * sq.std() / math.sqrt(n)
    assert abs(np.mean(z > 0) - p_pos) < 4.5 * math.sqrt(p_pos * (1 - p_pos) / n)


def test_zero_skew_is_standard_normal():
    z = draw_z(np.random.default_rng(7), 0.0, N_SAMPLES)
    assert stats.kstest(z, stats.norm.cdf).pvalue > 1e-3
    assert abs(z.mean()) < 4.5 / math.sqrt(N_SAMPLES)
    assert abs(z.var() - 1.0) < 4.5 * math.sqrt(2.0 / N_SAMPLES)


@pytest.mark.parametrize("gamma", [0.5, -0.5])
def test_skew_normal_distribution_matches_scipy(gamma):
    z = draw_z(np.random.default_rng(99), gamma, N_SAMPLES)
    assert stats.kstest(z, stats.skewnorm(a=gamma).cdf).pvalue > 1e-3
    # and the test has power: the sample is clearly not N(0, 1)
    assert stats.kstest(z, stats.norm.cdf).pvalue < 1e-6


@pytest.mark.parametrize("gamma", [0.0, 0.5, -1.0])
def test_compiled_sampler_equals_numpy_reimplementation_bit_for_bit(gamma):
    rng_numba, rng_numpy = np.random.default_rng(2024), np.random.default_rng(2024)
    z = draw_z(rng_numba, gamma, 10_000)
    assert np.array_equal(z, numpy_skew_normal_z(rng_numpy, gamma, 10_000))
    # both consumed exactly two normals per sample: the streams stay in step
    assert rng_numba.standard_normal() == rng_numpy.standard_normal()


def test_sampler_called_from_python_shares_the_generator_state():
    rng_a, rng_b = np.random.default_rng(5), np.random.default_rng(5)
    z = [skew_normal_z(rng_a, 0.5) for _ in range(3)]
    assert z == numpy_skew_normal_z(rng_b, 0.5, 3).tolist()
    assert rng_a.bit_generator.state == rng_b.bit_generator.state


def test_skew_normal_from_normals():
    g = 1.0
    d = 1 / math.sqrt(2)
    assert skew_normal_from_normals(g, 0.5, -0.2) == pytest.approx(d * 0.5 + d * -0.2, abs=1e-15)
    assert skew_normal_from_normals(g, -0.5, -0.2) == pytest.approx(-(d * -0.5 + d * -0.2), abs=1e-15)
    assert skew_normal_from_normals(0.0, -0.5, 0.3) == -0.3


# --- actions ----------------------------------------------------------------------------------


def test_gaussian_action_is_clipped_eq8_sample():
    rng_a, rng_b = np.random.default_rng(11), np.random.default_rng(11)
    a = draw_actions(rng_a, 0.7, 1.0, 0.0, 5_000, False)
    expected = np.clip(0.7 + 1.0 * rng_b.standard_normal(5_000), -1.0, 1.0)
    assert np.array_equal(a, expected)
    assert a.min() == -1.0 and a.max() == 1.0
    assert rng_a.standard_normal() == rng_b.standard_normal()


def test_skew_normal_action_is_clipped_eq14_sample():
    rng_a, rng_b = np.random.default_rng(13), np.random.default_rng(13)
    a = draw_actions(rng_a, -0.6, 0.8, 1.0, 5_000, True)
    expected = np.clip(-0.6 + 0.8 * numpy_skew_normal_z(rng_b, 1.0, 5_000), -1.0, 1.0)
    assert np.array_equal(a, expected)
    assert a.min() == -1.0 and a.max() == 1.0


def test_actions_with_zero_sigma_still_draw():
    rng_a, rng_b = np.random.default_rng(17), np.random.default_rng(17)
    assert gaussian_action(rng_a, 0.25, 0.0) == 0.25
    assert skew_normal_action(rng_a, 1.5, 0.0, 0.5) == 1.0
    rng_b.standard_normal(3)
    assert rng_a.bit_generator.state == rng_b.bit_generator.state


def test_small_sigma_stays_near_the_mean():
    a = draw_actions(np.random.default_rng(19), 0.3, 0.01, 1.0, 1_000, True)
    assert np.all(np.abs(a - 0.3) < 0.06)
    assert np.mean(a > 0.3) > 0.6  # skewed to the right for γ = 1 (P = 3/4)


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
