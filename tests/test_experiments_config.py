"""Experiment configuration: the shipped paper grid, errors that name the key, overrides."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pipefollow.experiments.config import load_experiment, with_overrides
from pipefollow.experiments.schema import (
    ConfigError,
    ExperimentConfig,
    Phase,
    TrialConfig,
    field_help,
    from_dict,
    to_dict,
)

PAPER_TRIALS = [
    "sarsa",
    "cacla",
    "supervised-cacla",
    "cacla-skew11.25",
    "cacla-skew22.5",
    "cacla-skew45",
    "supervised-cacla-skew22.5",
    "validation",
]


@pytest.fixture(scope="module")
def paper() -> ExperimentConfig:
    return load_experiment("paper")


def write_toml(tmp_path, text: str):
    path = tmp_path / "exp.toml"
    path.write_text(text)
    return path


MINIMAL = """
[experiment]
name = "tiny"
repeats = 2

[[trial]]
name = "a"
"""


def test_trial_defaults_are_the_learners_records():
    # one definition of the paper's step sizes: the learners' records; SARSA's γ_d is CACLA's
    from pipefollow.learners.actor_critic import PAPER_AC
    from pipefollow.learners.cacla_act import PAPER_CACLA
    from pipefollow.learners.sarsa import PAPER_SARSA

    t = TrialConfig()
    assert (t.alpha_v, t.alpha_pi, t.discount, t.delta_k) == (
        PAPER_CACLA.alpha_v,
        PAPER_CACLA.alpha_pi,
        PAPER_CACLA.discount,
        PAPER_CACLA.delta_k,
    )
    assert (t.alpha_q, t.discount) == (PAPER_SARSA.alpha, PAPER_SARSA.discount)
    assert tuple(PAPER_AC)[: len(PAPER_CACLA)] == tuple(PAPER_CACLA)


def test_paper_grid(paper):
    assert paper.name == "paper"
    assert len(paper.trials) == 8
    assert [t.name for t in paper.trials] == PAPER_TRIALS
    assert paper.repeats == 5
    assert paper.seeds() == [2010, 2011, 2012, 2013, 2014]
    # §4: the paper's learning parameters reach every trial through [defaults]
    for t in paper.trials:
        assert (t.alpha_v, t.alpha_pi, t.alpha_q, t.discount, t.delta_k) == (0.4, 0.2, 0.4, 0.8, 0.05)
        assert (t.sigma_start, t.sigma_end, t.episode_seconds) == (1.0, 0.01, 20.0)
    assert {t.skew_deg for t in paper.trials if t.name.startswith("cacla-skew")} == {11.25, 22.5, 45.0}
    assert paper.trial("sarsa").algorithm == "sarsa"
    assert paper.trial("supervised-cacla-skew22.5").supervised
    v = paper.trial("validation")
    assert [p.pipeline for p in v.phases] == ["paper-left", "paper-right"]
    assert v.episodes == 1000
    assert (v.evaluate_on, v.evaluate_seconds) == ("paper-validation", 60.0)


def test_every_field_is_documented():
    for cls in (Phase, TrialConfig, ExperimentConfig):
        assert all(field_help(cls).values()), cls


@pytest.mark.parametrize(
    ("table", "line", "names"),
    [
        ("[[trial]]", "learning_rate = 0.1", ["learning_rate", "alpha_v", "skew_deg"]),
        ("[experiment]", "repeat = 3", ["repeat", "repeats", "seed"]),
        ("[defaults]", "alpha = 0.1", ["alpha", "alpha_q", "discount"]),
    ],
)
def test_unknown_key_names_it_and_the_allowed_keys(tmp_path, table, line, names):
    text = (
        MINIMAL.replace(table, f"{table}\n{line}", 1)
        if table in MINIMAL
        else MINIMAL + f"\n{table}\n{line}\n"
    )
    with pytest.raises(ConfigError) as e:
        load_experiment(write_toml(tmp_path, text))
    msg = str(e.value)
    assert "exp.toml" in msg and "unknown key" in msg
    for name in names:
        assert name in msg


def test_invalid_choice_names_the_key_and_the_allowed_values(tmp_path):
    with pytest.raises(ConfigError, match=r"'algorithm' must be one of sarsa, cacla, ac, got 'ppo'"):
        load_experiment(write_toml(tmp_path, MINIMAL + 'algorithm = "ppo"\n'))
    with pytest.raises(ConfigError, match=r"'rbf' must be one of normalized, literal"):
        load_experiment(write_toml(tmp_path, MINIMAL + 'readings = ["rbf=cosine"]\n'))


@pytest.mark.parametrize(
    ("line", "pattern"),
    [
        ('repeats = "five"', r"'repeats' must be an integer, got 'five'"),
        ("repeats = 2.5", r"'repeats' must be an integer"),
        ("repeats = 0", r"'repeats' must be from 1 to 100,000"),
    ],
)
def test_wrong_experiment_value(tmp_path, line, pattern):
    text = MINIMAL.replace("repeats = 2", line)
    with pytest.raises(ConfigError, match=pattern):
        load_experiment(write_toml(tmp_path, text))


@pytest.mark.parametrize(
    ("line", "pattern"),
    [
        ('alpha_v = "big"', r"'alpha_v' must be a finite number, got 'big'"),
        ("alpha_v = 0.0", r"'alpha_v' must be in \(0, 1\]"),
        ("discount = 1.5", r"'discount' must be in \(0, 1\]"),
        ("supervised = 1", r"'supervised' must be true or false"),
        ("sigma_start = 0.001", r"'sigma_start' must be ≥ sigma_end"),
        ("episode_seconds = nan", r"'episode_seconds' must be a finite number"),
        ("episode_seconds = 1e308", r"'episode_seconds' must be from 1 to 86400"),
        ('readings = ["gamma_max=-1"]', r"'gamma_max' must be a number in \(0, 100\]"),
        ('readings = "skew_step=weights"', r"'readings' must be a list of strings"),
        ('phases = [{ pipeline = "paper-left", episodes = 0 }]', r"'episodes' must be from 1 to 10,000,000"),
        (
            'phases = [{ pipeline = "paper-left", epsiodes = 3 }]',
            r"unknown key 'epsiodes'; allowed: pipeline, episodes",
        ),
        ("phases = []", r"'phases' must be a non-empty list"),
        ('figures = "fig5"', r"'figures' must be a list of strings"),
        (
            'algorithm = "sarsa"\nskew_deg = 22.5',
            r"skew_deg applies to algorithm cacla only",
        ),
        ("critic_lambda = 1.5", r"key 'critic_lambda' must be in \[0, 1\], got 1.5"),
        ('actor_repeats = "twice"', r"'actor_repeats' must be one of once, var"),
        ('algorithm = "ac"\nactor_repeats = "var"', r"actor_repeats applies to algorithm cacla only"),
        ('algorithm = "sarsa"\ncritic_lambda = 0.5', r"critic_lambda applies to algorithm cacla and ac only"),
    ],
)
def test_wrong_trial_value_names_the_key(tmp_path, line, pattern):
    with pytest.raises(ConfigError, match=pattern) as e:
        load_experiment(write_toml(tmp_path, MINIMAL + line + "\n"))
    assert "[[trial]] #1 'a'" in str(e.value)


def test_trial_name_must_be_usable_in_file_names(tmp_path):
    with pytest.raises(ConfigError, match=r"\[\[trial\]\] #1 'a/b': key 'name' must be letters, digits"):
        load_experiment(write_toml(tmp_path, MINIMAL.replace('name = "a"', 'name = "a/b"')))


def test_file_problems(tmp_path):
    with pytest.raises(ConfigError, match="no such file"):
        load_experiment(tmp_path / "missing.toml")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_experiment(write_toml(tmp_path, "[experiment\n"))
    with pytest.raises(ConfigError, match=r"no \[\[trial\]\] tables"):
        load_experiment(write_toml(tmp_path, '[experiment]\nname = "x"\n'))
    with pytest.raises(ConfigError, match="trial names must be unique, repeated: a"):
        load_experiment(write_toml(tmp_path, MINIMAL + '[[trial]]\nname = "a"\n'))
    with pytest.raises(ConfigError, match=r"'repeats' belongs in the \[experiment\] table"):
        load_experiment(write_toml(tmp_path, "repeats = 3\n" + MINIMAL))


def test_defaults_apply_and_trials_override_them(tmp_path):
    text = MINIMAL + '[[trial]]\nname = "b"\nalpha_v = 0.1\n[defaults]\nalpha_v = 0.3\n'
    exp = load_experiment(write_toml(tmp_path, text))
    assert exp.trial("a").alpha_v == 0.3
    assert exp.trial("b").alpha_v == 0.1


def test_overrides(paper):
    exp = with_overrides(paper, repeats=2, episodes=7, seed=5, trials=["validation", "sarsa"])
    assert exp.seeds() == [5, 6]
    # the experiment's order, not the order of the options
    assert [t.name for t in exp.trials] == ["sarsa", "validation"]
    assert [p.episodes for p in exp.trial("validation").phases] == [7, 7]
    assert exp.trial("validation").episodes == 14
    assert exp.trial("sarsa") == dataclasses.replace(paper.trial("sarsa"), phases=(Phase("paper-left", 7),))
    assert with_overrides(paper) == paper


def test_override_errors(paper):
    with pytest.raises(ConfigError, match=r"--trial: unknown trial 'ppo'; allowed: sarsa, cacla, "):
        with_overrides(paper, trials=["ppo"])
    with pytest.raises(ConfigError, match="'repeats' must be from 1 to"):
        with_overrides(paper, repeats=0)
    with pytest.raises(ConfigError, match="'episodes' must be from 1 to"):
        with_overrides(paper, episodes=0)


def test_dict_round_trip_survives_json(paper):
    data = json.loads(json.dumps(to_dict(paper)))
    assert from_dict(data) == paper


@settings(max_examples=25, deadline=None)
@given(
    repeats=st.integers(1, 9),
    episodes=st.integers(1, 2000),
    seed=st.integers(0, 2**70),  # SeedSequence takes any non-negative integer
    subset=st.sets(st.sampled_from(PAPER_TRIALS), min_size=1),
)
def test_overridden_configs_round_trip(repeats, episodes, seed, subset):
    paper = load_experiment("paper")
    exp = with_overrides(paper, repeats=repeats, episodes=episodes, seed=seed, trials=sorted(subset))
    assert {t.name for t in exp.trials} == subset
    assert all(t.episodes == episodes * len(t.phases) for t in exp.trials)
    assert from_dict(json.loads(json.dumps(to_dict(exp)))) == exp


def test_trial_entries_that_are_not_tables(tmp_path):
    path = tmp_path / "exp.toml"
    path.write_text('trial = [1, 2]\n[experiment]\nname = "x"\n')
    with pytest.raises(ConfigError, match=r"\[\[trial\]\] #1 must be a table"):
        load_experiment(path)


def test_a_disturbance_table_trains_and_evaluates_under_it(tmp_path):
    import dataclasses
    import math

    from pipefollow.experiments.trial import run_trial

    text = MINIMAL + (
        "phases = [{ pipeline = 'paper-left', episodes = 3 }]\n"
        "disturbance = { current_speed = 0.1, current_direction_deg = 90, camera_noise = 0.05 }\n"
    )
    t = load_experiment(write_toml(tmp_path, text)).trials[0]
    assert t.disturbance == {"current_speed": 0.1, "current_direction_deg": 90, "camera_noise": 0.05}
    a, b = run_trial(t, 3), run_trial(t, 3)
    np.testing.assert_array_equal(a.stats, b.stats)  # seeded: the same noise
    assert a.evaluation == b.evaluation
    calm = run_trial(dataclasses.replace(t, disturbance=None), 3)
    assert not np.array_equal(calm.stats, a.stats)
    assert all(math.isfinite(v) for v in a.evaluation["learned"])
    with pytest.raises(ConfigError, match=r"key .disturbance.: camera_noise must be ≥ 0, got -1"):
        load_experiment(write_toml(tmp_path, MINIMAL + "disturbance = { camera_noise = -1 }\n"))
    with pytest.raises(ConfigError, match=r"unknown key 'wind'"):
        load_experiment(write_toml(tmp_path, MINIMAL + "disturbance = { wind = 3 }\n"))


def test_unknown_figure_is_refused_with_the_allowed_names(tmp_path):
    with pytest.raises(ConfigError, match=r"unknown figure 'fig99'; allowed: fig5, fig6, fig7, table1"):
        load_experiment(write_toml(tmp_path, MINIMAL + 'figures = ["fig5", "fig99"]\n'))


@pytest.mark.parametrize("seed", [-1, -(2**40)])
def test_negative_seed_is_refused(tmp_path, seed):
    text = MINIMAL.replace("repeats = 2", f"repeats = 2\nseed = {seed}")
    with pytest.raises(ConfigError, match=r"'seed' must be an integer ≥ 0"):
        load_experiment(write_toml(tmp_path, text))
    with pytest.raises(ConfigError, match="seed"):
        with_overrides(load_experiment("paper"), seed=seed)


def test_huge_seed_is_accepted(tmp_path):
    text = MINIMAL.replace("repeats = 2", "repeats = 2\nseed = 9223372036854775807")
    exp = with_overrides(load_experiment(write_toml(tmp_path, text)), seed=2**64)
    assert exp.seeds() == [2**64, 2**64 + 1]


def test_utf8_with_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "exp.toml"
    path.write_bytes(b"\xef\xbb\xbf" + MINIMAL.encode())
    assert load_experiment(path).name == "tiny"


@pytest.mark.parametrize("data", [MINIMAL.encode("utf-16"), b"\xff\xfe\x00\x81garbage"])
def test_file_that_is_not_utf8_gives_a_config_error(tmp_path, data):
    path = tmp_path / "exp.toml"
    path.write_bytes(data)
    with pytest.raises(ConfigError, match=r"exp.toml'?: not UTF-8 text"):
        load_experiment(path)


def test_relative_pipeline_paths_are_relative_to_the_experiment_file(tmp_path, monkeypatch):
    folder = tmp_path / "study"
    (folder / "pipes").mkdir(parents=True)
    (folder / "pipes" / "mine.json").write_text('{"points": [[0, 0], [5, 0]]}')
    text = MINIMAL + 'phases = [{ pipeline = "pipes/mine.json", episodes = 3 }]\n'
    text += 'evaluate_on = "paper-validation"\n'
    (folder / "exp.toml").write_text(text)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    exp = load_experiment("../study/exp.toml")
    (trial,) = exp.trials
    assert Path(trial.phases[0].pipeline).resolve() == (folder / "pipes" / "mine.json").resolve()
    assert trial.evaluate_on == "paper-validation"  # built-in names stay names
    from pipefollow.sim.pipe_names import resolve_fixed

    assert resolve_fixed(trial.phases[0].pipeline).length == 5.0


def test_the_reference_learners_experiment_sets_the_actor_critics_beside_cacla():
    from pipefollow.experiments.config import shipped_experiments

    assert "reference-learners" in shipped_experiments()
    exp = load_experiment("reference-learners")
    assert exp.repeats == 5
    setups = {(t.algorithm, t.supervised, t.actor_update) for t in exp.trials}
    assert setups == {
        (algorithm, supervised, update)
        for supervised in (False, True)
        for algorithm, update in [("cacla", "delta"), ("ac", "delta"), ("ac", "positive"), ("ac", "sign")]
    }
    for t in exp.trials:  # the paper's step sizes, training pipe and schedule (§4, §4.1)
        assert (t.alpha_v, t.alpha_pi, t.discount, t.delta_k) == (0.4, 0.2, 0.8, 0.05)
        assert [(p.pipeline, p.episodes) for p in t.phases] == [("paper-left", 500)]
        assert (t.sigma_start, t.sigma_end, t.skew_deg, t.readings) == (1.0, 0.01, 0.0, ())


def test_the_sample_efficiency_options_reach_the_trials_agent(tmp_path):
    from pipefollow.experiments.trial import build_agent

    exp = load_experiment(write_toml(tmp_path, MINIMAL + 'actor_repeats = "var"\ncritic_lambda = 0.9\n'))
    agent = build_agent(exp.trials[0])
    assert agent.params.actor_repeats == 1 and agent.params.critic_lambda == 0.9
    assert agent.name == "CACLA+Var, TD(0.9)"


def test_a_vision_camera_trial_trains_on_the_ideal_camera_and_evaluates_through_the_detector(tmp_path):
    import dataclasses

    pytest.importorskip("cv2")
    from pipefollow.experiments.trial import run_trial

    text = MINIMAL + (
        "phases = [{ pipeline = 'paper-left', episodes = 2 }]\n"
        "camera = 'vision'\n"
        "water = { preset = 'clear', turbidity = 0.3 }\n"
    )
    t = load_experiment(write_toml(tmp_path, text)).trials[0]
    assert (t.camera, t.water) == ("vision", {"preset": "clear", "turbidity": 0.3})
    turbid = run_trial(t, 3)
    ideal = run_trial(dataclasses.replace(t, camera="ideal", water=None), 3)
    np.testing.assert_array_equal(turbid.stats, ideal.stats)  # training: the compiled loops, unchanged
    np.testing.assert_array_equal(turbid.weights, ideal.weights)
    # the heuristic's evaluation episode: the detector in murky water misses frames the exact camera
    # sees, and each miss is the lost pipe's −10
    assert turbid.evaluation["heuristic"][0] < ideal.evaluation["heuristic"][0]
    assert turbid.evaluation == run_trial(t, 3).evaluation  # seeded


def test_the_sensor_of_a_trial_is_its_evaluation_episodes(tmp_path):
    import dataclasses

    from pipefollow.experiments.trial import run_trial

    # the sonar in turbid water: its evaluation episode differs from the ideal camera's, training does not
    text = MINIMAL + "phases = [{ pipeline = 'paper-left', episodes = 2 }]\nsensor = 'sonar'\n"
    text += "water = 'turbid'\n"
    t = load_experiment(write_toml(tmp_path, text)).trials[0]
    assert (t.sensor, t.camera, t.water) == ("sonar", "ideal", "turbid")
    sonar = run_trial(t, 3)
    ideal = run_trial(dataclasses.replace(t, sensor="camera", water=None), 3)
    np.testing.assert_array_equal(sonar.weights, ideal.weights)
    assert sonar.evaluation["heuristic"] != ideal.evaluation["heuristic"]
    assert sonar.evaluation == run_trial(t, 3).evaluation  # seeded


def test_a_trial_takes_every_camera_and_sensor_the_environment_takes(tmp_path):
    import dataclasses

    pytest.importorskip("cv2")
    from pipefollow.experiments.schema import TrialConfig
    from pipefollow.experiments.trial import run_trial
    from pipefollow.perception.camera import CAMERAS, SENSORS

    # one list of cameras and sensors: the environment's (the command line's options are held to it
    # by tests/test_cli.py)
    fields = {f.name: f for f in dataclasses.fields(TrialConfig)}
    assert fields["camera"].metadata["choices"] == CAMERAS
    assert fields["sensor"].metadata["choices"] == SENSORS
    # the detector alone, frame by frame, in murky water: it takes the water's settings, and its
    # evaluation episode differs from the tracker's
    text = MINIMAL + "phases = [{ pipeline = 'paper-left', episodes = 2 }]\ncamera = 'vision-raw'\n"
    text += "water = { preset = 'clear', turbidity = 0.3 }\n"
    t = load_experiment(write_toml(tmp_path, text)).trials[0]
    assert (t.camera, t.water) == ("vision-raw", {"preset": "clear", "turbidity": 0.3})
    raw = run_trial(t, 3)
    tracked = run_trial(dataclasses.replace(t, camera="vision"), 3)
    np.testing.assert_array_equal(raw.weights, tracked.weights)  # training: the ideal camera's
    assert raw.evaluation["heuristic"] != tracked.evaluation["heuristic"]
    # trained through the sensor too: other weights than the ideal camera's, and the weights of
    # train_phases through that sensor itself (the trial adds nothing of its own)
    through = dataclasses.replace(t, camera="vision", train_through_sensor=True)
    res = run_trial(through, 3)
    assert not np.allclose(res.weights, tracked.weights)
    from pipefollow.experiments.trial import build_agent, training_camera
    from pipefollow.training.phases import agent_rng, train_phases

    agent = build_agent(through, agent_rng(3))
    camera = training_camera(through)
    assert camera == {"camera": "vision", "water": {"preset": "clear", "turbidity": 0.3}, "sensor": "camera"}
    train_phases(agent, [("paper-left", 2)], seed=3, episode_seconds=through.episode_seconds, camera=camera)
    np.testing.assert_array_equal(res.weights, agent.weights)
    assert res.evaluation["learned"] == run_trial(through, 3).evaluation["learned"]


@pytest.mark.parametrize(
    "lines, pattern",
    [
        ("water = 'clear'\n", r"key 'water': water settings need camera = 'vision' or 'vision-raw' or"),
        ("sensor = 'radar'\n", r"key 'sensor' must be one of camera, sonar, fused, fls, fused-fls, got"),
        ("camera = 'vision'\nsensor = 'sonar'\n", r"key 'camera' must be 'ideal' with sensor = 'sonar'"),
        ("camera = 'laser'\n", r"key 'camera' must be one of ideal, vision, vision-raw, got 'laser'"),
        ("train_through_sensor = true\n", r"key 'train_through_sensor' must be false with the ideal camera"),
        ("train_through_sensor = 1\ncamera = 'vision'\n", r"key 'train_through_sensor' must be"),
        ("camera = 'vision'\nwater = 'murky'\n", r"key 'water': water preset 'murky': unknown"),
        ("camera = 'vision'\nwater = { turbidity = -1 }\n", r"'water': water setting turbidity must be in"),
        ("camera = 'vision'\nwater = { fog = 1 }\n", r"key 'water': unknown water setting\(s\) \['fog'\]"),
        ("camera = 'vision'\nwater = 3\n", r"key 'water' must be a preset name or a table, got 3"),
    ],
)
def test_bad_camera_or_water_is_a_one_line_error_naming_the_key(tmp_path, lines, pattern):
    with pytest.raises(ConfigError, match=pattern) as err:
        load_experiment(write_toml(tmp_path, MINIMAL + lines))
    assert "\n" not in str(err.value)


def test_the_repeats_experiment_is_the_papers_trials_with_the_papers_first_seeds():
    paper, more = load_experiment("paper"), load_experiment("repeats")
    assert more.trials == paper.trials and more.repeats >= 20
    assert more.seeds()[: paper.repeats] == paper.seeds()  # its first five are the default run's


def test_reproduce_help_names_every_shipped_experiment():
    from click.testing import CliRunner

    from pipefollow.cli import main
    from pipefollow.experiments.config import shipped_experiments

    for command in (["reproduce", "--help"], ["trials", "--help"]):
        text = " ".join(CliRunner().invoke(main, command).output.split())
        assert all(f"'{name}'" in text for name in shipped_experiments()), command
