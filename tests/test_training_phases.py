"""``pipefollow train`` and an experiment trial train through the one ``train_phases``."""

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.training.policy_files import load_policy

CASES = {
    # a fixed pipe under a reading that rescales σ, with a supervised learner
    "fixed": dict(algorithm="ac", supervised=True, pipeline="paper-left", readings=["sigma_unit=rad"]),
    # a new random pipe every episode, random disturbances and skew
    "random": dict(
        algorithm="cacla", skew=22.5, pipeline="random:easy", readings=[], camera_noise=0.05, miss_prob=0.05
    ),
}


@pytest.mark.parametrize("case", CASES)
def test_one_trial_experiment_and_train_write_identical_policy_weights(tmp_path, case):
    c = CASES[case]
    seed, episodes, seconds = 7, 6, 12
    args = ["train", "--algorithm", c["algorithm"], "--pipeline", c["pipeline"], "--episodes", str(episodes)]
    args += ["--seconds", str(seconds), "--seed", str(seed), "--out", str(tmp_path / "train"), "--json"]
    args += ["--supervised"] if c.get("supervised") else []
    args += ["--skew", str(c["skew"])] if c.get("skew") else []
    args += [x for r in c["readings"] for x in ("--reading", r)]
    disturbance = ""
    if c.get("camera_noise"):
        args += ["--camera-noise", str(c["camera_noise"]), "--miss-prob", str(c["miss_prob"])]
        disturbance = (
            f"disturbance = {{ camera_noise = {c['camera_noise']}, miss_prob = {c['miss_prob']} }}\n"
        )
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    trained = load_policy(json.loads(res.stdout)["policy"])

    toml = tmp_path / "one.toml"
    toml.write_text(
        f'[experiment]\nname = "one"\nrepeats = 1\nseed = {seed}\n[[trial]]\nname = "t"\n'
        f'algorithm = "{c["algorithm"]}"\n'
        f'phases = [{{ pipeline = "{c["pipeline"]}", episodes = {episodes} }}]\n'
        f"episode_seconds = {seconds}\nsupervised = {str(bool(c.get('supervised'))).lower()}\n"
        f"skew_deg = {c.get('skew', 0.0)}\nreadings = {json.dumps(c['readings'])}\n{disturbance}"
    )
    out = tmp_path / "experiment"
    res = CliRunner().invoke(
        main,
        ["reproduce", "--experiment", str(toml), "--out", str(out), "--backend", "serial", "--no-figures"],
    )
    assert res.exit_code == 0, res.output
    (policy,) = (out / "policies").glob("t-seed*.npz")
    from_trial = load_policy(policy)
    assert from_trial.params == trained.params and from_trial.readings == trained.readings
    np.testing.assert_array_equal(from_trial.weights, trained.weights)
    assert np.abs(trained.weights).sum() > 0


@pytest.mark.parametrize("readings, scale", [([], 1.0), (["sigma_unit=rad"], 2.0 / math.pi)])
def test_the_learning_curve_states_the_sigma_that_training_used(tmp_path, readings, scale):
    # sigma_unit=rad: σ = 1 rad of waypoint bearing is (180/π)° / 90° = 2/π in normalized action units
    args = ["train", "--algorithm", "cacla", "--episodes", "5", "--seconds", "4", "--out", str(tmp_path)]
    args += [x for r in readings for x in ("--reading", r)]
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    sigma = np.loadtxt(tmp_path / "learning_curve.csv", delimiter=",", skiprows=1)[:, 1]
    np.testing.assert_allclose(sigma, np.linspace(1.0, 0.01, 5) * scale, rtol=1e-12, atol=0)
