"""The user's own pipes: benchmark --suite folders, files and patterns; evaluate --pipeline names."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.sim.pipe_names import (
    FileSuite,
    did_you_mean,
    pipeline_source,
    resolve_fixed,
    resolve_pipeline,
    resolve_suite,
    resolve_training,
)
from pipefollow.sim.pipeline import PipelineError
from pipefollow.sim.suites import SUITES, min_length_for


@pytest.fixture
def runner():
    return CliRunner()


def _json(res) -> dict:
    assert res.exit_code == 0, res.output
    return json.loads(res.stdout)


@pytest.fixture
def exported(runner, tmp_path):
    out = tmp_path / "pipes"
    _json(runner.invoke(main, ["suites", "export", "heldout", "--out", str(out), "--pipes", "4", "--json"]))
    return out


def test_benchmark_on_an_exported_folder_equals_the_suite_itself(runner, exported):
    on_files = _json(runner.invoke(main, ["benchmark", "--suite", str(exported), "--json"]))
    on_suite = _json(runner.invoke(main, ["benchmark", "--suite", "heldout", "--pipes", "4", "--json"]))
    assert [e["name"] for e in on_files["episodes"]] == [f"heldout-{k:03d}" for k in range(4)]
    assert [e["return"] for e in on_files["episodes"]] == [e["return"] for e in on_suite["episodes"]]
    assert on_files["suite"] == "pipes" and on_files["n_episodes"] == 4


def test_benchmark_takes_files_and_patterns_in_the_order_given(runner, exported):
    res = runner.invoke(
        main,
        [
            "benchmark",
            "--suite",
            str(exported / "heldout-003.json"),
            "--suite",
            str(exported / "*-00[01].json"),
            "--json",
        ],
    )
    names = [e["name"] for e in _json(res)["episodes"]]
    assert names == ["heldout-003", "heldout-000", "heldout-001"]


@pytest.mark.parametrize(
    "spec, fragment",
    [
        ("heldot", "did you mean 'heldout'?"),
        ("{tmp}/nothing-*.json", "matches no file"),
        ("{tmp}", "without pipeline files"),
    ],
)
def test_bad_suites_are_one_line_errors(runner, tmp_path, spec, fragment):
    res = runner.invoke(main, ["benchmark", "--suite", spec.format(tmp=tmp_path)])
    assert res.exit_code == 2
    assert len(res.stderr.strip().splitlines()) == 1 and fragment in res.stderr


def test_a_suite_name_is_not_mixed_with_files(exported):
    with pytest.raises(PipelineError, match="cannot be combined"):
        resolve_suite(["heldout", str(exported)])


def test_pipes_beyond_a_folder_are_refused(runner, exported):
    res = runner.invoke(main, ["benchmark", "--suite", str(exported), "--pipes", "5"])
    assert res.exit_code == 2 and "has 4 pipes" in res.stderr


def test_file_suite_reads_the_pipes_back_exactly(exported):
    suite = resolve_suite(str(exported))
    assert isinstance(suite, FileSuite) and suite.count == 4
    for pipe, k in zip(suite.pipes(), range(4), strict=True):
        np.testing.assert_array_equal(pipe.points, SUITES["heldout"].pipe(k, min_length_for(60.0)).points)


def test_evaluate_takes_a_suite_pipe_by_its_exported_name(runner, exported):
    by_name = _json(
        runner.invoke(main, ["evaluate", "--pipeline", "heldout-003", "--seconds", "30", "--json"])
    )
    by_file = _json(
        runner.invoke(
            main, ["evaluate", "--pipeline", str(exported / "heldout-003.json"), "--seconds", "30", "--json"]
        )
    )
    assert by_name["mean_return"] == by_file["mean_return"]


def test_evaluate_takes_a_training_family_a_new_pipe_every_episode(runner):
    out = _json(runner.invoke(main, ["evaluate", "--pipeline", "random:hard", "--episodes", "2", "--json"]))
    first, second = (e["return"] for e in out["episodes"])
    assert first != second  # two different pipes (no start noise: the same pipe would repeat exactly)
    again = _json(runner.invoke(main, ["evaluate", "--pipeline", "random:hard", "--episodes", "2", "--json"]))
    assert again["episodes"] == out["episodes"]  # the seed decides the pipes


def test_a_pipe_past_the_end_of_a_held_out_suite_is_refused():
    with pytest.raises(PipelineError, match="pipes 0 to 99"):
        resolve_pipeline("heldout-100", 20.0)


def test_unknown_pipeline_suggests_the_closest_name(runner):
    res = runner.invoke(main, ["evaluate", "--pipeline", "paper-lft"])
    assert res.exit_code == 2 and "did you mean 'paper-left'?" in res.stderr


def test_did_you_mean_is_silent_when_nothing_is_close():
    assert did_you_mean("zzzz", ["paper-left", "heldout"]) == ""
    assert did_you_mean("rando:hard", ["random:hard", "random:easy"]) == " (did you mean 'random:hard'?)"


def test_gym_make_takes_a_pipeline_as_its_points():
    import gymnasium as gym

    import pipefollow

    env = gym.make(pipefollow.ENV_ID, pipeline=[[0, 0], [5, 0], [5, 5]])
    obs, _ = env.reset(seed=0)
    np.testing.assert_array_equal(env.unwrapped.pipeline.points, [[0.0, 0.0], [5.0, 0.0], [5.0, 5.0]])
    # heading north along the first segment, the pipe straight ahead: x1 = 0, y1 at the footprint's far edge
    assert obs[0] == 0.0 and obs[1] == 3.0
    with pytest.raises(PipelineError, match="pipeline points: needs at least two distinct points"):
        gym.make(pipefollow.ENV_ID, pipeline=[[0, 0]])


def test_each_entry_point_takes_its_forms_and_shares_the_fixed_ones():
    points = [[0, 0], [3, 4]]
    for pipe in (resolve_fixed(points), resolve_training(points), pipeline_source(points)[1]):
        assert pipe.name == "pipeline points" and pipe.length == 5.0
    with pytest.raises(PipelineError, match="pipeline points: points contain a number too large"):
        pipeline_source([[0, 0], [10**400, 1]])
    family, first = pipeline_source("random:hard")
    assert family is SUITES["hard"] and first.name == "hard-000"
    assert resolve_pipeline("heldout-003", 20.0).name == "heldout-003"  # suite pipes: evaluation only
    family, pipe = pipeline_source("heldout-003", 20.0)  # the environments, told their episode
    assert family is None and np.array_equal(pipe.points, resolve_pipeline("heldout-003", 20.0).points)
    with pytest.raises(PipelineError, match="not a built-in .* and no such file"):
        resolve_fixed("heldout-003")
    for resolve in (resolve_training, pipeline_source):  # training, and an environment not told its episode
        with pytest.raises(PipelineError, match="a suite's pipe is for judging a policy"):
            resolve("heldout-003")
    with pytest.raises(PipelineError, match="no such file"):
        resolve_fixed("random:hard")  # a family is no fixed pipeline


def test_robustness_takes_what_benchmark_takes_and_an_exported_folder_equals_its_suite(runner, exported):
    args = ["robustness", "--speeds", "0,0.1", "--scenarios", "", "--json"]
    on_files = _json(runner.invoke(main, [*args, "--suite", str(exported)]))
    on_suite = _json(runner.invoke(main, [*args, "--suite", "heldout", "--pipes", "4"]))
    assert on_files["pipes"] == on_suite["pipes"] == 4 and on_files["suite"] == "pipes"
    assert on_files["curve"] == on_suite["curve"]
