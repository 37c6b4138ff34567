"""The shipped 30,000-decision recipe is the policy the sample-efficiency table reports.

``examples/recipe-30k.toml`` (an experiment file, ``pipefollow reproduce --experiment``) and the
variant ``supervised-cacla-recipe`` of ``examples/sample_efficiency.py`` (the table's runs) must
train the same weights for the same seed, bit for bit: the two paths share nothing but the
learner, the trainer and the seeding convention, so this holds only while all three agree.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from pipefollow.experiments.config import load_experiment
from pipefollow.experiments.trial import build_agent, run_trial

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
