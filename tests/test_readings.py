"""Readings of the open points: ids, parsing, and what each reading does to the layers below."""

import dataclasses
import math

import numpy as np
import pytest

from pipefollow import readings as rd
from pipefollow.learners import cacla, cacla_act, cacla_update
from pipefollow.learners.rbf import STATE_CENTRES
from pipefollow.sim import decision as sim
from pipefollow.training.agents import make_agent
from pipefollow.training.policy_files import load_policy, save_policy


def test_every_open_point_is_a_field_with_its_default():
    fields = {f.name: f.default for f in dataclasses.fields(rd.Readings)}
    assert list(fields) == [p.key for p in rd.OPEN_POINTS]
    for p in rd.OPEN_POINTS:
        assert rd.parse(f"{p.key}={p.default}") == rd.DEFAULT  # the stated default is the field's
        assert p.paper and p.meaning
        if p.choices:
            assert p.default in p.choices


def test_ids_parse_join_and_canonicalize():
    assert rd.DEFAULT.id == "default"
    r = rd.parse(["start_speed=cruise,skew_step=weights", "gamma_max=2"])
    assert (r.skew_step, r.start_speed, r.gamma_max) == ("weights", "cruise", 2.0)
    assert r.id == "skew_step=weights,gamma_max=2,start_speed=cruise"  # the order of OPEN_POINTS
    assert rd.parse(r.id) == r
    assert rd.parse(["skew_step=weights", "skew_step=gamma"]) == rd.DEFAULT  # later ones win
    assert rd.parse("default") == rd.parse([]) == rd.parse(" ") == rd.DEFAULT
    assert rd.parse("converge_in_view=0.99").training == rd.DEFAULT
    assert rd.parse("rbf=literal,converge_in_view=0.99").training == rd.parse("rbf=literal")


@pytest.mark.parametrize(
    "rid, message",
    [
        ("skew_step", r"expected key=value, got 'skew_step'"),
        ("skew=1", r"unknown key 'skew'; known: skew_step"),
        ("skew_sample=mean", r"'skew_sample' must be one of location, centred, moments, got 'mean'"),
        ("gamma_max=0", r"'gamma_max' must be a number in \(0, 100\]"),
        ("gamma_max=nan", r"'gamma_max' must be"),
        ("converge_in_view=1.5", r"'converge_in_view' must be a fraction from 0 to 1"),
        ("converge_progress_m=inf", r"'converge_progress_m' must be a finite number"),
    ],
)
def test_bad_ids_name_the_reading_and_what_is_allowed(rid, message):
    with pytest.raises(rd.ReadingError, match=message):
        rd.parse(rid)


def test_skew_unit_and_sigma_unit():
    assert rd.skew_gamma(22.5) == 0.5  # "22.5° equals absolute value of 0.5"
    assert rd.skew_gamma(22.5, rd.parse("skew_unit=rad")) == pytest.approx(math.pi / 8)
    assert rd.sigma_scale() == 1.0
    assert rd.sigma_scale(rd.parse("sigma_unit=rad")) * math.pi / 2 == pytest.approx(1.0)


def test_cacla_params_under_each_reading():
    p = rd.cacla_params(skew_deg=45.0, supervised=True)
    expected = (1.0, 1.0, cacla_update.STEP_GAMMA, cacla.SAMPLE_LOCATION)
    assert (p.skew, p.gamma_max, p.skew_step, p.skew_sample) == expected
    assert (p.k_update, p.k_step, p.supervised) == (cacla_update.K_EVERY, cacla_update.STEP_WEIGHTS, True)
    r = rd.parse("skew_step=weights,skew_sample=moments,gamma_max=0.5,k_update=positive,k_step=k")
    q = rd.cacla_params(r, 22.5)
    assert (q.skew_step, q.skew_sample, q.gamma_max) == (cacla_update.STEP_WEIGHTS, cacla.SAMPLE_MOMENTS, 0.5)
    assert (q.k_update, q.k_step) == (cacla_update.K_POSITIVE, cacla_update.STEP_GAMMA)
    np.testing.assert_array_equal(cacla_act.unpack(cacla_act.pack(q)), q)  # the packed form keeps them


def test_every_learner_has_its_inputs_under_the_readings():
    from pipefollow.learners import registry

    assert set(rd.LEARNER_INPUTS) == set(registry.NAMES)
    r = rd.parse("rbf=literal,skew_unit=rad")
    for name in registry.NAMES:
        inputs = rd.learner_inputs(name, r)
        assert inputs["grid"] == rd.state_grid(r)
        agent = registry.learner(name).make(**inputs, readings=r.id)
        assert agent.params == inputs["params"] and agent.readings == r.id
    assert rd.learner_inputs("sarsa", r)["action_grid"] == rd.action_grid(r)
    assert rd.learner_inputs("ac", r)["params"] == rd.actor_critic_params(r)


def test_rbf_readings_reach_both_learners():
    r = rd.parse("rbf=literal,rbf_width=half-range")
    for agent in (make_agent("cacla", readings=r), make_agent("sarsa", readings=r)):
        assert agent.grid.form == "literal" and agent.grid.width == "half-range"
        assert agent.readings == r.id
        # half the span of the centres: x1 spans 2 m, y1 3 m, v_x 0.75 m/s
        np.testing.assert_allclose(agent.grid.widths, [(c[-1] - c[0]) / 2 for c in STATE_CENTRES])
    assert make_agent("sarsa", readings=r).action_grid.width == "half-range"
    assert make_agent("cacla").grid.width == "half-spacing"


def test_cruise_start_is_the_steady_speed_of_action_zero():
    # independent check: integrate the closed loop with the waypoint straight ahead until it settles
    pts = np.array([[0.0, 0.0], [300.0, 0.0]])
    cum = np.array([0.0, 300.0])
    p = sim.PAPER_SIM
    s = np.empty(sim.STATE_SIZE)
    sim.init_state(s, pts, cum, 0.0, 0.0, 0.0, p)
    for _ in range(120):
        sim.decide(s, 0.0, pts, cum, p)
    assert rd.CRUISE_SPEED == pytest.approx(s[sim.U], abs=1e-3)
    # a cruise start begins there and stays there
    q = rd.sim_params(rd.parse("start_speed=cruise"))
    sim.init_state(s, pts, cum, 0.0, 0.0, 0.0, q)
    assert s[sim.U] == s[sim.VX] == rd.CRUISE_SPEED
    sim.decide(s, 0.0, pts, cum, q)
    assert s[sim.U] == pytest.approx(rd.CRUISE_SPEED, abs=1e-3)
    assert rd.sim_params().start_speed == 0.0


def test_policy_files_keep_their_readings(tmp_path):
    r = rd.parse("skew_step=weights,rbf_width=half-range")
    agent = make_agent("cacla", skew_deg=22.5, readings=r, rng=np.random.default_rng(0))
    agent.weights[:] = np.random.default_rng(1).normal(size=agent.weights.shape)
    back = load_policy(save_policy(agent, tmp_path / "p.npz"))
    assert back.readings == r.id and back.params == agent.params and back.grid == agent.grid
    np.testing.assert_array_equal(back.weights, agent.weights)


def test_a_trial_applies_its_readings_to_sigma_start_and_features():
    from pipefollow.experiments.schema import Phase, TrialConfig
    from pipefollow.experiments.trial import build_agent, run_trial

    base = TrialConfig(name="t", phases=(Phase("paper-left", 3),), skew_deg=22.5)
    t = dataclasses.replace(base, readings=("sigma_unit=rad", "start_speed=cruise,rbf=literal"))
    r = run_trial(t, 1)
    np.testing.assert_allclose(r.sigma, [2 / math.pi, (1 + 0.01) / math.pi, 0.02 / math.pi])
    assert build_agent(t).grid.form == "literal" and build_agent(base).grid.form == "normalized"
    assert not np.array_equal(run_trial(base, 1).stats, r.stats)
