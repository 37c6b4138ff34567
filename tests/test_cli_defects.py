"""Defects a new user hit on the command line (issue "what a new user hit"), one test each."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.files import progress


@pytest.fixture
def runner():
    return CliRunner()


def _error(res) -> str:
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.output
    return lines[0]


@pytest.fixture(scope="module")
def policy_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "skewed"
    args = [
        "train",
        "--algorithm",
        "cacla",
        "--supervised",
        "--skew",
        "22.5",
        "--episodes",
        "5",
        "--out",
        str(out),
    ]
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    return out


def test_training_prints_progress_lines_when_stderr_is_not_a_terminal(runner, tmp_path, monkeypatch):
    monkeypatch.setattr(progress, "INTERVAL_S", 0.0)
    res = runner.invoke(
        main, ["train", "--algorithm", "cacla", "--episodes", "30", "--out", str(tmp_path / "r")]
    )
    assert res.exit_code == 0, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("training CACLA: ")]
    assert lines and lines[-1].startswith("training CACLA: 30/30 episodes (100%)")


def test_progress_lines_come_at_intervals_and_at_the_end(monkeypatch):
    import io

    out = io.StringIO()
    clock = iter([0.0, 1.0, 5.0, 12.0, 13.0, 25.0, 26.0])
    monkeypatch.setattr(progress.time, "perf_counter", lambda: next(clock))
    with progress.progress(5, "work", file=out, unit="items") as bar:
        for _ in range(5):
            bar.update(1)
    assert out.getvalue().splitlines() == ["work: 3/5 items (60%), 12 s", "work: 5/5 items (100%), 26 s"]


def test_deep_training_errors_name_the_real_options(runner, tmp_path):
    args = [
        "train",
        "--algorithm",
        "ppo",
        "--out",
        str(tmp_path / "d"),
        "--init",
        "x.npz",
        "--reading",
        "rbf=literal",
    ]
    line = _error(runner.invoke(main, args))
    assert "--init, --reading not available with --algorithm ppo" in line
    assert "--init-policy" not in line and "--readings" not in line and "--steps" not in line
    line = _error(
        runner.invoke(main, ["train", "--algorithm", "sac", "--episodes", "3", "--out", str(tmp_path)])
    )
    assert line.endswith("--episodes not available with --algorithm sac; its budget is --steps")


def test_an_unknown_controller_suggests_the_closest(runner):
    line = _error(runner.invoke(main, ["evaluate", "--controller", "heurstic"]))
    assert "did you mean 'heuristic'?" in line and "no such file" not in line


def test_a_folder_holding_policy_npz_is_a_controller(runner, policy_dir):
    by_folder = json.loads(
        runner.invoke(main, ["evaluate", "--controller", str(policy_dir), "--json"]).stdout
    )
    by_file = runner.invoke(main, ["evaluate", "--controller", str(policy_dir / "policy.npz"), "--json"])
    assert by_folder["mean_return"] == json.loads(by_file.stdout)["mean_return"]


def test_a_folder_without_a_policy_is_named(runner, tmp_path):
    line = _error(runner.invoke(main, ["evaluate", "--controller", str(tmp_path)]))
    assert "a folder without policy.npz" in line


def test_train_init_keeps_the_saved_options_and_names_those_that_differ(runner, policy_dir, tmp_path):
    res = runner.invoke(main, ["train", "--algorithm", "cacla", "--episodes", "3", "--init", str(policy_dir),
                               "--out", str(tmp_path / "more"), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["algorithm"] == "supervised CACLA, skew 22.5°"
    args = ["train", "--algorithm", "cacla", "--episodes", "3", "--skew", "45", "--init", str(policy_dir)]
    line = _error(runner.invoke(main, [*args, "--out", str(tmp_path / "other")]))
    assert "skew 0.5 (this run: 1.0)" in line and "supervised" not in line.split("options differ")[1]
    assert not (tmp_path / "other").exists()
