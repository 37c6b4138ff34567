"""``--camera``, ``--sensor`` and the water's options on robustness, compare, rollouts and train.

The options are ``cli.options.camera_options``, as on ``evaluate`` and ``benchmark``; each test holds
a command's numbers to episodes run directly in the environment through the same sensor, and to
different numbers from the ideal camera's.
"""

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim.suites import get_suite, min_length_for
from pipefollow.training.compiled import run_episode

SECONDS = 20.0


def _invoke(args):
    return CliRunner().invoke(main, args)


def _heuristic_returns(n: int, reset_seeds: bool = False, entropy=lambda k: [0, k], **sensor) -> list[float]:
    """The heuristic's return on each of the first ``n`` held-out pipes, in the environment itself.

    Pipe k's environment draws from ``default_rng(SeedSequence(entropy(k)))`` (the benchmark's noise
    generators, module docstring of ``evaluation.benchmark``: ``[noise seed, k]``; a robustness
    scenario is one pipe of noise seed k: ``[k, 0]``), or is reset with seed k (``rollouts``).
    """
    out = []
    for k, pipe in enumerate(get_suite("heldout").pipes(n, min_length_for(SECONDS))):
        env = PipelineFollowingEnv(pipe, SECONDS, **sensor)
        if reset_seeds:
            stats = run_episode(env, Heuristic(), seed=k)
        else:
            env.np_random = np.random.default_rng(np.random.SeedSequence(entropy(k)))
            stats = run_episode(env, Heuristic())
        out.append(float(stats.ret))
    return out


def test_compare_observes_through_the_sonar():
    res = _invoke(["compare", "heuristic", "--pipes", "2", "--seconds", "20", "--reps", "100", "--sensor",
                   "sonar", "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert (out["camera"], out["sensor"], out["water"]["turbidity"]) == ("ideal", "sonar", 0.1)
    sonar = _heuristic_returns(2, sensor="sonar", water="clear")
    assert out["scores"]["heuristic"][0] == pytest.approx(sonar, abs=1e-9)
    ideal = _heuristic_returns(2)
    assert not np.allclose(sonar, ideal, atol=1e-3)  # the sensor changed the episodes


def test_robustness_observes_through_the_sonar():
    res = _invoke(["robustness", "--pipes", "2", "--seconds", "20", "--speeds", "0", "--scenarios", "",
                   "--sensor", "sonar", "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["sensor"] == "sonar"
    (row,) = [r for r in out["curve"] if r["controller"] == "heuristic"]
    sonar = _heuristic_returns(2, entropy=lambda k: [k, 0], sensor="sonar", water="clear")
    assert row["mean_return"] == pytest.approx(np.mean(sonar), abs=1e-9)
    ideal = _invoke(["robustness", "--pipes", "2", "--seconds", "20", "--speeds", "0", "--scenarios", "",
                     "--json"])  # fmt: skip
    assert "sensor" not in json.loads(ideal.output)
    (ideal_row,) = [r for r in json.loads(ideal.output)["curve"] if r["controller"] == "heuristic"]
    assert ideal_row["mean_return"] == pytest.approx(np.mean(_heuristic_returns(2)), abs=1e-9)
    assert abs(ideal_row["mean_return"] - row["mean_return"]) > 1e-3


@pytest.mark.parametrize(
    "command", ["robustness", "compare heuristic", "rollouts --out OUT", "train --algorithm ppo --out OUT"]
)
@pytest.mark.parametrize(
    "bad, named",
    [
        (["--sensor", "sonr"], "--sensor"),
        (["--camera", "fisheye"], "--camera"),
        (["--water", "murky", "--camera", "vision"], "murky"),
        (["--turbidity", "-1", "--sensor", "sonar"], "--turbidity"),
        (["--burial", "0.5"], "--burial"),  # the ideal camera's state: no water to bury the pipe in
    ],
)
def test_bad_camera_values_are_one_line_errors_naming_the_option(command, bad, named, tmp_path):
    args = [a.replace("OUT", str(tmp_path / "out")) for a in command.split()]
    res = _invoke([*args, *bad])
    assert res.exit_code == 2
    assert named in res.output
    assert len(res.output.strip().splitlines()) == 1, res.output
    assert not (tmp_path / "out").exists()


def test_rollouts_record_the_sensor_in_the_dataset(tmp_path):
    minari = pytest.importorskip("minari")
    pytest.importorskip("h5py")
    pytest.importorskip("jax")
    res = _invoke(["rollouts", "--pipes", "2", "--seconds", "20", "--sensor", "sonar", "--water", "turbid",
                   "--out", str(tmp_path), "--name", "pipefollow/sonar-v0", "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["sensor"] == "sonar" and out["water"]["turbidity"] == 0.25
    import os

    os.environ["MINARI_DATASETS_PATH"] = str(tmp_path)
    try:
        dataset = minari.load_dataset("pipefollow/sonar-v0")
        env = dataset.recover_environment()
        assert env.unwrapped.camera_settings.sensor == "sonar"
        assert env.unwrapped.camera_settings.water.turbidity == 0.25
        sums = [float(np.sum(e.rewards)) for e in dataset.iterate_episodes()]
    finally:
        del os.environ["MINARI_DATASETS_PATH"]
    sonar = _heuristic_returns(2, reset_seeds=True, sensor="sonar", water="turbid")
    assert sums == pytest.approx(sonar, abs=1e-3)  # float32 storage


@pytest.mark.slow  # ≈ 15 s each: torch and one PPO rollout
@pytest.mark.parametrize(
    "options, camera, sensor, turbidity",
    [
        (["--camera", "vision-raw"], "vision-raw", "camera", 0.1),
        # the closed-loop table's sensor-trained PPO (examples/closed_loop_table.py, FUSED_TURBID)
        (["--camera", "vision", "--sensor", "fused", "--water", "turbid"], "vision", "fused", 0.25),
    ],
)
def test_train_ppo_observes_through_the_camera(tmp_path, options, camera, sensor, turbidity):
    pytest.importorskip("stable_baselines3")
    pytest.importorskip("cv2")
    res = _invoke(["train", "--algorithm", "ppo", "--steps", "64", "--seconds", "10",
                   *options, "--out", str(tmp_path / "o"), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert json.loads(res.output)["camera"] == camera
    record = json.loads((tmp_path / "o" / "hyperparameters.json").read_text())
    seen = record["observed_through"]
    assert (seen["camera"], seen.get("sensor", "camera")) == (camera, sensor)
    assert seen["water"]["turbidity"] == turbidity
    # the policy file records it too, as the paper's learners' files do (training.policy_files)
    with np.load(tmp_path / "o" / "policy.npz") as f:
        through = json.loads(json.loads(str(f["metadata"]))["trained_through"])
    assert (through["camera"], through["sensor"]) == (camera, sensor)
    assert through["water"]["turbidity"] == turbidity
