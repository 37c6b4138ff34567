"""CACLA's parameter record and its compiled action (eqs. 8, 10, 14), with the entry points from Python.

:class:`CaclaParams` is the record of CACLA's step sizes and options (the actor-critic's record
extends it); :func:`pack` and :func:`unpack` carry it across the Python ↔ compiled boundary as a
float array. :func:`act` is the action of every head on the features φ(s) — the actor's mean,
Gaussian (eq. 8) or skew-normal (eq. 14) exploration, the supervisor's share (eq. 10) — and the
``*_packed`` functions are the cheap entry points through which the agent class
(:class:`~pipefollow.learners.cacla.Cacla`) calls it and the update
(:func:`~pipefollow.learners.cacla_update.update`); the compiled episode loop
(:func:`~pipefollow.learners.cacla.episodes`) calls the same :func:`act`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit
from numba.np.unsafe.ndarray import to_fixed_tuple

from pipefollow.learners.cacla_update import (
    HEAD_A,
    HEAD_G,
    HEAD_K,
    K_EVERY,
    REPEAT_ONCE,
    SAMPLE_LOCATION,
    SAMPLE_MOMENTS,
    STEP_GAMMA,
    STEP_WEIGHTS,
    A,
    G,
    K,
    clip1,
    update,
)
from pipefollow.learners.exploration import skew_normal_from_normals
from pipefollow.learners.heuristic import heuristic_action
from pipefollow.learners.rbf import features_if_finite
from pipefollow.learners.sums import dot
from pipefollow.sim import records


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
    actor_repeats: int = REPEAT_ONCE  # beyond the paper: REPEAT_VAR makes ⌈δ/√var⌉ actor updates (CACLA+Var)
    var_rate: float = 0.001  # β of CACLA+Var: var ← (1 − β) var + β δ² (Van Hasselt & Wiering 2007)
    critic_lambda: float = 0.0  # beyond the paper: λ of the critic's TD(λ) trace; 0 = eqs. 5-6 (TD(0))


PAPER_CACLA = CaclaParams()
_N_PARAMS = records.size(PAPER_CACLA)


def pack(p: CaclaParams) -> np.ndarray:
    """``p`` as a float array for compiled code (a NamedTuple argument costs microseconds per call)."""
    return records.pack(p)


@njit(cache=True)
def unpack(a):
    """Inverse of :func:`pack` inside compiled code: the record, its flags and codes as floats.

    A record that extends :class:`CaclaParams` by fields after its own (the actor-critic's) packs
    into an array that starts with CACLA's; ``unpack`` reads those.
    """
    return CaclaParams(*to_fixed_tuple(a, _N_PARAMS))


@njit(cache=True)
def act(w, phi, sigma, z0, z1, a_sup, p, heads=None):
    """Action for features ``phi``: returns ``(a, a_rl)``, executed and learner's action.

    ``heads`` (an array of :data:`.cacla_update.HEADS` slots, or None) receives the heads' values on
    φ(s) that were computed — A(s), and w_γ·φ(s), w_K·φ(s) before clipping, NaN where not — for the
    update of the transition from s (:func:`.cacla_update.update`), which reuses them.

    ``a_rl = clip(A(s) + σ z)`` with z Gaussian (eq. 8) or skew-normal with skew γ(s) (eq. 14),
    built from the standard normals ``z0, z1``; σ = 0 gives the deterministic policy. The skew
    sample's reading (``p.skew_sample``): A(s) and σ are the location and scale (the paper's form),
    or z is shifted to mean 0 (``centred``), or standardized to mean 0 and s.d. 1 (``moments``).
    Supervised agents execute ``a = k(s) a_rl + (1 − k(s)) a_sup`` (eq. 10).
    """
    mu = dot(w[A], phi)
    if heads is not None:
        heads[:] = np.nan
        heads[HEAD_A] = mu
    if sigma > 0.0:
        if p.skew > 0.0:
            g_raw = dot(w[G], phi)
            if heads is not None:
                heads[HEAD_G] = g_raw
            g = min(p.gamma_max, max(-p.gamma_max, g_raw))
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
        k_raw = dot(w[K], phi)
        if heads is not None:
            heads[HEAD_K] = k_raw
        k = min(p.k_max, max(0.0, k_raw))
        return k * a_rl + (1.0 - k) * a_sup, a_rl
    return a_rl, a_rl


@njit(cache=True)
def act_packed(w, phi, sigma, z0, z1, a_sup, hp):
    """:func:`act` with packed parameters: the cheap entry point from Python."""
    return act(w, phi, sigma, z0, z1, a_sup, unpack(hp))


@njit(cache=True)
def update_packed(w, phi, a_rl, a_sup, reward, discount, phi_next, hp, rule, var, trace):
    """:func:`update` with packed parameters: the cheap entry point from Python."""
    return update(w, phi, a_rl, a_sup, reward, discount, phi_next, unpack(hp), rule, var, trace)


@njit(cache=True)
def act_heuristic_packed(w, phi, sigma, z0, z1, x1, y1, hp):
    """:func:`act_packed` with the paper's heuristic as supervisor, evaluated in compiled code."""
    p = unpack(hp)
    a_sup = heuristic_action(x1, y1) if p.supervised else 0.0
    a, a_rl = act(w, phi, sigma, z0, z1, a_sup, p)
    return a, a_rl, a_sup


@njit(cache=True)
def update_next_packed(w, phi, a_rl, a_sup, reward, discount, next_obs, grid, normalized, phi_next, hp, rule,
                       var, trace):  # fmt: skip
    """φ(s') into ``phi_next`` and :func:`update`, in one call; ``(δ, False)`` if s' is not finite."""
    if not features_if_finite(next_obs, grid[0], grid[1], grid[2], normalized, phi_next):
        return 0.0, False
    return update(w, phi, a_rl, a_sup, reward, discount, phi_next, unpack(hp), rule, var, trace), True
