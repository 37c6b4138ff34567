"""Exploration: Gaussian (eq. 8) and skew-normal (eq. 14) action noise, and the σ schedule.

The exploring action is ``a = clip(μ + σ z, −1, 1)`` in normalized action units (a = 1 ↦ 90°),
with ``z ~ N(0, 1)`` (eq. 8) or ``z ~ SkewNormal(γ)`` (eq. 14). By default (reading
``skew_sample=location``) the skew-normal is used in its location/scale form: with γ ≠ 0 the mean
of ``z`` is ``δ √(2/π)``, so exploration leans towards the side that has earned positive TD-errors;
the readings ``centred`` and ``moments`` shift (and scale) ``z`` instead (docs/design.md, "Readings").

σ falls linearly from 1 to 0.01 over the episodes of a trial (paper §4; docs/design.md, "exploration σ").

Randomness comes only from an explicit ``numpy.random.Generator``. The learners draw their
standard normals themselves (one per exploring action; two, u0 then v, for a skew-normal one) and
build the sample with :func:`skew_normal_from_normals`, so that the Python and the compiled
training paths consume the same numbers in the same order.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit, vectorize

# Δγ of eq. 15 is given in degrees; 45° is one unit of γ ("22.5° equals 0.5", paper §4.1).
DEGREES_PER_GAMMA = 45.0


# The paper's exploration schedule (§4): "The exploration factor starts at σ = 1 and decreases
# linearly per episode towards σ = 0.01", in the units of the reading sigma_unit.
SIGMA_START = 1.0
SIGMA_END = 0.01


@njit(cache=True)
def linear_sigma(episode, n_episodes, start=SIGMA_START, end=SIGMA_END):
    """Exploration σ of episode ``episode`` (0 … n_episodes − 1), linear from ``start`` to ``end``.

    The first episode gets ``start``, the last ``end``; with one episode, ``start``.

    Raises:
        ValueError: ``n_episodes < 1`` or ``episode`` outside ``0 … n_episodes − 1``.
    """
    if n_episodes < 1:
        raise ValueError("n_episodes must be at least 1")
    if episode < 0 or episode >= n_episodes:
        raise ValueError("episode must be in 0 ... n_episodes - 1")
    if n_episodes == 1:
        return float(start)
    t = episode / (n_episodes - 1)
    return (1.0 - t) * start + t * end  # exact at both ends


def sigma_schedule(episodes: int, start: float = SIGMA_START, end: float = SIGMA_END) -> np.ndarray:
    """σ of every episode of a phase of ``episodes`` episodes: :func:`linear_sigma` of each."""
    return np.array([linear_sigma(e, episodes, start, end) for e in range(episodes)], dtype=np.float64)


def _skew_normal_kernel(x, mu, sigma, gamma):
    z = (x - mu) / sigma
    # ∫_{−∞}^{γz} e^{−t²/2} dt = √(2π) Φ(γz) = √(π/2) erfc(−γz/√2); erfc keeps the far tail accurate.
    integral = math.sqrt(0.5 * math.pi) * math.erfc(-gamma * z / math.sqrt(2.0))
    return math.exp(-0.5 * z * z) * integral / (sigma * math.pi)


@functools.cache
def _skew_normal_ufunc():
    # Built on first use: a typed ``vectorize`` compiles (or loads its cache) when it is applied,
    # which at import cost every command, and every trial worker, a few tenths of a second.
    return vectorize(["float64(float64, float64, float64, float64)"], cache=True)(_skew_normal_kernel)


def skew_normal_pdf(x, mu, sigma, gamma):
    """Skew-normal density, eq. 14 as printed.

    ``f(x) = 1/(σπ) · exp(−(x − μ)²/(2σ²)) · ∫_{−∞}^{γ(x−μ)/σ} exp(−t²/2) dt``, which is
    ``(2/σ) φ(z) Φ(γz)`` with ``z = (x − μ)/σ`` (Azzalini's form; scipy's ``skewnorm(a=γ)``).

    Args:
        x: where to evaluate (scalar or array; all arguments broadcast).
        mu: location μ.
        sigma: scale σ > 0.
        gamma: skew γ (0 gives the Gaussian of eq. 8).

    Returns:
        The density, a float for scalar arguments, else an array.

    Raises:
        ValueError: σ not positive and finite.
    """
    sigma_arr = np.asarray(sigma, dtype=np.float64)
    if not np.all(np.isfinite(sigma_arr) & (sigma_arr > 0.0)):
        raise ValueError(f"sigma must be positive and finite, got {sigma}")
    out = _skew_normal_ufunc()(x, mu, sigma_arr, gamma)
    return float(out) if np.ndim(out) == 0 else out


@njit(cache=True)
def skew_normal_from_normals(gamma, u0, v):
    """A standard skew-normal sample (location 0, scale 1, skew γ) from two standard normals.

    Azzalini's construction: ``δ = γ/√(1+γ²)``, ``u1 = δ u0 + √(1−δ²) v``, ``z = u1`` if ``u0 ≥ 0``
    else ``−u1``. γ = 0 gives ``±v``, a standard normal.
    """
    delta = gamma / math.sqrt(1.0 + gamma * gamma)
    u1 = delta * u0 + math.sqrt(1.0 - delta * delta) * v
    return u1 if u0 >= 0.0 else -u1


def skew_step_to_gamma(step_deg: float) -> float:
    """Δγ of eq. 15 from degrees to γ units: 11.25°, 22.5°, 45° → 0.25, 0.5, 1.0.

    Raises:
        ValueError: ``step_deg`` negative or not finite.
    """
    step = float(step_deg)
    if not math.isfinite(step) or step < 0.0:
        raise ValueError(f"skew step must be a finite number of degrees ≥ 0, got {step_deg!r}")
    return step / DEGREES_PER_GAMMA
