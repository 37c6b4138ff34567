"""A report of the user's own experiment: titled by it, no paper's claims, no links it does not hold."""

from __future__ import annotations

import re

import numpy as np
import pytest

from pipefollow.experiments import report
from pipefollow.experiments.schema import ExperimentConfig, Phase, TrialConfig
from test_report import EPISODES, REPEATS, make_run, provide_trial_files


def _converging(repeat, episodes):
    e = np.arange(episodes)
    return -100.0 + 90.0 * (1 - np.exp(-e / 30.0)) + repeat, np.full(episodes, 0.99), np.full(episodes, 6.0)


@pytest.fixture
def custom_run(tmp_path, monkeypatch):
    phases = (Phase("paper-right", EPISODES),)
    trial = TrialConfig("mine", "my CACLA", algorithm="cacla", phases=phases, figures=())
    exp = ExperimentConfig("curvy", repeats=REPEATS, seed=2010, trials=(trial,))
    run, trials = make_run(tmp_path, exp, spec_override={"mine": _converging})
    provide_trial_files(run, trials, monkeypatch)
    return run


def test_a_custom_experiment_is_titled_by_itself_and_states_no_claims(custom_run):
    report.write_outputs(custom_run)
    text = (custom_run / "REPORT.md").read_text()
    assert text.startswith("# Experiment `curvy`: results\n")
    assert "Reproduction report" not in text
    assert not re.search(r"[Cc]laim \d", text) and "not tested" not in text
    assert "paper-left" not in text  # the convergence rule is not explained by a pipe it did not use


def test_a_report_links_only_files_its_run_folder_holds(custom_run):
    report.write_outputs(custom_run)
    text = (custom_run / "REPORT.md").read_text()
    links = re.findall(r"\]\(([^)]+)\)", text)
    assert all((custom_run / link).is_file() for link in links), links
    assert "readings/REPORT.md" not in text
