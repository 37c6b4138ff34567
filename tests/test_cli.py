import csv
import json

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main


@pytest.fixture
def runner():
    return CliRunner()


def test_evaluate_heuristic_json(runner, tmp_path):
    plot = tmp_path / "h.png"
    res = runner.invoke(
        main,
        [
            "evaluate",
            "--controller",
            "heuristic",
            "--pipeline",
            "paper-left",
            "--episodes",
            "2",
            "--json",
            "--plot",
            str(plot),
        ],
    )
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert set(out) >= {"mean_return", "mean_pipe_in_view", "mean_progress_m", "episodes"}
    assert len(out["episodes"]) == 2
    assert set(out["episodes"][0]) >= {"return", "pipe_in_view", "progress_m"}
    assert out["mean_pipe_in_view"] == 1.0
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    "content, message",
    [
        (None, "no such file"),
        ("{not json", "not valid JSON"),
        ('{"pts": []}', '"points"'),
        ('{"points": [[0, 0]]}', "at least two"),
        ('{"points": [[0, 0], [0, 0]]}', "zero-length"),
        ('{"points": [[0, 0], [1, 2, 3]]}', "pairs"),
        ('{"points": [[0, 0], [NaN, 1]]}', "NaN"),
    ],
)
def test_bad_pipeline_file_gives_one_line_error_exit_2(runner, tmp_path, content, message):
    path = tmp_path / "pipe.json"
    if content is not None:
        path.write_text(content)
    res = runner.invoke(main, ["evaluate", "--pipeline", str(path)])
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.output
    assert str(path) in lines[0] and message in lines[0]


def test_unknown_builtin_pipeline(runner):
    res = runner.invoke(main, ["evaluate", "--pipeline", "paper-up"])
    assert res.exit_code == 2
    assert "paper-up" in res.stderr


def test_train_then_evaluate_policy_then_continue(runner, tmp_path):
    out = tmp_path / "run"
    res = runner.invoke(
        main,
        [
            "train",
            "--algorithm",
            "cacla",
            "--skew",
            "22.5",
            "--supervised",
            "--pipeline",
            "paper-left",
            "--episodes",
            "12",
            "--seed",
            "1",
            "--out",
            str(out),
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    result = json.loads(res.stdout)
    assert len(result["returns"]) == 12
    assert (out / "policy.npz").exists() and (out / "learning_curve.csv").exists()
    with open(out / "learning_curve.csv") as f:
        curve = list(csv.DictReader(f))
    np.testing.assert_allclose([float(r["return"]) for r in curve], result["returns"])
    res = runner.invoke(main, ["evaluate", "--controller", result["policy"], "--json"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        main,
        [
            "train",
            "--algorithm",
            "cacla",
            "--skew",
            "22.5",
            "--supervised",
            "--pipeline",
            "paper-right",
            "--episodes",
            "5",
            "--out",
            str(tmp_path / "r2"),
            "--init",
            result["policy"],
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    res = runner.invoke(
        main,
        [
            "train",
            "--algorithm",
            "sarsa",
            "--episodes",
            "2",
            "--out",
            str(tmp_path / "r3"),
            "--init",
            result["policy"],
        ],
    )
    assert res.exit_code == 2


def test_evaluate_rejects_a_foreign_policy_file(runner, tmp_path):
    p = tmp_path / "x.npz"
    np.savez(p, a=np.zeros(2))
    res = runner.invoke(main, ["evaluate", "--controller", str(p)])
    assert res.exit_code == 2
    assert "not a pipefollow policy" in res.stderr


def _one_line_error(res, *fragments):
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.output, res.output
    for f in fragments:
        assert f in lines[0]


def test_train_to_an_unwritable_folder_fails_before_training(runner, tmp_path):
    blocker = tmp_path / "afile"
    blocker.write_text("")
    res = runner.invoke(
        main, ["train", "--algorithm", "cacla", "--episodes", "2", "--out", str(blocker / "sub")]
    )
    _one_line_error(res, "--out", "cannot write there")


@pytest.mark.parametrize(
    "toml, fragment",
    [
        ("trial = [1, 2]\n", "must be a table"),
        ('[experiment]\nname = "x"\n[[trial]]\nname = "t"\nepisode_seconds = 1e308\n', "episode_seconds"),
        ('[experiment]\nname = "x"\n[[trial]]\nname = "t"\nalgoritm = "cacla"\n', "unknown key 'algoritm'"),
        ("[experiment\n", "not valid TOML"),
    ],
)
def test_bad_experiment_file_gives_one_line_error_and_no_run_folder(runner, tmp_path, toml, fragment):
    path = tmp_path / "exp.toml"
    path.write_text(toml)
    out = tmp_path / "run"
    res = runner.invoke(main, ["reproduce", "--experiment", str(path), "--out", str(out), "--no-figures"])
    _one_line_error(res, str(path), fragment)
    assert not out.exists()


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["train", "--algorithm", "cacla", "--episodes", "0"], "--episodes"),
        (["train", "--algorithm", "cacla", "--skew", "nan"], "--skew"),
        (["train", "--algorithm", "cacla", "--seconds", "inf"], "--seconds"),
        (["train", "--algorithm", "cacla", "--reading", "skew_step=gamma2"], "'skew_step' must be one of"),
        (["train", "--algorithm", "cacla", "--reading", "nope=1"], "unknown key 'nope'"),
        (["evaluate", "--reading", "start_speed"], "expected key=value"),
        (["evaluate", "--start-noise", "nan"], "--start-noise"),
        (["evaluate", "--bogus"], "--bogus"),
    ],
)
def test_bad_options_give_one_line_errors_and_write_nothing(runner, tmp_path, args, fragment):
    out = tmp_path / "out"
    res = runner.invoke(main, [*args, *(["--out", str(out)] if args[0] == "train" else [])])
    _one_line_error(res, fragment)
    assert not out.exists()


def test_rejected_init_leaves_no_output_folder(runner, tmp_path):
    res = runner.invoke(
        main, ["train", "--algorithm", "sarsa", "--episodes", "2", "--out", str(tmp_path / "a")]
    )
    assert res.exit_code == 0, res.output
    out = tmp_path / "b"
    res = runner.invoke(
        main,
        ["train", "--algorithm", "cacla", "--init", str(tmp_path / "a" / "policy.npz"), "--out", str(out)],
    )
    _one_line_error(res, "not cacla")
    assert not out.exists()
