"""The reference learners' update rules (eqs. 9 and 11) against hand-computed steps, beside CACLA's."""

import numpy as np
import pytest

from pipefollow.learners import actor_critic as ac
from pipefollow.learners import cacla, cacla_act
from pipefollow.learners.cacla_update import A, K, V
from pipefollow.training.agents import make_agent

PHI = np.array([1.0, 0.0, 0.0])  # one feature: each head's value is its first weight
ALPHA_V, ALPHA_PI = 0.4, 0.2


def one_update(agent_class, p, reward, a_rl, a_sup=0.0, k=0.0):
    """One update as ``agent_class``'s agents make it: CACLA's entry point with the class's step factor."""
    w = np.zeros((4, 3))
    w[K, 0] = k
    hp, rule, var, trace = cacla_act.pack(p), agent_class.rule(p), np.ones(1), np.zeros(3)
    delta = cacla_act.update_packed(w, PHI, a_rl, a_sup, reward, 0.0, np.zeros(3), hp, rule, var, trace)
    return delta, w


@pytest.mark.parametrize(
    ("update", "reward", "actor"),
    [
        # δ = r (V = 0, no bootstrap); actor step α_π · factor(δ) · (a − A(s)) with A(s) = 0, a = 0.5
        ("delta", -2.0, ALPHA_PI * -2.0 * 0.5),  # eq. 9: away from an action with δ < 0
        ("delta", 3.0, ALPHA_PI * 3.0 * 0.5),  # and towards it by δ's size
        ("positive", -2.0, 0.0),  # max term alone: no step when δ ≤ 0
        ("positive", 3.0, ALPHA_PI * 3.0 * 0.5),
        ("sign", -2.0, ALPHA_PI * -1.0 * 0.5),  # sign term alone: a unit step both ways
        ("sign", 3.0, ALPHA_PI * 1.0 * 0.5),
    ],
)
def test_actor_critic_steps_by_hand(update, reward, actor):
    p = ac.PAPER_AC._replace(actor_update=ac.ACTOR_UPDATES[update])
    delta, w = one_update(ac.ActorCritic, p, reward, 0.5)
    assert delta == reward
    assert w[V, 0] == pytest.approx(ALPHA_V * reward) and w[A, 0] == pytest.approx(actor)


@pytest.mark.parametrize("reward", [-2.0, 3.0])
def test_cacla_is_the_actor_critic_with_both_terms(reward):
    _, w_cacla = one_update(cacla.Cacla, cacla_act.PAPER_CACLA, reward, 0.5)
    assert w_cacla[A, 0] == pytest.approx(ALPHA_PI * 0.5 if reward > 0 else 0.0)  # max(sgn δ, 0)


def test_supervised_actor_critic_is_eq_11_by_hand():
    p = ac.PAPER_AC._replace(supervised=True)
    delta, w = one_update(ac.ActorCritic, p, -2.0, 0.5, a_sup=-0.4, k=0.5)
    # α_π [k δ (a_RL − A) + (1 − k)(a_SUP − A)] with k = 0.5, δ = −2, A = 0
    assert w[A, 0] == pytest.approx(ALPHA_PI * (0.5 * -2.0 * 0.5 + 0.5 * -0.4))
    assert w[K, 0] == pytest.approx(0.5 + 0.05)  # eq. 13: k(s) grows by Δk·φ at every visit
    _, w12 = one_update(
        cacla.Cacla, cacla_act.PAPER_CACLA._replace(supervised=True), -2.0, 0.5, a_sup=-0.4, k=0.5
    )
    assert w12[A, 0] == pytest.approx(ALPHA_PI * 0.5 * -0.4)  # eq. 12: the RL part drops out for δ < 0


def test_the_actor_critic_takes_no_skew_and_names_its_update():
    with pytest.raises(ValueError, match="skew must be 0"):
        ac.ActorCritic(ac.PAPER_AC._replace(skew=0.5))
    with pytest.raises(ValueError, match="actor_update must be one of delta, positive, sign"):
        make_agent("ac", actor_update="max")
    assert make_agent("ac").name == "actor-critic"
    assert make_agent("ac", supervised=True, actor_update="sign").name == "supervised actor-critic, sgn(δ)"
    with pytest.raises(ValueError, match="actor_update applies to algorithm ac only"):
        make_agent("cacla", actor_update="sign")


def test_cacla_code_reads_the_actor_critic_record():
    # CACLA's compiled code reads the first fields of the packed record; the step factor goes beside it
    from pipefollow.sim import records

    assert ac.ActorCriticParams._fields == (*cacla_act.CaclaParams._fields, "actor_update")
    assert ac.PAPER_AC == (*cacla_act.PAPER_CACLA, ac.DELTA)  # CACLA's defaults, then eq. 9's δ
    p = ac.PAPER_AC._replace(supervised=True, alpha_pi=0.3, delta_k=0.07, actor_update=ac.SIGN)
    expected = cacla_act.CaclaParams(supervised=True, alpha_pi=0.3, delta_k=0.07)
    assert cacla_act.unpack(records.pack(p)) == expected
    assert ac.ActorCritic(p).rule(p) == ac.SIGN
    assert cacla.Cacla().rule(cacla_act.PAPER_CACLA) == cacla.SIGN_AND_MAX
