"""CACLA (eqs. 5–8), its skew-normal exploration (eqs. 14–15) and supervised CACLA (eqs. 10–13).

All four heads are linear in the same RBF state features φ(s) (paper §4):

* critic ``V(s) = w_V·φ(s)`` (eqs. 5–6), actor mean ``A(s) = w_A·φ(s)`` (eq. 7),
* skew ``γ(s) = w_γ·φ(s)`` (eq. 15, only with ``skew > 0``),
* supervisor trust ``k(s) = w_k·φ(s)`` (eq. 13, only when ``supervised``).

The update rules are compiled functions of plain arrays, so that the agent class below and the
compiled training loop (:mod:`pipefollow.training`) run the very same code. Random numbers are
drawn by the caller from a ``numpy.random.Generator`` and passed in as standard normals.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.exploration import DEGREES_PER_GAMMA, skew_normal_from_normals
from pipefollow.heuristic import heuristic_action
from pipefollow.linear import dot
from pipefollow.rbf import STATE_GRID, RBFGrid, features_if_finite

V, A, G, K = 0, 1, 2, 3  # rows of the weight matrix: critic, actor, skew, supervisor trust


class CaclaParams(NamedTuple):
    """CACLA's step sizes and options (paper §4; DESIGN.md)."""

    alpha_v: float = 0.4  # critic step size α_V (paper §4)
    alpha_pi: float = 0.2  # actor step size α_π (paper §4)
    discount: float = 0.8  # discount factor γ_d (paper §4)
    skew: float = 0.0  # skew step Δγ in γ units (22.5° ↦ 0.5); 0 = Gaussian exploration (eq. 8)
    gamma_max: float = 1.0  # cap |γ(s)| ≤ γ_max (paper: α_max = 1)
    supervised: bool = False  # supervised CACLA (eqs. 10–13)
    delta_k: float = 0.05  # Δk per visit (paper §4.1)
    k_max: float = 1.0  # cap on k(s) (eq. 13)
    forgetting: float = 0.0  # per-update decay of w_k (Rosenstein & Barto); the paper uses none
    skew_centred: bool = False  # subtract the skew-normal's mean shift σδ√(2/π): an extension


PAPER_CACLA = CaclaParams()


def pack(p: CaclaParams) -> np.ndarray:
    """``p`` as a float array for compiled code (a NamedTuple argument costs µs per call)."""
    return np.array(p, dtype=np.float64)


@njit(cache=True)
def unpack(a):
    """Inverse of :func:`pack` inside compiled code."""
    return CaclaParams(a[0], a[1], a[2], a[3], a[4], a[5] != 0.0, a[6], a[7], a[8], a[9] != 0.0)


@njit(cache=True)
def clip1(x):
    """Clip to the action range [-1, 1]."""
    return min(1.0, max(-1.0, x))


@njit(cache=True)
def act(w, phi, sigma, z0, z1, a_sup, p):
    """Action for features ``phi``: returns ``(a, a_rl)``, executed and learner's action.

    ``a_rl = clip(A(s) + σ z)`` with z Gaussian (eq. 8) or skew-normal with skew γ(s) (eq. 14),
    built from the standard normals ``z0, z1``; σ = 0 gives the deterministic policy. Supervised
    agents execute ``a = k(s) a_rl + (1 − k(s)) a_sup`` (eq. 10).
    """
    mu = dot(w[A], phi)
    if sigma > 0.0:
        if p.skew > 0.0:
            g = min(p.gamma_max, max(-p.gamma_max, dot(w[G], phi)))
            z = skew_normal_from_normals(g, z0, z1)
            if p.skew_centred:  # keep the exploration's mean on A(s); the paper does not
                z -= g / math.sqrt(1.0 + g * g) * math.sqrt(2.0 / math.pi)
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

    ``discount`` is γ_d^n for a transition of n decisions (semi-Markov, DESIGN.md). Returns δ.
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
            for i in range(phi.shape[0]):
                w[G, i] += inc * phi[i]
    if p.supervised:  # eq. 13
        if p.forgetting > 0.0:
            w[K] *= 1.0 - p.forgetting
        if dot(w[K], phi) < p.k_max:
            for i in range(phi.shape[0]):
                w[K, i] += p.delta_k * phi[i]
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


def cacla_label(p: CaclaParams) -> str:
    """Label such as ``supervised CACLA, skew 22.5°``."""
    name = "supervised CACLA" if p.supervised else "CACLA"
    if p.skew > 0.0:
        name += f", skew {p.skew * DEGREES_PER_GAMMA:g}°" + (" centred" if p.skew_centred else "")
    return name
