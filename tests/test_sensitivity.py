"""The readings experiment: expanding trials per reading, the claims under each, readings.csv."""

import csv
import json

import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.experiments import sensitivity
from pipefollow.experiments.claims import CONFIRMED, NOT_CONFIRMED, NOT_TESTED
from pipefollow.experiments.config import load_experiment
from pipefollow.experiments.schema import ConfigError

SMALL = """
[experiment]
name = "small-readings"
repeats = 2
trials_from = "paper"
compare_readings = ["default", "skew_step=weights", "converge_in_view=0.99", "start_speed=cruise"]
"""


def test_expand_trains_each_training_reading_once():
    exp = load_experiment("readings")
    assert exp.repeats >= 10 and len(exp.compare_readings) >= 10
    base = load_experiment("paper")
    assert [t.name for t in exp.trials] == [t.name for t in base.trials]
    big = sensitivity.expand(exp)
    training = {sensitivity.training_id(r) for r in exp.compare_readings}
    assert "default" in training and not any("converge" in t for t in training)
    assert len(big.trials) == len(base.trials) * len(training)
    t = big.trial("cacla-skew22.5@skew_step=weights")
    assert t.reading.skew_step == "weights" and t.skew_deg == 22.5 and t.label == "CACLA, skew 22.5°"
    # a report-only reading judges the default runs with its thresholds
    judged = sensitivity.under(big, "converge_in_view=0.99")
    assert [t.name for t in judged.trials] == [f"{b.name}@default" for b in base.trials]
    assert all(t.reading.converge_in_view == 0.99 for t in judged.trials)
    assert sensitivity.expand(load_experiment("paper")) == load_experiment("paper")


def test_duplicate_or_bad_compared_readings_are_refused(tmp_path):
    path = tmp_path / "x.toml"
    path.write_text(SMALL.replace('"start_speed=cruise"', '"skew_step=weights,skew_step=weights"'))
    with pytest.raises(ConfigError, match="the same reading appears twice: skew_step=weights"):
        sensitivity.expand(load_experiment(path))
    path.write_text(SMALL.replace('"start_speed=cruise"', '"start_speed=fast"'))
    with pytest.raises(ConfigError, match="compare_readings.*'start_speed' must be one of rest, cruise"):
        load_experiment(path)


def test_verdict_lines():
    rows = tuple(
        sensitivity.Row(r, c, "s", 1, 2, v)
        for r, c, v in [
            ("default", "1a", CONFIRMED),
            ("x=1", "1a", CONFIRMED),
            ("default", "1b", NOT_CONFIRMED),
            ("x=1", "1b", NOT_CONFIRMED),
            ("default", "2a", CONFIRMED),
            ("x=1", "2a", NOT_CONFIRMED),
            ("default", "2b", NOT_TESTED),
        ]
    )
    s = sensitivity.Sensitivity(None, ("default", "x=1"), {}, rows)
    assert s.verdict_line("1a") == sensitivity.HOLDS
    assert s.verdict_line("1b") == sensitivity.FAILS
    assert s.verdict_line("2a") == "depends on the reading: holds under `default`; fails under `x=1`"
    assert s.verdict_line("2b") == "not tested under any reading"


@pytest.mark.slow  # a readings run with its report (≈ 1.5 s)
def test_a_small_readings_run_writes_the_table_and_the_report(tmp_path):
    toml = tmp_path / "small.toml"
    toml.write_text(SMALL)
    out = tmp_path / "run"
    args = ["reproduce", "--experiment", str(toml), "--out", str(out), "--episodes", "3"]
    args += ["--backend", "serial"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    config = json.loads((out / "config.json").read_text())
    assert len(config["trials"]) == 8 * 3  # default, skew_step=weights, start_speed=cruise train
    with (out / "readings.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["reading", "claim", "passed", "repeats", "verdict"]
    claims = ["1a", "1b", "1c", "2a", "2b", "3a", "3b", "4a", "4b"]
    readings = ["default", "skew_step=weights", "converge_in_view=0.99", "start_speed=cruise"]
    assert [(r["reading"], r["claim"]) for r in rows] == [(r, c) for r in readings for c in claims]
    by = {(r["reading"], r["claim"]): r for r in rows}
    for r in rows:
        assert 0 <= int(r["passed"]) <= int(r["repeats"])
        assert r["verdict"] in (CONFIRMED, NOT_CONFIRMED)
    assert by["default", "1b"]["repeats"] == "2" and by["default", "2a"]["repeats"] == "8"
    # the threshold reading re-judges the default runs: Table 1 counts are the same runs'
    assert by["converge_in_view=0.99", "4a"] == {**by["default", "4a"], "reading": "converge_in_view=0.99"}
    report = (out / "REPORT.md").read_text()
    assert "| `skew_step=weights` |" in report and "## The open points" in report
    per_setup = report.split("## Per set-up")[1].split("## The open points")[0]
    assert all(f"| `{r}` | " in per_setup for r in readings)
    for c in claims:
        assert f"- **{c}**" in report
    assert "claim 1a:" in result.output


def test_readings_csv_reads_back_to_the_same_verdicts(tmp_path):
    toml = tmp_path / "small.toml"
    toml.write_text(SMALL)
    out = tmp_path / "run"
    args = ["reproduce", "--experiment", str(toml), "--out", str(out), "--episodes", "2", "--repeats", "1"]
    assert CliRunner().invoke(main, [*args, "--backend", "serial"]).exit_code == 0
    computed = sensitivity.load(out)
    back = sensitivity.read_csv(out / sensitivity.READINGS_CSV)
    assert back.readings == computed.readings and back.claim_ids() == computed.claim_ids()
    assert all(back.verdict_line(c) == computed.verdict_line(c) for c in computed.claim_ids())
