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


def test_a_reading_that_cannot_change_an_evaluation_is_warned_about(runner):
    res = runner.invoke(main, ["evaluate", "--reading", "rbf=literal,start_speed=cruise", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert len(out["warnings"]) == 1 and out["warnings"][0].startswith("--reading rbf: acts in training only")
    assert "pipefollow: warning: --reading rbf" in res.stderr and "start_speed:" not in res.stderr
    quiet = runner.invoke(main, ["benchmark", "--pipes", "2", "--reading", "start_speed=cruise", "--json"])
    assert "warnings" not in json.loads(quiet.stdout) and quiet.stderr == ""


def test_the_readings_said_to_act_in_an_evaluation_are_those_the_simulation_reads():
    from pipefollow import readings as rd

    acting = set()
    for point in rd.OPEN_POINTS:
        other = [c for c in point.choices if c != point.default] or ["0.5"]
        changed = rd.parse(f"{point.key}={other[0]}")
        if rd.sim_params(changed) != rd.sim_params(rd.DEFAULT):
            acting.add(point.key)
    assert acting == set(rd.SIM_READINGS)


def test_the_text_report_names_the_disturbances(runner):
    res = runner.invoke(main, ["evaluate", "--current", "0.1,45", "--camera-noise", "0.05"])
    assert res.exit_code == 0, res.output
    head = res.stdout.splitlines()[0]
    assert "disturbances: current 0.1 m/s towards 45°, camera noise 0.05 m" in head
    res = runner.invoke(main, ["benchmark", "--pipes", "2", "--miss-prob", "0.1"])
    assert "disturbances   missed detections 10%" in res.stdout


def test_identical_episodes_are_said_to_be_identical(runner):
    res = runner.invoke(main, ["evaluate", "--episodes", "3"])
    assert "the 3 episodes are the same" in res.stderr
    for extra in (["--start-noise", "0.2"], ["--camera-noise", "0.05"], ["--pipeline", "random:easy"]):
        assert "are the same" not in runner.invoke(main, ["evaluate", "--episodes", "3", *extra]).stderr


def _completions(args: list[str], incomplete: str) -> list[tuple[str, str]]:
    from click.shell_completion import ShellComplete

    items = ShellComplete(main, {}, "pipefollow", "_PIPEFOLLOW_COMPLETE").get_completions(args, incomplete)
    return [(i.value, i.type) for i in items]


@pytest.mark.parametrize(
    "args, incomplete, expected",
    [
        (["evaluate", "--pipeline"], "paper-l", ("paper-left", "plain")),
        (["train", "--pipeline"], "random:h", ("random:hard", "plain")),
        (["evaluate", "--controller"], "heu", ("heuristic", "plain")),
        (["benchmark", "--suite"], "heldout-e", ("heldout-easy", "plain")),
        (["compare", "heuristic", "--suite"], "heldout-h", ("heldout-hard", "plain")),
    ],
)
def test_completion_offers_names_and_then_files(args, incomplete, expected):
    got = _completions(args, incomplete)
    assert expected in got and (incomplete, "file") in got


def _all_commands():
    import click

    from pipefollow import cli

    todo = [cli.main.get_command(click.Context(cli.main), n) for n in cli.COMMANDS]
    while todo:
        cmd = todo.pop()
        yield cmd
        if isinstance(cmd, click.Group):
            todo += list(cmd.commands.values())


def test_every_option_has_help():
    import click

    missing = [
        f"{cmd.name} {p.opts[0]}"
        for cmd in _all_commands()
        for p in cmd.params
        if isinstance(p, click.Option) and not p.hidden and not (p.help or "").strip()
    ]
    assert missing == []


def test_a_plot_without_suffix_says_so(runner):
    line = _error(runner.invoke(main, ["evaluate", "--plot", "h"]))
    assert "--plot 'h': has no suffix to tell the file type; use one of" in line


@pytest.mark.slow
def test_reproduce_says_one_worker_and_prints_progress_lines_off_a_terminal(runner, tmp_path, monkeypatch):
    monkeypatch.setattr(progress, "INTERVAL_S", 0.0)
    args = ["reproduce", "--trial", "sarsa", "--repeats", "1", "--episodes", "3", "--backend", "serial"]
    res = runner.invoke(main, [*args, "--no-figures", "--out", str(tmp_path / "r")])
    assert res.exit_code == 0, res.output
    assert "(1 worker)" in res.stdout and "(1 workers)" not in res.stdout
    assert "paper: trials: 1/1 trials (100%)" in res.stderr


def test_no_command_writes_into_the_repositorys_docs_by_default():
    # committed results are written only by their documented regeneration commands (--out docs/...)
    import click

    from pipefollow.cli import COMMANDS, main

    ctx = click.Context(main)
    found = []
    for name in COMMANDS:
        cmd = main.get_command(ctx, name)
        commands = list(cmd.commands.values()) if isinstance(cmd, click.Group) else [cmd]
        for c in commands:
            for p in c.params:
                path = p.default.replace("\\", "/").lstrip("./") if isinstance(p.default, str) else ""
                if path.startswith("docs"):
                    found.append(f"{name} {c.name} {p.opts}: {p.default}")
    # the one exception: `docs results` reads the stored outputs of --docs and regenerates the
    # committed pages in DOCS/results (its help says so); its --out has no default of its own
    assert found == ["docs results ['--docs']: docs"]
