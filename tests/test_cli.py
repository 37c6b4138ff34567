import csv
import json

import click
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


def test_bare_command_prints_help_to_stdout_and_exits_0(runner):
    res = runner.invoke(main, [])
    assert res.exit_code == 0, res.output
    assert res.stdout.startswith("Usage:") and "evaluate" in res.stdout
    assert "error" not in res.output


TRAIN = ["train", "--algorithm", "sarsa", "--episodes", "2"]


@pytest.mark.parametrize(
    "args",
    [
        ["evaluate", "--seed", "-1"],
        [*TRAIN, "--seed", "-1"],
        ["reproduce", "--quick", "--seed", "-1", "--backend", "serial"],
    ],
)
def test_negative_seed_is_a_one_line_error_and_writes_nothing(runner, tmp_path, args):
    out = tmp_path / "out"
    res = runner.invoke(main, [*args, *(["--out", str(out)] if args[0] != "evaluate" else [])])
    _one_line_error(res, "--seed", "-1")
    assert not out.exists()


def test_seeds_beyond_64_bits_work_everywhere(runner, tmp_path):
    huge = str(2**64)
    res = runner.invoke(main, ["evaluate", "--seed", huge, "--start-noise", "0.5", "--json"])
    assert res.exit_code == 0, res.output
    # the seed reaches the start perturbation: another seed gives another start
    other = runner.invoke(main, ["evaluate", "--seed", str(2**64 + 1), "--start-noise", "0.5", "--json"])
    assert json.loads(res.stdout)["mean_return"] != json.loads(other.stdout)["mean_return"]
    res = runner.invoke(main, [*TRAIN, "--seed", huge, "--out", str(tmp_path / "t"), "--json"])
    assert res.exit_code == 0, res.output
    out = tmp_path / "r"
    args = ["reproduce", "--seed", huge, "--out", str(out), "--backend", "serial", "--no-figures"]
    res = runner.invoke(main, [*args, "--trial", "sarsa", "--repeats", "1", "--episodes", "2", "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["trials"]["sarsa"]["seeds"] == [2**64]
    assert (out / "policies" / f"sarsa-seed{huge}.npz").exists()


def test_train_refuses_to_replace_a_policy_unless_forced(runner, tmp_path):
    out = tmp_path / "run"
    assert runner.invoke(main, [*TRAIN, "--out", str(out)]).exit_code == 0
    before = (out / "policy.npz").read_bytes()
    res = runner.invoke(main, [*TRAIN, "--seed", "5", "--out", str(out)])
    _one_line_error(res, f"--out '{out}' already holds policy.npz", "--force")
    assert (out / "policy.npz").read_bytes() == before
    res = runner.invoke(main, [*TRAIN, "--seed", "5", "--out", str(out), "--force"])
    assert res.exit_code == 0, res.output
    assert (out / "policy.npz").read_bytes() != before


def test_ctrl_c_during_train_exits_130_and_leaves_nothing(runner, tmp_path, monkeypatch):
    import pipefollow.training.phases

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(pipefollow.training.phases, "train_compiled", interrupted)
    out = tmp_path / "new" / "runs" / "run"
    res = runner.invoke(main, [*TRAIN, "--out", str(out)])
    assert res.exit_code == 130, res.output
    assert res.stderr.strip().splitlines() == [f"pipefollow: interrupted; nothing written to '{out}'"]
    assert list(tmp_path.iterdir()) == []  # nor the folders made for --out


def test_full_disk_during_train_names_the_file_and_leaves_nothing(runner, tmp_path, monkeypatch):
    import errno

    import pipefollow.files.atomic

    def no_space(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(pipefollow.files.atomic.os, "fsync", no_space)
    out = tmp_path / "run"
    res = runner.invoke(main, [*TRAIN, "--out", str(out)])
    _one_line_error(res, str(out / "policy.npz"), "No space left on device")
    assert not out.exists()


def test_full_disk_on_the_second_training_output_removes_the_first(runner, tmp_path, monkeypatch):
    import pipefollow.training.outputs

    def no_space(path, *args, **kwargs):
        import errno

        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(pipefollow.training.outputs, "write_learning_curve", no_space)
    out = tmp_path / "run"
    out.mkdir()
    res = runner.invoke(main, [*TRAIN, "--out", str(out)])
    _one_line_error(res, "learning_curve.csv", "No space left on device")
    assert list(out.iterdir()) == []


@pytest.mark.parametrize(
    "name, magic",
    [("p.jpg", b"\xff\xd8\xff"), ("p.JPEG", b"\xff\xd8\xff"), ("p.svg", b"<?xml"), ("p.pdf", b"%PDF")],
)
def test_plot_is_written_in_the_format_its_suffix_names(runner, tmp_path, name, magic):
    path = tmp_path / name
    res = runner.invoke(main, ["evaluate", "--seconds", "3", "--plot", str(path)])
    assert res.exit_code == 0, res.output
    assert path.read_bytes().startswith(magic)


@pytest.mark.parametrize(
    "name, fragment",
    [
        ("p.xyz", "'.xyz' is not a known file type; use one of"),
        ("p", "has no suffix to tell the file type"),
        ("afile/p.png", "is a file, not a folder"),
        ("afile/sub/p.png", "is a file, not a folder"),
    ],
)
def test_bad_plot_paths_are_refused_before_the_episodes(runner, tmp_path, monkeypatch, name, fragment):
    (tmp_path / "afile").write_text("")
    monkeypatch.chdir(tmp_path)
    res = runner.invoke(main, ["evaluate", "--plot", name])
    _one_line_error(res, f"--plot '{name}'", fragment)


def test_evaluate_animates_the_first_episode(runner, tmp_path):
    path = tmp_path / "sub" / "ep.gif"
    args = ["evaluate", "--seconds", "4", "--episodes", "2", "--start-noise", "0.3", "--json"]
    res = runner.invoke(main, [*args, "--animate", str(path)])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["animation"] == str(path) and path.read_bytes()[:4] == b"GIF8"
    plain = json.loads(runner.invoke(main, args).stdout)  # recording changes nothing
    assert plain["episodes"] == out["episodes"]


@pytest.mark.parametrize(
    "name, fragment",
    [("ep.avi", "'.avi' is not a known file type"), ("afile/ep.gif", "is a file, not a folder")],
)
def test_bad_animation_paths_are_refused(runner, tmp_path, monkeypatch, name, fragment):
    (tmp_path / "afile").write_text("")
    monkeypatch.chdir(tmp_path)
    res = runner.invoke(main, ["evaluate", "--animate", name])
    _one_line_error(res, f"--animate '{name}'", fragment)


def test_mp4_without_ffmpeg_is_a_one_line_error(runner, tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))  # no ffmpeg here
    res = runner.invoke(main, ["evaluate", "--animate", str(tmp_path / "ep.mp4")])
    _one_line_error(res, "--animate", "needs ffmpeg")
    assert not (tmp_path / "ep.mp4").exists()


def test_shell_completion_scripts_come_from_click(runner):
    for shell, marker in [("bash", "_pipefollow_completion()"), ("zsh", "#compdef pipefollow")]:
        res = runner.invoke(main, [], prog_name="pipefollow", env={"_PIPEFOLLOW_COMPLETE": f"{shell}_source"})
        assert res.exit_code == 0 and marker in res.stdout
    env = {"_PIPEFOLLOW_COMPLETE": "bash_complete", "COMP_WORDS": "pipefollow pip", "COMP_CWORD": "1"}
    res = runner.invoke(main, [], prog_name="pipefollow", env=env)
    assert res.stdout.split() == ["plain,pipelines"]


def test_an_episode_longer_than_the_limit_is_refused_by_the_options_the_files_and_the_environment(tmp_path):
    import gymnasium

    import pipefollow.envs  # noqa: F401 (registers the environment)
    from pipefollow.cli import main
    from pipefollow.files.limits import MAX_EPISODE_SECONDS

    too_long = str(MAX_EPISODE_SECONDS * 1.5)
    res = CliRunner().invoke(main, ["evaluate", "--seconds", too_long])
    assert res.exit_code == 2 and "--seconds" in res.output
    toml = tmp_path / "x.toml"
    toml.write_text(f'[experiment]\nname = "x"\n[[trial]]\nname = "t"\nepisode_seconds = {too_long}\n')
    res = CliRunner().invoke(main, ["reproduce", "--experiment", str(toml), "--out", str(tmp_path / "r")])
    assert res.exit_code == 2 and "episode_seconds" in res.output
    with pytest.raises(ValueError, match="episode_seconds"):
        gymnasium.make("pipefollow/PipelineFollowing-v0", episode_seconds=MAX_EPISODE_SECONDS * 1.5)


@pytest.mark.parametrize("as_json", [True, False])
def test_echo_result_prints_json_or_the_text_and_formats_only_what_it_prints(as_json):
    from pipefollow.cli.common import echo_result
    from pipefollow.cli.options import json_option

    formatted = []

    @click.command()
    @json_option()
    def show(as_json):
        echo_result({"a": "é"}, as_json, lambda: formatted.append(1) or "a table", ensure_ascii=False)

    out = CliRunner().invoke(show, ["--json"] if as_json else []).output
    assert out == ('{"a": "é"}\n' if as_json else "a table\n")
    assert formatted == ([] if as_json else [1])


@pytest.mark.parametrize("command", ["benchmark", "evaluate"])
def test_the_camera_and_sensor_options_take_what_the_environment_takes(command):
    # cli.options spells the choices out (importing perception.camera loads numba); held to it here
    from pipefollow.perception.camera import CAMERAS, SENSORS

    cmd = main.get_command(click.Context(main), command)
    choices = {p.name: tuple(p.type.choices) for p in cmd.params if p.name in ("camera", "sensor")}
    assert choices == {"camera": CAMERAS, "sensor": SENSORS}
