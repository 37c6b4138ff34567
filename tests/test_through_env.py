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
from pipefollow.training.phases import agent_rng, train_phases
from pipefollow.training.runs import new_agent
from pipefollow.training.through_env import env_seed

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
    other, _ = _trained("cacla", VISION_FUSED, seed=4, supervised=True)
    assert not np.allclose(other.weights, first.weights)


def test_random_pipes_through_a_sensor_come_from_the_environments_stream():
    # the environment draws a random phase's pipes: seeds give other pipes, the same seed the same
    a, s_a = _trained("cacla", {"camera": "ideal", "sensor": "sonar"}, pipeline="random:mixed")
    b, s_b = _trained("cacla", {"camera": "ideal", "sensor": "sonar"}, pipeline="random:mixed")
    c, s_c = _trained("cacla", {"camera": "ideal", "sensor": "sonar"}, seed=4, pipeline="random:mixed")
    np.testing.assert_array_equal(s_a, s_b)
    assert not np.array_equal(s_a, s_c)


def test_each_phase_has_a_stream_of_its_own_apart_from_the_disturbances():
    seeds = {env_seed(s, k) for s in range(3) for k in range(3)}
    assert len(seeds) == 9
    # child 0 is the compiled loops' disturbance stream (phases.disturbance_rng): not reused
    child0 = np.random.SeedSequence(0, spawn_key=(0,)).generate_state(1, dtype=np.uint32)[0]
    assert env_seed(0, 0) != int(child0)
    assert agent_rng(0).integers(1 << 30) == np.random.default_rng(0).integers(1 << 30)


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
