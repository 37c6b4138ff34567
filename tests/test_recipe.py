"""The shipped recipes are the policies the sample-efficiency table reports.

``examples/recipe-30k.toml`` (an experiment file, ``pipefollow reproduce --experiment``) and the
variant ``supervised-cacla-recipe`` of ``examples/sample_efficiency.py`` (the table's runs) must
train the same weights for the same seed, bit for bit: the two paths share nothing but the
learner, the trainer and the seeding convention, so this holds only while all three agree. The
same for ``examples/recipe-100k.toml`` (the 30,000-decision recipe trained on) and the variant
``supervised-cacla-recipe-100k``.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from pipefollow.experiments.config import load_experiment
from pipefollow.experiments.schema import learner_values
from pipefollow.experiments.trial import build_agent, phase_params, run_trial
from pipefollow.learners.cacla_update import REPEAT_VAR

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _sample_efficiency():
    spec = importlib.util.spec_from_file_location("sample_efficiency", EXAMPLES / "sample_efficiency.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def recipe():
    exp = load_experiment(EXAMPLES / "recipe-30k.toml")
    assert len(exp.trials) == 1
    return exp


def test_recipe_budget_and_seeds_are_the_tables(recipe):
    se = _sample_efficiency()
    (trial,) = recipe.trials
    decisions = sum(ph.episodes for ph in trial.phases) * int(trial.episode_seconds)
    assert trial.episode_seconds == se.EPISODE_S
    assert [ph.pipeline for ph in trial.phases] == [f"random:{se.TRAIN_FAMILY}"]
    assert decisions == (30_000 // int(se.EPISODE_S)) * int(se.EPISODE_S) == 29_970
    assert recipe.seeds() == list(se.SEEDS)


def test_recipe_options_differ_from_the_paper(recipe):
    """The options the file sets reach the agent (a file that silently trained the paper's
    learner would still pass the equality below if the script's variant did the same)."""
    agent = build_agent(recipe.trials[0])
    assert (agent.params.critic_lambda, agent.params.alpha_pi, agent.params.alpha_v) == (0.9, 0.8, 0.6)
    assert agent.params.discount == 0.9 and agent.supervised


@pytest.mark.parametrize("seed", [0, 3])
def test_recipe_trains_the_tables_policy(recipe, seed):
    se = _sample_efficiency()
    agent, steps = se.VARIANTS["supervised-cacla-recipe"][1](30_000, seed)
    result = run_trial(recipe.trials[0], seed)
    assert steps == 29_970
    np.testing.assert_array_equal(result.weights, agent.weights)


@pytest.fixture(scope="module")
def recipe100k():
    exp = load_experiment(EXAMPLES / "recipe-100k.toml")
    assert len(exp.trials) == 1
    return exp


def test_recipe_100k_starts_as_the_30k_recipe(recipe, recipe100k):
    """Its first phase is the 30,000-decision recipe (options, pipes, episodes, seeds), so its policy
    at 29,970 decisions is that recipe's; the phases after it add 70,020 decisions."""
    se = _sample_efficiency()
    (short,), (long,) = recipe.trials, recipe100k.trials
    assert learner_values(long) == learner_values(short)
    assert long.phases[0] == short.phases[0] and long.episode_seconds == short.episode_seconds
    assert long.episodes * int(long.episode_seconds) == (100_000 // int(se.EPISODE_S)) * int(se.EPISODE_S)
    assert all(ph.pipeline == short.phases[0].pipeline for ph in long.phases)
    assert recipe100k.seeds() == recipe.seeds()
    first, then = phase_params(long)
    assert first is None and then.actor_repeats == REPEAT_VAR


@pytest.mark.slow
def test_recipe_100k_trains_the_tables_policy(recipe100k):
    se = _sample_efficiency()
    agent, steps = se.VARIANTS["supervised-cacla-recipe-100k"][1](100_000, 2)
    result = run_trial(recipe100k.trials[0], 2)
    assert steps == 99_990
    np.testing.assert_array_equal(result.weights, agent.weights)
