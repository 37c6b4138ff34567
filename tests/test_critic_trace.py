"""The critic's TD(λ) trace (``critic_lambda``), an option beyond the paper, against hand-computed steps."""

import numpy as np
import pytest

from pipefollow import readings as rd
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.learners import cacla
from pipefollow.learners.cacla_act import CaclaParams
from pipefollow.learners.cacla_update import A, V
from pipefollow.sim.pipeline import builtin
from pipefollow.training.agents import make_agent
from pipefollow.training.compiled import train, train_compiled

PHI = np.array([0.2, 0.5, 0.3])
PHI_NEXT = np.array([0.0, 0.4, 0.6])
LAM = CaclaParams(critic_lambda=0.5)


def test_two_steps_of_td_lambda_by_hand():
    w, trace = np.zeros((4, 3)), np.zeros(3)
    # step 1: V = 0 everywhere, δ = r = -1; e = φ(s); w_V = 0.4·(−1)·φ(s)
    d1 = cacla.update(w, PHI, 0.0, 0.0, -1.0, 0.8, PHI_NEXT, LAM, trace=trace)
    assert d1 == pytest.approx(-1.0)
    np.testing.assert_allclose(trace, PHI)
    np.testing.assert_allclose(w[V], -0.4 * PHI)
    # step 2 from s' = PHI_NEXT to PHI: V(s') = −0.4·(0.2 + 0.18) = −0.152, V(next) = −0.4·0.38 = −0.152
    v_s, v_n = -0.4 * PHI @ PHI_NEXT, -0.4 * PHI @ PHI
    d2 = cacla.update(w, PHI_NEXT, 0.0, 0.0, -1.0, 0.8, PHI, LAM, trace=trace)
    assert d2 == pytest.approx(-1.0 + 0.8 * v_n - v_s)
    e2 = 0.8 * 0.5 * PHI + PHI_NEXT  # e ← γ_d λ e + φ(s)
    np.testing.assert_allclose(trace, e2)
    np.testing.assert_allclose(w[V], -0.4 * PHI + 0.4 * d2 * e2)  # the first state's value moves too
    np.testing.assert_array_equal(w[A], 0.0)  # δ < 0: no actor step


def test_lambda_zero_or_no_trace_is_the_papers_td0():
    w0, w1, trace = np.zeros((4, 3)), np.zeros((4, 3)), np.zeros(3)
    for w, p, t in ((w0, CaclaParams(), trace), (w1, LAM, None)):
        cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, p, trace=t)
        cacla.update(w, PHI_NEXT, 0.6, 0.0, 0.3, 0.8, PHI, p, trace=t)
    np.testing.assert_array_equal(w0, w1)
    np.testing.assert_array_equal(trace, 0.0)  # λ = 0 leaves the trace alone


def test_compiled_path_equals_the_environment_path_and_the_trace_restarts_each_episode():
    pipe = builtin("paper-left")
    a, b = (
        make_agent("cacla", supervised=True, critic_lambda=0.7, rng=np.random.default_rng(4)) for _ in "ab"
    )
    td0 = make_agent("cacla", supervised=True, rng=np.random.default_rng(4))
    stats_env = train(PipelineFollowingEnv(pipe, 20), a, 8)
    stats_fast = train_compiled(b, pipe, 8, chunk=3)
    train_compiled(td0, pipe, 8, chunk=3)
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
    assert np.abs(td0.weights[V] - b.weights[V]).max() > 1e-3
    a.begin_episode(0.5)
    assert not a.critic_trace.any()
    assert b.name == "supervised CACLA, TD(0.7)"


def test_bad_lambda_is_refused():
    with pytest.raises(ValueError, match=r"critic_lambda must be in \[0, 1\], got 1.5"):
        make_agent("cacla", critic_lambda=1.5)
    with pytest.raises(ValueError, match="critic_lambda applies to algorithm cacla and ac only"):
        make_agent("sarsa", critic_lambda=0.5)
    assert make_agent("ac", critic_lambda=0.5, readings=rd.DEFAULT).params.critic_lambda == 0.5
