"""CACLA (eqs. 5–8), its skew-normal exploration (eqs. 14–15) and supervised CACLA (eqs. 10–13).

All four heads are linear in the same RBF state features φ(s) (paper §4):

* critic ``V(s) = w_V·φ(s)`` (eqs. 5–6), actor mean ``A(s) = w_A·φ(s)`` (eq. 7),
* skew ``γ(s) = w_γ·φ(s)`` (eqs. 14–15, only with ``skew > 0``),
* supervisor trust ``k(s) = w_k·φ(s)`` (eq. 13, only when ``supervised``).

The update rules are compiled functions of plain arrays, so that the agent class below and the
compiled training loop (:mod:`pipefollow.training.compiled`) run the very same code. Random numbers are
drawn by the caller from a ``numpy.random.Generator`` and passed in as standard normals.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.learners.exploration import DEGREES_PER_GAMMA, skew_normal_from_normals
from pipefollow.learners.heuristic import heuristic_action
from pipefollow.learners.rbf import STATE_GRID, RBFGrid, features_if_finite
from pipefollow.learners.sums import dot

V, A, G, K = 0, 1, 2, 3  # rows of the weight matrix: critic, actor, skew, supervisor trust

# Readings of open points (docs/design.md, "Readings"); codes as stored in CaclaParams.
SAMPLE_LOCATION, SAMPLE_CENTRED, SAMPLE_MOMENTS = 0, 1, 2  # skew sample: location/scale, centred, mean/s.d.
STEP_GAMMA, STEP_WEIGHTS = 0, 1  # eqs. 13, 15: the head's value moves by the step, or its weights by step·φ
K_EVERY, K_POSITIVE = 0, 1  # eq. 13: k(s) grows at every visit, or only when δ > 0


class CaclaParams(NamedTuple):
    """CACLA's step sizes and options (paper §4; docs/design.md)."""

    alpha_v: float = 0.4  # critic step size α_V (paper §4)
    alpha_pi: float = 0.2  # actor step size α_π (paper §4)
    discount: float = 0.8  # discount factor γ_d (paper §4)
    skew: float = 0.0  # skew step Δγ in γ units (22.5° ↦ 0.5); 0 = Gaussian exploration (eq. 8)
    gamma_max: float = 1.0  # cap |γ(s)| ≤ γ_max (paper: α_max = 1)
    supervised: bool = False  # supervised CACLA (eqs. 10–13)
    delta_k: float = 0.05  # Δk per visit (paper §4.1)
    k_max: float = 1.0  # cap on k(s) (eq. 13)
    forgetting: float = 0.0  # per-update decay of w_k (Rosenstein & Barto); the paper uses none
    skew_sample: int = SAMPLE_LOCATION  # skew sample: location/scale, centred on A(s), or mean/s.d.
    skew_step: int = STEP_GAMMA  # eq. 15 step: γ(s) moves by Δγ (default) or w_γ by Δγ·φ(s)
    k_update: int = K_EVERY  # eq. 13: k(s) grows at every visit (default) or only when δ > 0
    k_step: int = STEP_WEIGHTS  # eq. 13 step: w_k by Δk·φ(s) (default) or k(s) by Δk (STEP_GAMMA)


PAPER_CACLA = CaclaParams()


def pack(p: CaclaParams) -> np.ndarray:
    """``p`` as a float array for compiled code (a NamedTuple argument costs microseconds per call)."""
    return np.array(p, dtype=np.float64)


@njit(cache=True)
def unpack(a):
    """Inverse of :func:`pack` inside compiled code."""
    flags = int(a[9]), int(a[10]), int(a[11]), int(a[12])
    return CaclaParams(a[0], a[1], a[2], a[3], a[4], a[5] != 0.0, a[6], a[7], a[8], *flags)


@njit(cache=True)
def clip1(x):
    """Clip to the action range [-1, 1]."""
    return min(1.0, max(-1.0, x))


@njit(cache=True)
def act(w, phi, sigma, z0, z1, a_sup, p):
    """Action for features ``phi``: returns ``(a, a_rl)``, executed and learner's action.

    ``a_rl = clip(A(s) + σ z)`` with z Gaussian (eq. 8) or skew-normal with skew γ(s) (eq. 14),
    built from the standard normals ``z0, z1``; σ = 0 gives the deterministic policy. The skew
    sample's reading (``p.skew_sample``): A(s) and σ are the location and scale (the paper's form),
    or z is shifted to mean 0 (``centred``), or standardized to mean 0 and s.d. 1 (``moments``).
    Supervised agents execute ``a = k(s) a_rl + (1 − k(s)) a_sup`` (eq. 10).
    """
    mu = dot(w[A], phi)
    if sigma > 0.0:
        if p.skew > 0.0:
            g = min(p.gamma_max, max(-p.gamma_max, dot(w[G], phi)))
            z = skew_normal_from_normals(g, z0, z1)
            if p.skew_sample != SAMPLE_LOCATION:  # readings that keep the exploration's mean on A(s)
                d = g / math.sqrt(1.0 + g * g)
                z -= d * math.sqrt(2.0 / math.pi)
                if p.skew_sample == SAMPLE_MOMENTS:
                    z /= math.sqrt(1.0 - 2.0 * d * d / math.pi)
        else:
            z = z0
        a_rl = clip1(mu + sigma * z)
    else:
        a_rl = clip1(mu)
    if p.supervised:
        k = min(p.k_max, max(0.0, dot(w[K], phi)))
        return k * a_rl + (1.0 - k) * a_sup, a_rl
    return a_rl, a_rl


@njit(cache=True)
def update(w, phi, a_rl, a_sup, reward, discount, phi_next, p):
    """One CACLA update for the transition from φ(s) with reward and bootstrap ``discount``·V(s').

    ``discount`` is γ_d^n for a transition of n decisions (semi-Markov, docs/design.md). Returns δ.

    Eq. 15 (``skew > 0``) moves γ(s) by ``Δγ·sgn(δ)·sgn(a_rl − A(s))``: with the default step
    reading the weights move along ``φ(s)/‖φ(s)‖²``, which changes γ(s) = w_γ·φ(s) by exactly that
    amount; the ``weights`` reading moves them by ``Δγ·…·φ(s)``, which changes γ(s) by ``Δγ‖φ‖²``.
    """
    v = dot(w[V], phi)
    delta = reward + discount * dot(w[V], phi_next) - v  # eq. 4, pre-update critic
    mu = dot(w[A], phi)
    if p.supervised:
        k = min(p.k_max, max(0.0, dot(w[K], phi)))
        rl = k * (a_rl - mu) if delta > 0.0 else 0.0
        step = p.alpha_pi * (rl + (1.0 - k) * (a_sup - mu))  # eq. 12
    else:
        step = p.alpha_pi * (a_rl - mu) if delta > 0.0 else 0.0  # eq. 7
    cv = p.alpha_v * delta  # eqs. 5-6
    for i in range(phi.shape[0]):
        w[V, i] += cv * phi[i]
        w[A, i] += step * phi[i]
    if p.skew > 0.0:  # eq. 15
        # the side of the executed sample: compared with the clipped mean, as a_rl is clipped too
        inc = p.skew * np.sign(delta) * np.sign(a_rl - clip1(mu))
        g = dot(w[G], phi)
        if (inc > 0.0 and g < p.gamma_max) or (inc < 0.0 and g > -p.gamma_max):
            if p.skew_step == STEP_GAMMA:
                norm2 = dot(phi, phi)
                inc = inc / norm2 if norm2 > 0.0 else 0.0
            for i in range(phi.shape[0]):
                w[G, i] += inc * phi[i]
    if p.supervised:  # eq. 13
        if p.forgetting > 0.0:
            w[K] *= 1.0 - p.forgetting
        if (p.k_update == K_EVERY or delta > 0.0) and dot(w[K], phi) < p.k_max:
            inc = p.delta_k
            if p.k_step == STEP_GAMMA:  # k(s) itself moves by Δk
                norm2 = dot(phi, phi)
                inc = inc / norm2 if norm2 > 0.0 else 0.0
            for i in range(phi.shape[0]):
                w[K, i] += inc * phi[i]
    return delta


@njit(cache=True)
def act_packed(w, phi, sigma, z0, z1, a_sup, hp):
    """:func:`act` with packed parameters: the cheap entry point from Python."""
    return act(w, phi, sigma, z0, z1, a_sup, unpack(hp))


@njit(cache=True)
def update_packed(w, phi, a_rl, a_sup, reward, discount, phi_next, hp):
    """:func:`update` with packed parameters: the cheap entry point from Python."""
    return update(w, phi, a_rl, a_sup, reward, discount, phi_next, unpack(hp))


@njit(cache=True)
def act_heuristic_packed(w, phi, sigma, z0, z1, x1, y1, hp):
    """:func:`act_packed` with the paper's heuristic as supervisor, evaluated in compiled code."""
    p = unpack(hp)
    a_sup = heuristic_action(x1, y1) if p.supervised else 0.0
    a, a_rl = act(w, phi, sigma, z0, z1, a_sup, p)
    return a, a_rl, a_sup


@njit(cache=True)
def update_next_packed(w, phi, a_rl, a_sup, reward, discount, next_obs, grid, normalized, phi_next, hp):
    """φ(s') into ``phi_next`` and :func:`update`, in one call; ``(δ, False)`` if s' is not finite."""
    if not features_if_finite(next_obs, grid[0], grid[1], grid[2], normalized, phi_next):
        return 0.0, False
    return update(w, phi, a_rl, a_sup, reward, discount, phi_next, unpack(hp)), True


def _draw_count(p: CaclaParams) -> int:
    """Standard normals per exploring decision: skew-normal samples take two."""
    return 2 if p.skew > 0.0 else 1


class Cacla:
    """A CACLA agent on RBF features; works on any Gymnasium env with a Box observation.

    Args:
        params: step sizes and options.
        grid: the RBF grid of the observation (default: the paper's 1,764-feature grid).
        rng: generator for exploration noise (or ``seed``).
        supervisor: ``obs -> a_sup`` for supervised CACLA (default: the paper's heuristic).
    """

    def __init__(
        self,
        params: CaclaParams = PAPER_CACLA,
        grid: RBFGrid = STATE_GRID,
        rng: np.random.Generator | None = None,
        seed: int | None = None,
        supervisor: Callable[[np.ndarray], float] | None = None,
    ) -> None:
        self.params = params
        self.grid = grid
        self.readings = "default"  # id of the readings it learns under (set by make_agent)
        self.rng = rng if rng is not None else np.random.default_rng(seed)
        self.weights = np.zeros((4, grid.n_features))
        self.sigma = 1.0
        self._packed = pack(params)
        self._draws = _draw_count(params)
        self.default_supervisor = supervisor is None  # the compiled training loop knows only this one
        if supervisor is None:

            def supervisor(obs):
                return heuristic_action(float(obs[0]), float(obs[1]))

        self.supervisor = supervisor
        self._pending = None
        self._phi_cache: tuple[bytes, np.ndarray] | None = None  # φ(s') of the last update

    algorithm = "cacla"

    @property
    def name(self) -> str:
        """Short algorithm label."""
        return cacla_label(self.params)

    @property
    def discount(self) -> float:
        """The discount factor γ_d."""
        return self.params.discount

    def begin_episode(self, sigma: float) -> None:
        """Set the exploration σ for the coming episode."""
        self.sigma = float(sigma)
        self._pending = None

    def features(self, obs) -> np.ndarray:
        """φ(obs)."""
        return self.grid.features(obs)

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
            a, a_rl, a_sup = act_heuristic_packed(self.weights, phi, sigma, z0, z1, x[0], x[1], self._packed)
        else:
            a_sup = self.supervisor(obs) if self.params.supervised else 0.0
            a, a_rl = act_packed(self.weights, phi, sigma, z0, z1, a_sup, self._packed)
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
        if cache is not None and cache[0] == next_key:
            return update_packed(
                self.weights, phi, a_rl, a_sup, float(reward), float(discount), cache[1], self._packed
            )
        if next_obs.shape != (self.grid.ndim,):
            raise ValueError(f"next_obs must have {self.grid.ndim} entries, got shape {next_obs.shape}")
        phi_next = np.empty(self.grid.n_features)
        delta, finite = update_next_packed(
            self.weights,
            phi,
            a_rl,
            a_sup,
            float(reward),
            float(discount),
            next_obs,
            self.grid.packed,
            self.grid.form == "normalized",
            phi_next,
            self._packed,
        )
        if not finite:
            raise ValueError(f"next_obs must be finite, got {next_obs}")
        self._phi_cache = (next_key, phi_next)
        return delta


def _key(obs) -> bytes:
    """An observation's identity for the caches: its float64 bytes."""
    return np.asarray(obs, dtype=np.float64).tobytes()


SAMPLE_SUFFIX = {SAMPLE_LOCATION: "", SAMPLE_CENTRED: " centred", SAMPLE_MOMENTS: " mean/s.d."}


def cacla_label(p: CaclaParams) -> str:
    """Label such as ``supervised CACLA, skew 22.5°``."""
    name = "supervised CACLA" if p.supervised else "CACLA"
    if p.skew > 0.0:
        name += f", skew {p.skew * DEGREES_PER_GAMMA:g}°" + SAMPLE_SUFFIX[p.skew_sample]
    return name
