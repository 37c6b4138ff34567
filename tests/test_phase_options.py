"""A training phase's own learner options (an experiment file's phase ``learner`` table)."""

from __future__ import annotations

import numpy as np
import pytest

from pipefollow.experiments.config import load_experiment
from pipefollow.experiments.schema import ConfigError
from pipefollow.experiments.trial import build_agent, phase_params
from pipefollow.learners.cacla_update import REPEAT_ONCE, REPEAT_VAR
from pipefollow.training.agents import make_agent
from pipefollow.training.phases import agent_rng, train_phases

HEAD = '[experiment]\nname = "x"\nrepeats = 1\nseed = 0\n\n[[trial]]\nname = "t"\nalgorithm = "{algorithm}"\n'


def _load(tmp_path, phases: str, algorithm: str = "cacla"):
    path = tmp_path / "x.toml"
    path.write_text(HEAD.format(algorithm=algorithm) + f"phases = {phases}\n")
    return load_experiment(path)


def _trained(phases, records, seed=3):
    agent = make_agent("cacla", supervised=True, rng=agent_rng(seed), critic_lambda=0.9)
    train_phases(agent, phases, seed=seed, episode_seconds=20.0, phase_params=records)
    return agent


PHASES = [("random:mixed", 4), ("random:mixed", 4)]


def test_a_phase_repeating_the_trials_options_trains_the_same_weights():
    own = make_agent("cacla", supervised=True, critic_lambda=0.9).params
    plain = _trained(PHASES, None)
    same = _trained(PHASES, [None, own])
    np.testing.assert_array_equal(plain.weights, same.weights)


def test_a_phases_options_reach_the_compiled_loop_and_end_with_it():
    var = make_agent("cacla", supervised=True, critic_lambda=0.9, actor_repeats="var", alpha_pi=0.5).params
    plain = _trained(PHASES, None)
    agent = _trained(PHASES, [None, var])
    assert agent.params.actor_repeats == REPEAT_VAR
    assert agent.td_var[0] != 1.0  # CACLA+Var's running variance moved only in the second phase
    assert not np.array_equal(plain.weights, agent.weights)  # the second phase's α_π
    first = _trained(PHASES[:1], None)  # the first phase alone: the same as without the table
    again = _trained([*PHASES[:1], ("random:mixed", 4), ("random:mixed", 4)], [None, var, None])
    assert again.params.actor_repeats == REPEAT_ONCE  # a phase without a table: the trial's own
    assert first.td_var[0] == 1.0


def test_phase_params_must_match_the_phases():
    with pytest.raises(ValueError, match="one entry per phase"):
        _trained(PHASES, [None])


def test_experiment_file_phase_learner_table(tmp_path):
    second = '{pipeline = "random:mixed", episodes = 2, learner = {actor_repeats = "var", alpha_pi = 0.5}}'
    exp = _load(tmp_path, f'[{{pipeline = "random:mixed", episodes = 2}}, {second}]')
    (trial,) = exp.trials
    first, second = phase_params(trial)
    assert first is None
    own = build_agent(trial).params
    assert (second.actor_repeats, second.alpha_pi, second.alpha_v) == (REPEAT_VAR, 0.5, own.alpha_v)


@pytest.mark.parametrize(
    ("table", "algorithm", "message"),
    [
        ("{skew_deg = 22.5}", "cacla", "may set actor_repeats, critic_lambda"),
        ("{critic_lambda = 1.5}", "cacla", r"key 'learner.critic_lambda' must be in \[0, 1\], got 1.5"),
        ('{actor_repeats = "often"}', "cacla", "key 'learner.actor_repeats' must be one of once, var"),
        ("{alpha_q = 0.1}", "cacla", "key 'learner.alpha_q' applies to algorithm sarsa only"),
        ('{actor_repeats = "var"}', "sarsa", "key 'learner.actor_repeats' applies to algorithm cacla only"),
        ('"var"', "cacla", "must be a table of learner options"),
    ],
)
def test_bad_phase_learner_tables_are_one_line_errors(tmp_path, table, algorithm, message):
    with pytest.raises(ConfigError, match=message) as err:
        _load(tmp_path, f'[{{pipeline = "random:mixed", episodes = 2, learner = {table}}}]', algorithm)
    assert "\n" not in str(err.value)


def test_retune_refuses_a_change_of_the_heads():
    agent = make_agent("cacla", supervised=True)
    with pytest.raises(ValueError, match="skew or the supervisor"):
        agent.retune(make_agent("cacla", supervised=False).params)


def test_trials_lists_a_phases_own_options(tmp_path):
    from pipefollow.cli.tables import table, trials

    second = '{pipeline = "random:mixed", episodes = 3, learner = {actor_repeats = "var"}}'
    exp = _load(tmp_path, f'[{{pipeline = "random:mixed", episodes = 2}}, {second}]')
    (row,) = trials(exp)
    assert row["phases"][0] == {"pipeline": "random:mixed", "episodes": 2}
    assert row["phases"][1]["learner"] == {"actor_repeats": "var"}
    text = table([row], [("phases", "phases")])
    assert "random:mixed ×2 then random:mixed ×3 (actor_repeats var)" in text
