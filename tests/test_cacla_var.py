"""CACLA+Var (Van Hasselt & Wiering 2007), an option beyond the paper, against hand-computed steps."""

import numpy as np
import pytest

from pipefollow.learners import cacla, cacla_update
from pipefollow.learners.cacla_act import CaclaParams
from pipefollow.learners.cacla_update import MAX_ACTOR_REPEATS, A, V
from pipefollow.sim.pipeline import builtin
from pipefollow.training.agents import make_agent
from pipefollow.training.compiled import train_compiled
from pipefollow.training.policy_files import load_policy, save_policy

PHI = np.array([0.2, 0.5, 0.3])  # ‖φ‖² = 0.04 + 0.25 + 0.09 = 0.38
PHI_NEXT = np.array([0.0, 0.4, 0.6])
VAR = CaclaParams(actor_repeats=cacla.REPEAT_VAR)
SHRINK = 1.0 - 0.2 * 0.38  # one actor step moves A(s) by α_π ‖φ‖² (a − A(s)): a − A(s) shrinks by 0.924


def weights():
    w = np.zeros((4, 3))
    w[V] = [1.0, -2.0, 0.5]  # V(s) = -0.65; V(s') = -0.5
    w[A] = [0.5, 0.1, -0.2]  # A(s) = 0.09
    return w


def test_var_makes_ceil_delta_over_sd_actor_updates_and_tracks_the_variance():
    w, var = weights(), np.array([0.01])
    delta = cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, VAR, var=var)
    assert delta == pytest.approx(0.55)  # 0.3 + 0.8·(−0.5) + 0.65
    # ⌈0.55 / √0.01⌉ = ⌈5.5⌉ = 6 updates, each with A(s) recomputed: a − A(s) = 0.51 · 0.924⁶ after them
    assert w[A] @ PHI == pytest.approx(0.6 - 0.51 * SHRINK**6)
    np.testing.assert_allclose(w[A], weights()[A] + 0.51 * (1 - SHRINK**6) / 0.38 * PHI)
    np.testing.assert_allclose(w[V], weights()[V] + 0.4 * 0.55 * PHI)  # the critic steps once
    assert var[0] == pytest.approx(0.999 * 0.01 + 0.001 * 0.55**2)  # 0.0102925


def test_var_leaves_the_actor_alone_when_delta_is_not_positive_but_tracks_delta():
    w, var = weights(), np.array([0.01])
    delta = cacla.update(w, PHI, 0.6, 0.0, -1.0, 0.8, PHI_NEXT, VAR, var=var)
    assert delta == pytest.approx(-0.75)
    np.testing.assert_array_equal(w[A], weights()[A])
    assert var[0] == pytest.approx(0.999 * 0.01 + 0.001 * 0.5625)


def test_var_with_a_large_variance_is_one_update_and_once_leaves_the_variance_alone():
    w, var = weights(), np.array([1.0])
    cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, VAR, var=var)  # ⌈0.55 / 1⌉ = 1: eq. 7's step
    np.testing.assert_allclose(w[A], weights()[A] + 0.2 * 0.51 * PHI)
    w2, var2 = weights(), np.array([0.01])
    cacla.update(w2, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, CaclaParams(), var=var2)
    np.testing.assert_allclose(w2[A], weights()[A] + 0.2 * 0.51 * PHI)
    assert var2[0] == 0.01


def test_supervised_var_repeats_eq_12():
    w, var = weights(), np.array([0.25])  # k(s) = 0: eq. 12 is α_π (a_sup − A(s)) φ; ⌈0.55 / 0.5⌉ = 2
    cacla.update(w, PHI, 0.6, -0.4, 0.3, 0.8, PHI_NEXT, VAR._replace(supervised=True), var=var)
    assert w[A] @ PHI == pytest.approx(-0.4 + 0.49 * SHRINK**2)


def test_the_number_of_updates_is_capped():
    w, var = weights(), np.array([1e-12])  # ⌈0.55 / 1e-6⌉ = 550,000 → MAX_ACTOR_REPEATS = 100
    cacla.update(w, PHI, 0.6, 0.0, 0.3, 0.8, PHI_NEXT, VAR, var=var)
    assert MAX_ACTOR_REPEATS == 100
    assert w[A] @ PHI == pytest.approx(0.6 - 0.51 * SHRINK**100)


def test_agent_option_label_policy_file_and_refusals(tmp_path):
    agent = make_agent("cacla", supervised=True, actor_repeats="var", rng=np.random.default_rng(0))
    assert agent.name == "supervised CACLA+Var" and agent.params.actor_repeats == cacla.REPEAT_VAR
    assert make_agent("cacla").params.actor_repeats == cacla_update.REPEAT_ONCE
    train_compiled(agent, builtin("paper-left"), 5)
    assert agent.td_var[0] != 1.0  # the compiled loop kept the running variance
    loaded = load_policy(save_policy(agent, tmp_path / "p.npz"))
    assert loaded.params == agent.params and loaded.td_var[0] == agent.td_var[0]
    with pytest.raises(ValueError, match="actor_repeats must be one of once, var, got 'twice'"):
        make_agent("cacla", actor_repeats="twice")
    with pytest.raises(ValueError, match="actor_repeats applies to algorithm cacla only"):
        make_agent("ac", actor_repeats="var")


def test_compiled_path_equals_the_environment_path_when_updates_repeat():
    from pipefollow.envs.env import PipelineFollowingEnv
    from pipefollow.training.compiled import train

    pipe = builtin("paper-left")
    a, b, once = (
        make_agent("cacla", rng=np.random.default_rng(3), actor_repeats=r, var_rate=0.0)
        for r in ("var", "var", "once")
    )
    # β = 0 holds var at a small value, so that the updates repeat (δ ≫ √var); with the paper's
    # β the early lost-pipe punishments (δ ≈ −10 per decision) make √var exceed every positive δ
    a.td_var[0] = b.td_var[0] = 1e-4
    stats_env = train(PipelineFollowingEnv(pipe, 20), a, 10, sigma_start=1.0, sigma_end=0.3)
    stats_fast = train_compiled(b, pipe, 10, chunk=4, sigma_start=1.0, sigma_end=0.3)
    train_compiled(once, pipe, 10, chunk=4, sigma_start=1.0, sigma_end=0.3)
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
    assert np.abs(once.weights[A] - b.weights[A]).max() > 1e-3  # repeated updates happened


def test_policy_files_name_the_options_beyond_the_paper_only_when_set(tmp_path):
    import json

    for options, stored in (
        ({}, set()),
        ({"actor_repeats": "var", "critic_lambda": 0.5}, {"actor_repeats", "critic_lambda"}),
    ):
        path = save_policy(make_agent("cacla", **options), tmp_path / "p.npz")
        with np.load(path, allow_pickle=False) as z:
            keys = set(json.loads(str(z["params"])))
        assert keys & {"actor_repeats", "var_rate", "critic_lambda"} == stored
        assert load_policy(path).params == make_agent("cacla", **options).params
