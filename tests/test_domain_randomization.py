"""Training under randomized disturbances: compiled loops equal the environment; same seed, same numbers."""

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.sim import decision as sim
from pipefollow.sim import randomization as rz
from pipefollow.sim.disturbance import make_disturbance
from pipefollow.sim.pipeline import builtin
from pipefollow.sim.suites import get_suite
from pipefollow.training.agents import make_agent
from pipefollow.training.compiled import run_episode, train, train_compiled
from pipefollow.training.random_pipes import train_random_compiled

KINDS = {
    "cacla": dict(algorithm="cacla"),
    "supervised-skew": dict(algorithm="cacla", skew_deg=22.5, supervised=True),
    "sarsa": dict(algorithm="sarsa"),
}
# every kind on, in ranges wide enough that episodes differ a lot
WILD = rz.Randomization(
    current_speed=(0.0, 0.3),
    current_time_constant=20.0,
    current_speed_sd=0.03,
    current_direction_sd_deg=15.0,
    camera_noise=(0.0, 0.08),
    miss_prob=(0.0, 0.15),
    buried_prob=0.5,
    buried_count=2,
    buried_length_m=(0.3, 1.0),
    buried_region_m=(1.0, 9.0),
)


@pytest.mark.parametrize("kind", list(KINDS))
def test_compiled_path_equals_the_environment_under_randomization(kind):
    pipe = builtin("paper-left")
    a = make_agent(rng=np.random.default_rng(3), **KINDS[kind])
    b = make_agent(rng=np.random.default_rng(3), **KINDS[kind])
    env = PipelineFollowingEnv(pipe, 20, randomization=WILD)
    env.np_random = np.random.default_rng(11)
    currents = []
    stats_env = train(env, a, 8, callback=lambda e, ep: currents.append(env.episode_setup.params.disturbance))
    stats_fast = train_compiled(b, pipe, 8, env_rng=np.random.default_rng(11), randomization=WILD)
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
    # each episode met its own disturbances: the draws of default_rng(11) interleaved with the normals
    assert len({d.current_speed for d in currents}) == 8
    assert stats_env[:, 3].sum() > 0  # misses and burial lost the pipe at times


@pytest.mark.parametrize("kind", ["cacla", "sarsa"])
def test_random_pipes_under_randomization_equal_the_environment_with_one_generator(kind):
    a = make_agent(rng=np.random.default_rng(5), **KINDS[kind])
    b = make_agent(rng=np.random.default_rng(5), **KINDS[kind])
    env = PipelineFollowingEnv("random:hard", 20, randomization="harsh")
    env.np_random = np.random.default_rng(21)
    stats_env = train(env, a, 6)
    g = np.random.default_rng(21)  # the environment's one generator: pipes and disturbances
    stats_fast = train_random_compiled(b, get_suite("hard"), 6, pipe_rng=g, env_rng=g, randomization="harsh")
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)


def test_the_environment_draws_the_disturbances_of_a_reset_first():
    env = PipelineFollowingEnv("paper-left", 20, randomization="moderate")
    env.reset(seed=4)
    expected = rz.draw(rz.PRESETS["moderate"], np.random.default_rng(4))
    assert env.episode_setup.params.disturbance == expected
    _, info = env.reset()
    second = env.episode_setup.params.disturbance
    assert second != expected
    assert float(info["current"][0]) == pytest.approx(second.current_speed)
    # an episode under the draw equals an episode under that disturbance, fixed
    fixed = PipelineFollowingEnv("paper-left", 20, disturbance=expected)
    fixed.np_random = np.random.default_rng(4)
    rz.draw(rz.PRESETS["moderate"], fixed.np_random)  # the draw the randomized reset made
    again = PipelineFollowingEnv("paper-left", 20, randomization="moderate")
    ep_random = run_episode(again, make_agent("cacla", rng=np.random.default_rng(0)), seed=4)
    ep_fixed = run_episode(fixed, make_agent("cacla", rng=np.random.default_rng(0)))
    assert ep_random.ret == ep_fixed.ret


def test_randomization_refuses_a_fixed_disturbance_too():
    with pytest.raises(ValueError, match="not both"):
        PipelineFollowingEnv("paper-left", 20, disturbance={"camera_noise": 0.1}, randomization="mild")
    params = sim.PAPER_SIM._replace(disturbance=make_disturbance(0.1, 0.0))
    with pytest.raises(ValueError, match="not both"):
        train_compiled(make_agent("cacla"), builtin("paper-left"), 2, params=params,
                       env_rng=np.random.default_rng(0), randomization="mild")  # fmt: skip
    with pytest.raises(ValueError, match="env_rng"):
        train_compiled(make_agent("cacla"), builtin("paper-left"), 2, randomization="mild")
    with pytest.raises(rz.DisturbanceError, match="preset 'stormy'"):
        PipelineFollowingEnv("paper-left", 20, randomization="stormy")


# ---------------------------------------------------------------------------------------------
# The command line


def _train(tmp_path, name, *extra):
    out = tmp_path / name
    args = ["train", "--algorithm", "cacla", "--pipeline", "random:mixed", "--episodes", "12", "--seconds",
            "30", "--seed", "7", "--out", str(out), "--json", *extra]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    with np.load(out / "policy.npz") as f:
        return json.loads(res.stdout), f["weights"]


def test_cli_train_with_a_preset_or_a_table_is_seeded(tmp_path):
    a, wa = _train(tmp_path, "a", "--randomization", "moderate")
    b, wb = _train(tmp_path, "b", "--randomization", "moderate")
    calm, wc = _train(tmp_path, "c")
    assert a["returns"] == b["returns"]
    np.testing.assert_array_equal(wa, wb)
    assert a["returns"] != calm["returns"]
    assert a["randomization"]["current_speed"] == [0.0, 0.2]
    table = tmp_path / "sea.toml"
    table.write_text('preset = "moderate"\n')
    t, wt = _train(tmp_path, "t", "--randomization", str(table))
    assert t["returns"] == a["returns"]


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("stormy", "preset 'stormy'"),
        ("{table}", "miss_prob"),
    ],
)
def test_cli_train_bad_randomization_is_one_line_exit_2_and_writes_nothing(tmp_path, value, message):
    table = tmp_path / "bad.toml"
    table.write_text("miss_prob = [0.0, 1.5]\n")
    out = tmp_path / "out"
    args = ["train", "--algorithm", "cacla", "--episodes", "2", "--out", str(out),
            "--randomization", value.format(table=table)]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0]
    assert not out.exists()


def test_the_vector_environment_equals_single_environments_under_randomization():
    from pipefollow.envs.vector_env import PipelineFollowingVectorEnv

    n, seconds = 3, 8
    vec = PipelineFollowingVectorEnv(n, "random:medium", episode_seconds=seconds, randomization=WILD)
    singles = [PipelineFollowingEnv("random:medium", seconds, randomization=WILD) for _ in range(n)]
    obs, _ = vec.reset(seed=40)
    firsts = [env.reset(seed=40 + i)[0] for i, env in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.array(firsts))
    rng = np.random.default_rng(0)
    for t in range(2 * seconds + 1):  # through an autoreset (next step after the end)
        actions = rng.uniform(-1, 1, n)
        obs, rewards, _, truncated, _ = vec.step(actions)
        for i, env in enumerate(singles):
            if t == seconds:  # the step after the end resets it
                o = env.reset()[0]
                r, tr = 0.0, False
            else:
                o, r, _, tr, _ = env.step([actions[i]])
            np.testing.assert_allclose(obs[i], o, rtol=0, atol=1e-12)
            assert rewards[i] == pytest.approx(r, abs=1e-12)
            assert truncated[i] == tr
    assert vec._packed[0].tolist() != vec._packed[1].tolist()  # each its own disturbances


def test_an_experiment_trial_and_train_randomize_alike(tmp_path):
    seed, episodes, seconds = 3, 6, 12
    args = ["train", "--algorithm", "cacla", "--pipeline", "random:easy", "--episodes", str(episodes),
            "--seconds", str(seconds), "--seed", str(seed), "--out", str(tmp_path / "train"), "--json",
            "--randomization", "harsh"]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    from pipefollow.training.policy_files import load_policy

    trained = load_policy(json.loads(res.stdout)["policy"])
    toml = tmp_path / "one.toml"
    toml.write_text(
        f'[experiment]\nname = "one"\nrepeats = 1\nseed = {seed}\n[[trial]]\nname = "t"\n'
        'algorithm = "cacla"\n'
        f'phases = [{{ pipeline = "random:easy", episodes = {episodes} }}]\nepisode_seconds = {seconds}\n'
        'randomization = { preset = "harsh" }\n'
    )
    out = tmp_path / "experiment"
    res = CliRunner().invoke(
        main,
        ["reproduce", "--experiment", str(toml), "--out", str(out), "--backend", "serial", "--no-figures"],
    )
    assert res.exit_code == 0, res.output
    (policy,) = (out / "policies").glob("t-seed*.npz")
    np.testing.assert_array_equal(load_policy(policy).weights, trained.weights)


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ('randomization = "stormy"', "preset 'stormy'"),
        ("randomization = { miss_prob = [0.2, 0.1] }", "miss_prob"),
        ('randomization = "mild"\ndisturbance = { camera_noise = 0.1 }', "not both"),
        ("randomization = 3", "preset name or a table"),
    ],
)
def test_experiment_files_refuse_a_bad_randomization(tmp_path, line, message):
    from pipefollow.experiments.config import ConfigError, load_experiment

    toml = tmp_path / "bad.toml"
    toml.write_text(
        '[experiment]\nname = "bad"\n[[trial]]\nname = "t"\nalgorithm = "cacla"\n'
        f'phases = [{{ pipeline = "paper-left", episodes = 2 }}]\n{line}\n'
    )
    with pytest.raises(ConfigError, match=message) as e:
        load_experiment(toml)
    assert "\n" not in str(e.value)


@pytest.mark.slow
def test_cli_ppo_trains_under_a_randomization(tmp_path):
    pytest.importorskip("stable_baselines3")
    out = tmp_path / "ppo"
    args = ["train", "--algorithm", "ppo", "--pipeline", "random:easy", "--steps", "64", "--seconds", "8",
            "--out", str(out), "--randomization", "mild", "--json"]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["randomization"]["current_speed"] == [0.0, 0.1]
    assert (out / "policy.npz").exists()
