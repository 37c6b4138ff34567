"""The paper's learners trained through a camera or sensor in the environment (``training.through_env``).

Through the ideal camera the environment path is the compiled loop (the learner contract), so a
phase trained there must end with the compiled loop's weights and statistics: that holds the
path's plumbing (σ schedule, readings, state, pipes) to an independent computation. Through a
rendered camera or the sonar the learner must see what that sensor shows (other weights than the
ideal camera's), the same seed giving the same numbers.
"""

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow import readings as rd
from pipefollow.cli import main
from pipefollow.training import through_env
from pipefollow.training.phases import train_phases
from pipefollow.training.runs import new_agent
from pipefollow.training.through_env import env_seed, train_through_env

VISION_FUSED = {"camera": "vision", "sensor": "fused", "water": {"preset": "turbid"}}


def _trained(algorithm: str, camera, seed: int = 3, pipeline: str = "paper-left", **options):
    agent = new_agent(algorithm, seed, rd.DEFAULT, **options)
    stats = train_phases(agent, [(pipeline, 4)], seed=seed, episode_seconds=8.0, camera=camera)
    return agent, stats[0]


@pytest.mark.parametrize("algorithm, options", [("sarsa", {}), ("cacla", {}), ("cacla", {"supervised": True}),
                                                ("ac", {})])  # fmt: skip
def test_through_the_ideal_camera_the_environment_path_is_the_compiled_loop(algorithm, options):
    compiled, c_stats = _trained(algorithm, None, **options)
    through, e_stats = _trained(algorithm, {"camera": "ideal"}, **options)
    np.testing.assert_allclose(e_stats, c_stats, rtol=0, atol=1e-9)
    np.testing.assert_allclose(through.weights, compiled.weights, rtol=0, atol=1e-9)
    assert np.any(compiled.weights != 0.0)  # it learned something to compare


def test_through_a_sensor_the_learner_sees_the_sensor_and_a_seed_fixes_the_numbers():
    ideal, _ = _trained("cacla", None, supervised=True)
    first, s1 = _trained("cacla", VISION_FUSED, supervised=True)
    again, s2 = _trained("cacla", VISION_FUSED, supervised=True)
    np.testing.assert_array_equal(first.weights, again.weights)
    np.testing.assert_array_equal(s1, s2)
    assert not np.allclose(first.weights, ideal.weights)  # the fused sensor's view, not the exact one
    # another environment stream alone (the agent's generator the same): other images, other weights
    other = new_agent("cacla", 3, rd.DEFAULT, supervised=True)
    sigma = (1.0, 0.01)
    train_through_env(other, "paper-left", 4, camera=VISION_FUSED, seed=4, episode_seconds=8.0,
                      sigma_start=sigma[0], sigma_end=sigma[1])  # fmt: skip
    same = new_agent("cacla", 3, rd.DEFAULT, supervised=True)
    train_through_env(same, "paper-left", 4, camera=VISION_FUSED, seed=3, episode_seconds=8.0,
                      sigma_start=sigma[0], sigma_end=sigma[1])  # fmt: skip
    np.testing.assert_array_equal(same.weights, first.weights)  # train_phases' single phase is this
    assert not np.allclose(other.weights, first.weights)


def test_random_pipes_through_a_sensor_come_from_the_environments_stream(monkeypatch):
    # the environment draws a random phase's pipes from its own stream: the agent's generator alone
    # (monkeypatched env_seed held fixed) gives the same pipes, so the same distance along them
    sonar = {"camera": "ideal", "sensor": "sonar"}
    _, s_a = _trained("cacla", sonar, pipeline="random:mixed")
    _, s_b = _trained("cacla", sonar, pipeline="random:mixed")
    np.testing.assert_array_equal(s_a, s_b)
    lengths = []
    import pipefollow.envs.env as env_module

    made = env_module.PipelineFollowingEnv.reset

    def reset(self, *args, **kwargs):  # the pipe of every episode
        out = made(self, *args, **kwargs)
        lengths.append(round(float(self.pipeline.length), 9))
        return out

    monkeypatch.setattr(env_module.PipelineFollowingEnv, "reset", reset)
    for agent_seed in (3, 4):
        monkeypatch.setattr(through_env, "env_seed", lambda seed, phase=0: 11)
        _trained("cacla", sonar, seed=agent_seed, pipeline="random:mixed")
    assert lengths[:4] == lengths[4:] and len(set(lengths[:4])) > 1
    lengths.clear()
    for stream in (11, 12):
        monkeypatch.setattr(through_env, "env_seed", lambda seed, phase=0, s=stream: s)
        _trained("cacla", sonar, pipeline="random:mixed")
    assert lengths[:4] != lengths[4:]


def test_each_phase_has_a_stream_of_its_own_apart_from_the_compiled_loops():
    seeds = {env_seed(s, k) for s in range(3) for k in range(3)}
    assert len(seeds) == 9
    # child 0 is the compiled loops' stream (phases.disturbance_rng): not reused
    child0 = np.random.SeedSequence(0, spawn_key=(0,)).generate_state(1, dtype=np.uint32)[0]
    assert env_seed(0, 0) != int(child0)


def test_two_phases_train_through_two_streams():
    agent = new_agent("cacla", 3, rd.DEFAULT)
    stats = train_phases(agent, [("random:mixed", 3), ("random:mixed", 3)], seed=3, episode_seconds=8.0,
                         camera={"camera": "ideal", "sensor": "sonar"})  # fmt: skip
    assert [s.shape[0] for s in stats] == [3, 3]
    assert not np.array_equal(stats[0], stats[1])


FUSED_TURBID = ["--camera", "vision", "--sensor", "fused", "--water", "turbid"]


@pytest.mark.parametrize("given", [["--camera", "vision"], ["--sensor", "sonar"], FUSED_TURBID])
def test_train_takes_a_sensor_for_the_papers_learners_and_records_it(given, tmp_path):
    args = ["train", "--algorithm", "cacla", "--episodes", "3", "--seconds", "6", "--json", *given]
    runs = [CliRunner().invoke(main, [*args, "--out", str(tmp_path / name)]) for name in ("a", "b")]
    for res in runs:
        assert res.exit_code == 0, res.output
    out = [json.loads(res.output) for res in runs]
    assert out[0]["returns"] == out[1]["returns"]
    assert out[0]["camera"] == given[1] if given[0] == "--camera" else out[0]["sensor"] == "sonar"
    if "--water" in given:
        assert out[0]["sensor"] == "fused" and out[0]["water"]["turbidity"] == 0.25
    # the policy learned through the sensor: the same run on the ideal camera learns other weights
    ideal = CliRunner().invoke(main, [*args[: -len(given)], "--out", str(tmp_path / "ideal")])
    assert ideal.exit_code == 0, ideal.output
    assert "camera" not in json.loads(ideal.output)
    with np.load(tmp_path / "a" / "policy.npz") as a, np.load(tmp_path / "ideal" / "policy.npz") as i:
        assert not np.allclose(a["weights"], i["weights"])
        through = json.loads(json.loads(str(a["metadata"]))["trained_through"])
        assert "trained_through" not in json.loads(str(i["metadata"]))
    assert through["camera"] == out[0]["camera"] and through["sensor"] == out[0].get("sensor", "camera")
    assert through["water"] == out[0]["water"]


def test_trains_text_names_the_sensor_trained_through(tmp_path):
    args = ["train", "--algorithm", "sarsa", "--episodes", "2", "--seconds", "5"]
    res = CliRunner().invoke(main, [*args, *FUSED_TURBID, "--burial", "0.3", "--out", str(tmp_path / "a")])
    assert res.exit_code == 0, res.output
    last = res.output.strip().splitlines()[-1]
    assert last == "trained through: camera vision, sensor fused, water turbidity 0.25, burial 0.3"
    ideal = CliRunner().invoke(main, [*args, "--out", str(tmp_path / "b")])
    assert ideal.exit_code == 0 and "trained through" not in ideal.output
