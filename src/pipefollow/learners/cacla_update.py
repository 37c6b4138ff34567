"""CACLA's update (eqs. 5–7, 12–13, 15) and its options beyond the paper, as compiled functions of arrays.

:func:`update` is the one update of CACLA and of the general actor-critic (:mod:`.actor_critic`,
another actor step factor): the critic's TD error and step (eqs. 4–6; with ``critic_lambda`` > 0
along an eligibility trace, TD(λ)), the actor's step (eq. 7, eq. 12 when supervised; with
``actor_repeats`` var made ⌈δ/√var⌉ times, CACLA+Var), the skew head (eq. 15) and the supervisor's
trust k(s) (eq. 13). The record ``p`` is a :class:`~pipefollow.learners.cacla_act.CaclaParams` (or one
that extends it), read by attribute; the codes of its integer fields, the rows of the weight matrix
(:data:`V`, :data:`A`, :data:`G`, :data:`K`: critic, actor mean, skew, supervisor trust) and the
codes of the actor's step factor (:func:`step_factor`) are defined here.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pipefollow.learners.sums import dot

V, A, G, K = 0, 1, 2, 3  # rows of the weight matrix: critic, actor, skew, supervisor trust

# The actor's step factor on (a − A(s)) (paper §2.1): eq. 9's δ; max(δ, 0), eq. 7's max term alone;
# sgn(δ), its sign term alone; both terms, max(sgn δ, 0): CACLA's eq. 7, no step at all when δ ≤ 0.
DELTA, POSITIVE, SIGN, SIGN_AND_MAX = 0, 1, 2, 3

# Readings of open points (docs/design.md, "Readings"); codes as stored in CaclaParams.
SAMPLE_LOCATION, SAMPLE_CENTRED, SAMPLE_MOMENTS = 0, 1, 2  # skew sample: location/scale, centred, mean/s.d.
STEP_GAMMA, STEP_WEIGHTS = 0, 1  # eqs. 13, 15: the head's value moves by the step, or its weights by step·φ
K_EVERY, K_POSITIVE = 0, 1  # eq. 13: k(s) grows at every visit, or only when δ > 0
# Beyond the paper: one actor update per δ > 0 (eq. 7), or ⌈δ/√var⌉ of them (CACLA+Var, Van Hasselt &
# Wiering 2007), var a running variance of δ; at most MAX_ACTOR_REPEATS (a guard against var → 0).
REPEAT_ONCE, REPEAT_VAR = 0, 1
# Slots of the heads' values on φ(s) that acting computed and the update reuses (NaN: not computed).
HEAD_A, HEAD_G, HEAD_K = 0, 1, 2
HEADS = 3
ACTOR_REPEATS = {"once": REPEAT_ONCE, "var": REPEAT_VAR}
MAX_ACTOR_REPEATS = 100


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


@njit(cache=True)
def actor_step(mu, k_raw, a_rl, a_sup, f, moves, p):
    """The actor's step of eq. 7 (eq. 12 when supervised) with factor ``f``, as a multiple of φ(s).

    ``mu`` is A(s) = w_A·φ(s) and ``k_raw`` w_K·φ(s) (before k(s)'s clipping; unused unsupervised).
    """
    if p.supervised:
        k = min(p.k_max, max(0.0, k_raw))
        rl = k * f * (a_rl - mu) if moves else 0.0
        return p.alpha_pi * (rl + (1.0 - k) * (a_sup - mu))  # eq. 12 (eq. 11)
    return p.alpha_pi * f * (a_rl - mu) if moves else 0.0  # eq. 7 (eq. 9: Gaussian score, 1/σ² in α_π)


@njit(cache=True)
def repeats(delta, var, p):
    """CACLA+Var: the number of actor updates for δ, ⌈δ/√var⌉ if δ > 0 (else 1), and var's update.

    ``var[0]`` is the running variance of δ before this transition; it becomes
    ``(1 − β) var + β δ²``. With ``actor_repeats`` once: 1, and ``var`` is left alone.
    """
    if p.actor_repeats != REPEAT_VAR:
        return 1
    n = 1
    if delta > 0.0:
        n = min(MAX_ACTOR_REPEATS, max(1, math.ceil(delta / math.sqrt(var[0]))))
    var[0] = (1.0 - p.var_rate) * var[0] + p.var_rate * delta * delta
    return n


@njit(cache=True)
def update(
    w, phi, a_rl, a_sup, reward, discount, phi_next, p, rule=SIGN_AND_MAX, var=None, trace=None, heads=None
):
    """One CACLA update for the transition from φ(s) with reward and bootstrap ``discount``·V(s').

    ``discount`` is γ_d^n for a transition of n decisions (semi-Markov, docs/design.md). Returns δ.
    The actor's step ``rule`` (:func:`step_factor`) is eq. 7's (eq. 12 when supervised)
    or the actor-critic's: eq. 9 (eq. 11), or one of eq. 7's terms alone. With ``actor_repeats``
    var and the running variance ``var`` (a one-entry array, :func:`repeats`), the actor's step is
    made ⌈δ/√var⌉ times when δ > 0, A(s) recomputed before each (CACLA+Var). With ``critic_lambda``
    λ > 0 and the critic's eligibility trace ``trace`` (zero at an episode's start), the critic steps
    along the trace, ``e ← discount·λ·e + φ(s)``, ``w_V += α_V δ e`` (TD(λ), accumulating traces).

    Eq. 15 (``skew > 0``) moves γ(s) by ``Δγ·sgn(δ)·sgn(a_rl − A(s))``: with the default step
    reading the weights move along ``φ(s)/‖φ(s)‖²``, which changes γ(s) = w_γ·φ(s) by exactly that
    amount; the ``weights`` reading moves them by ``Δγ·…·φ(s)``, which changes γ(s) by ``Δγ‖φ‖²``.

    ``heads`` holds A(s), w_γ·φ(s) and w_K·φ(s) as acting computed them with these weights
    (:data:`HEADS` slots, NaN where not computed), or None: each is then computed here.
    """
    # each head's value on φ(s) is computed once and reused while its weights are unchanged
    v = dot(w[V], phi)
    delta = reward + discount * dot(w[V], phi_next) - v  # eq. 4, pre-update critic
    mu = _head(w, phi, heads, A, HEAD_A)
    k_raw = _head(w, phi, heads, K, HEAD_K) if p.supervised else 0.0  # w_K moves only in trust_step
    norm2 = -1.0  # ‖φ(s)‖², computed when first needed
    f = step_factor(delta, rule)
    moves = rule != SIGN_AND_MAX or delta > 0.0  # eq. 7's max term: no step at all when δ ≤ 0
    step = actor_step(mu, k_raw, a_rl, a_sup, f, moves, p)
    cv = p.alpha_v * delta  # eqs. 5-6
    if trace is not None and p.critic_lambda > 0.0:  # TD(λ): the critic steps along its trace
        decay = discount * p.critic_lambda
        for i in range(phi.shape[0]):
            trace[i] = decay * trace[i] + phi[i]
            w[V, i] += cv * trace[i]
            w[A, i] += step * phi[i]
    else:
        for i in range(phi.shape[0]):
            w[V, i] += cv * phi[i]
            w[A, i] += step * phi[i]
    if var is not None:
        for _ in range(repeats(delta, var, p) - 1):  # CACLA+Var's further actor updates
            step = actor_step(dot(w[A], phi), k_raw, a_rl, a_sup, f, moves, p)  # A(s) has moved
            for i in range(phi.shape[0]):
                w[A, i] += step * phi[i]
    if p.skew > 0.0:  # eq. 15
        # the side of the executed sample: compared with the clipped mean, as a_rl is clipped too
        inc = p.skew * np.sign(delta) * np.sign(a_rl - clip1(mu))
        g = _head(w, phi, heads, G, HEAD_G)  # w_γ has not moved in this update
        if (inc > 0.0 and g < p.gamma_max) or (inc < 0.0 and g > -p.gamma_max):
            if p.skew_step == STEP_GAMMA:
                norm2 = dot(phi, phi)
                inc = inc / norm2 if norm2 > 0.0 else 0.0
            for i in range(phi.shape[0]):
                w[G, i] += inc * phi[i]
    if p.supervised:
        trust_step(w, phi, delta, k_raw, norm2, p)
    return delta


@njit(cache=True)
def _head(w, phi, heads, row, slot):
    """Row ``row``'s value on φ(s): from ``heads`` if acting computed it, else computed now."""
    if heads is not None and not math.isnan(heads[slot]):
        return heads[slot]
    return dot(w[row], phi)


@njit(cache=True)
def trust_step(w, phi, delta, k_raw, norm2, p):
    """Eq. 13: k(s) grows by Δk (capped at k_max), after the optional forgetting of its weights.

    ``k_raw`` is w_K·φ(s) before this step and ``norm2`` ‖φ(s)‖² (negative: not yet computed).
    """
    if p.forgetting > 0.0:
        w[K] *= 1.0 - p.forgetting
        k_raw = dot(w[K], phi)
    if (p.k_update == K_EVERY or delta > 0.0) and k_raw < p.k_max:
        inc = p.delta_k
        if p.k_step == STEP_GAMMA:  # k(s) itself moves by Δk
            norm2 = norm2 if norm2 >= 0.0 else dot(phi, phi)
            inc = inc / norm2 if norm2 > 0.0 else 0.0
        for i in range(phi.shape[0]):
            w[K, i] += inc * phi[i]
