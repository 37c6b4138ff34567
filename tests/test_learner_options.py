"""Every learner option of the one table, from the command line and from experiment files, alike.

``pipefollow train`` builds its learner options from ``pipefollow.learners.options.LEARNER_OPTIONS``
and experiment trials have one field per entry; the same values and seed give the same policy,
weight for weight.
"""

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.experiments.schema import TrialConfig, field_help
from pipefollow.learners.options import LEARNER_OPTIONS, OPTION
from pipefollow.learners.registry import LEARNERS, agent_options, taking
from pipefollow.training.policy_files import load_policy, policy_options

CASES = {
    # supervised CACLA+Var with the critic's trace, every step size, its own σ schedule, the DVL's drift
    "cacla": dict(
        algorithm="cacla",
        supervised=True,
        critic_lambda=0.9,
        actor_repeats="var",
        var_rate=0.01,
        alpha_v=0.3,
        alpha_pi=0.15,
        discount=0.85,
        delta_k=0.04,
        forgetting=0.001,
        sigma_start=0.7,
        sigma_end=0.05,
        state="paper+drift",
    ),  # fmt: skip
    # the general actor-critic's sign factor, and the yaw rate
    "ac": dict(algorithm="ac", actor_update="sign", critic_lambda=0.5, state="paper+yaw", sigma_start=0.8),
    # SARSA's step size and discount
    "sarsa": dict(algorithm="sarsa", alpha_q=0.3, discount=0.7, sigma_end=0.1),
}
SEED, EPISODES, SECONDS = 5, 6, 12


def _toml_value(v) -> str:
    return str(v).lower() if isinstance(v, bool) else json.dumps(v)


def _flags(options: dict) -> list[str]:
    out = []
    for name, value in options.items():
        o = OPTION[name]
        out += [o.option] if o.kind is bool else [o.option, str(value)]
    return out


@pytest.mark.parametrize("case", CASES)
def test_train_and_an_experiment_trial_with_the_same_options_write_the_same_policy(tmp_path, case):
    options = dict(CASES[case])
    algorithm = options.pop("algorithm")
    args = ["train", "--algorithm", algorithm, "--pipeline", "paper-left", "--episodes", str(EPISODES),
            "--seconds", str(SECONDS), "--seed", str(SEED), "--current", "0.1,45", "--camera-noise", "0.05",
            "--dvl-noise", "0.01", "--gyro-noise", "0.1",
            "--out", str(tmp_path / "train"), "--json", *_flags(options)]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    trained = load_policy(summary["policy"])

    lines = "\n".join(f"{k} = {_toml_value(v)}" for k, v in options.items())
    toml = tmp_path / "one.toml"
    toml.write_text(
        f'[experiment]\nname = "one"\nrepeats = 1\nseed = {SEED}\n[[trial]]\nname = "t"\n'
        f'algorithm = "{algorithm}"\nphases = [{{ pipeline = "paper-left", episodes = {EPISODES} }}]\n'
        f"episode_seconds = {SECONDS}\n{lines}\n"
        "disturbance = { current_speed = 0.1, current_direction_deg = 45, camera_noise = 0.05, "
        "dvl_noise = 0.01, gyro_noise_deg = 0.1 }\n"
    )
    out = tmp_path / "experiment"
    res = CliRunner().invoke(
        main,
        ["reproduce", "--experiment", str(toml), "--out", str(out), "--backend", "serial", "--no-figures"],
    )
    assert res.exit_code == 0, res.output
    (policy,) = (out / "policies").glob("t-seed*.npz")
    from_trial = load_policy(policy)
    assert from_trial.params == trained.params and from_trial.state == trained.state
    assert from_trial.grid == trained.grid
    np.testing.assert_array_equal(from_trial.weights, trained.weights)
    assert np.abs(trained.weights).sum() > 0
    if options.get("actor_repeats") == "var":  # CACLA+Var's running variance moved with its var_rate
        assert trained.td_var[0] != 1.0  # (a run folder's policies keep the weights only, not td_var)
    # the options reach the learner's record, and the policy file and the summary show them
    shown = policy_options(trained)
    for name, value in options.items():
        assert shown[name] == value and summary["options"][name] == value
    curve = np.loadtxt(tmp_path / "train" / "learning_curve.csv", delimiter=",", skiprows=1)[:, 1]
    start, end = options.get("sigma_start", 1.0), options.get("sigma_end", 0.01)
    np.testing.assert_allclose(curve, np.linspace(start, end, EPISODES), rtol=1e-12, atol=0)


def test_the_table_is_the_trials_fields_and_the_train_options():
    fields = field_help(TrialConfig)
    train = {p.name: p for p in _train_params()}
    for o in LEARNER_OPTIONS:
        assert fields[o.name] == o.help and getattr(TrialConfig(), o.name) == o.default
        assert o.name in train and o.option in train[o.name].opts
        assert taking(o.name)  # some learner takes it
    assert train["skew_deg"].opts == ["--skew"]  # the flag the paper's runs always had


def _train_params():
    from pipefollow.cli.run import train

    return train.params


@pytest.mark.parametrize("o", [o for o in LEARNER_OPTIONS if o.kind is float], ids=lambda o: o.name)
def test_a_value_out_of_range_is_a_one_line_error_naming_the_option(tmp_path, o):
    bad = (o.high + 1.0) if o.high is not None else -1.0
    res = CliRunner().invoke(main, ["train", "--algorithm", taking(o.name)[0], o.option, str(bad),
                                    "--out", str(tmp_path / "x")])  # fmt: skip
    assert res.exit_code == 2 and len(res.stderr.strip().splitlines()) == 1
    assert o.option in res.stderr and f"{o.name} must be {o.allowed()}" in res.stderr
    assert not (tmp_path / "x").exists()


def test_an_option_for_another_learner_and_a_rising_sigma_are_refused(tmp_path):
    out = ["--out", str(tmp_path / "x")]
    res = CliRunner().invoke(main, ["train", "--algorithm", "sarsa", "--alpha-v", "0.3", *out])
    assert res.exit_code == 2 and "--alpha-v applies to --algorithm cacla and ac only" in res.stderr
    res = CliRunner().invoke(main, ["train", "--algorithm", "cacla", "--alpha-q", "0.3", *out])
    assert res.exit_code == 2 and "--alpha-q applies to --algorithm sarsa only" in res.stderr
    sigma = ["--sigma-start", "0.1", "--sigma-end", "0.2"]
    res = CliRunner().invoke(main, ["train", "--algorithm", "cacla", *sigma, *out])
    assert res.exit_code == 2
    assert "--sigma-start: sigma_start must be ≥ sigma_end (0.2), got 0.1" in res.stderr
    res = CliRunner().invoke(main, ["train", "--algorithm", "ppo", "--critic-lambda", "0.5", *out])
    assert res.exit_code == 2 and "--critic-lambda not available with --algorithm ppo" in res.stderr
    with pytest.raises(ValueError, match="var_rate applies to algorithm cacla only"):
        agent_options("ac", {"var_rate": 0.01})
    assert agent_options("ac", {"var_rate": 0.01}, strict=False) == {}  # [defaults] serve every learner
    assert set(LEARNERS["cacla"].step_sizes) >= {"alpha_v", "alpha_pi", "discount", "var_rate"}


def test_init_keeps_the_saved_options_and_refuses_others(tmp_path):
    first = tmp_path / "a"
    base = ["train", "--algorithm", "cacla", "--episodes", "3", "--seconds", "5", "--json"]
    options = ["--critic-lambda", "0.9", "--alpha-v", "0.3", "--state", "paper+drift"]
    res = CliRunner().invoke(main, [*base, *options, "--out", str(first)])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(main, [*base, "--init", str(first), "--out", str(tmp_path / "b")])
    assert res.exit_code == 0, res.output
    kept = load_policy(tmp_path / "b" / "policy.npz")
    assert (kept.params.critic_lambda, kept.params.alpha_v, kept.state) == (0.9, 0.3, "paper+drift")
    res = CliRunner().invoke(main, [*base, "--init", str(first), "--critic-lambda", "0.5", "--out",
                                    str(tmp_path / "c")])  # fmt: skip
    assert res.exit_code == 2 and "critic_lambda 0.9 (this run: 0.5)" in res.stderr
    res = CliRunner().invoke(main, [*base, "--init", str(first), "--state", "paper", "--out", str(tmp_path)])
    assert res.exit_code == 2 and "state 'paper+drift' (this run: 'paper')" in res.stderr


def test_trials_lists_the_options_set():
    res = CliRunner().invoke(main, ["trials", "--experiment", "reference-learners", "--json"])
    assert res.exit_code == 0, res.output
    rows = json.loads(res.stdout)
    assert any("actor_update" in r["options"] for r in rows)
