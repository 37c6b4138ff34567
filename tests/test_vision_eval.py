"""The detector report, the calibration and their commands."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.evaluation.vision import calibrate, measure, trajectory_frames
from pipefollow.perception.water import WATER_PRESETS
from pipefollow.sim.suites import get_suite


def test_calibration_takes_misses_and_the_rms_of_fine_errors_per_turbidity():
    rows = [
        {"turbidity": 0.1, "burial": 0.0, "detection_rate": 0.9, "rms_m": 0.05, "gross_error_rate": 0.1},
        {"turbidity": 0.1, "burial": 0.5, "detection_rate": 0.5, "rms_m": 0.09, "gross_error_rate": 0.2},
        {"turbidity": 0.3, "burial": 0.0, "detection_rate": 0.25, "rms_m": 0.12, "gross_error_rate": 0.5},
    ]
    out = calibrate(rows)
    assert [r["turbidity"] for r in out] == [0.1, 0.3]  # burial rows are not turbidity levels
    assert out[0]["miss_prob"] == pytest.approx(0.1) and out[0]["camera_noise"] == 0.05
    assert out[1]["miss_prob"] == pytest.approx(0.75) and out[1]["gross_error_rate"] == 0.5


def test_measure_on_trajectory_frames_finds_clear_pipes_and_not_absent_ones():
    pipes, frames = trajectory_frames(get_suite("heldout"), 2, seconds=60.0)
    assert len(frames) == 120 and all(f.pipe in (0, 1) for f in frames)
    clear = measure(WATER_PRESETS["clear"], pipes, frames, seed=0, condition=1)
    murky = measure(WATER_PRESETS["clear"]._replace(turbidity=1.0), pipes, frames, seed=0, condition=1)
    assert clear["frames_without_pipe"] == 120 and clear["frames_in_view"] > 100
    assert clear["detection_rate"] > 0.85 and clear["false_detection_rate"] <= 0.02
    assert murky["detection_rate"] < clear["detection_rate"] and clear["median_error_cm"] < 3.0
    again = measure(WATER_PRESETS["clear"], pipes, frames, seed=0, condition=1)
    assert again == clear  # same seed, same numbers


def test_calibrate_command_reads_a_report_and_prints_the_options(tmp_path):
    report = tmp_path / "report.csv"
    report.write_text(
        "turbidity,burial,detection_rate,gross_error_rate,rms_m\n0.2,0.0,0.8,0.1,0.04\n0.2,0.5,0.6,0.1,0.06\n",
        encoding="utf-8",
    )
    out = tmp_path / "cal.json"
    result = CliRunner().invoke(main, ["vision", "calibrate", "--report", str(report), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "--camera-noise 0.04 --miss-prob 0.2" in result.output
    assert json.loads(out.read_text())[0]["miss_prob"] == pytest.approx(0.2)


@pytest.mark.parametrize(
    "args, message",
    [
        (["vision", "calibrate", "--report", "nowhere.csv"], "no such file"),
        (["benchmark", "--controller", "heuristic", "--turbidity", "0.2"], "need --camera vision"),
        (["benchmark", "--controller", "heuristic", "--camera", "vision", "--burial", "0.95"], "burial"),
        (["benchmark", "--controller", "heuristic", "--camera", "vision", "--water", "murky"], "murky"),
        (["benchmark", "--controller", "heuristic", "--camera", "vision", "--turbidity", "nan"], "finite"),
    ],
)
def test_bad_camera_options_exit_2_with_one_line(args, message):
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 2
    assert message in result.output and result.output.count("\n") == 1


def test_benchmark_with_the_vision_camera_compares_with_the_ideal_heuristic():
    result = CliRunner().invoke(
        main, ["benchmark", "--controller", "heuristic", "--camera", "vision", "--pipes", "2", "--json"]
    )
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["camera"] == "vision" and summary["water"]["turbidity"] == 0.1
    assert "vs_heuristic" not in summary  # the heuristic through the same camera is itself
    assert math.isfinite(summary["vs_heuristic_ideal"]["mean_diff"])
    assert 0.0 <= summary["success_rate"] <= 1.0 and np.isfinite(summary["mean_return"])


def test_evaluate_takes_the_vision_camera_and_counts_the_true_pipe_in_view():
    args = ["evaluate", "--controller", "heuristic", "--pipeline", "paper-left", "--json"]
    ideal = json.loads(CliRunner().invoke(main, args).output)
    result = CliRunner().invoke(main, [*args, "--camera", "vision", "--water", "turbid", "--turbidity", "3"])
    assert result.exit_code == 0, result.output
    blind = json.loads(result.output)
    assert blind["camera"] == "vision" and blind["water"]["turbidity"] == 3.0
    # at 3/m the detector sees nothing: every decision is −10, but the AUV, searching on the spot
    # at the pipe's start, has the true pipe in view
    assert blind["mean_return"] == pytest.approx(-10.0 * 20)
    assert blind["mean_pipe_in_view"] > 0.0 and ideal["mean_return"] > blind["mean_return"]


@pytest.mark.parametrize("camera", ["vision", "vision-raw"])
def test_closed_loop_runs_the_camera_it_is_given(camera):
    from pipefollow.evaluation.benchmark import load_controller
    from pipefollow.evaluation.vision import closed_loop

    blind = WATER_PRESETS["turbid"]._replace(turbidity=3.0)
    agent = load_controller("heuristic")
    s = closed_loop(agent, get_suite("heldout"), blind, "h", n_pipes=2, seconds=5.0, camera=camera)
    assert s.summary["camera"] == camera
    # at 3/m nothing is ever detected, so nothing is tracked either: every decision is a search, −10
    assert s.summary["mean_return"] == pytest.approx(-10.0 * 5)


def test_closed_loop_refuses_another_camera_in_one_line():
    from pipefollow.evaluation.vision import closed_loop

    with pytest.raises(ValueError, match="camera must be 'vision' or 'vision-raw', got 'ideal'"):
        closed_loop(None, get_suite("heldout"), WATER_PRESETS["clear"], "h", camera="ideal")
