"""pipefollow rollouts: a controller's episodes as a Minari dataset, read back with Minari."""

from __future__ import annotations

import gc
import json
import warnings

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main

minari = pytest.importorskip("minari")
pytest.importorskip("h5py")
pytest.importorskip("jax")
pytestmark = pytest.mark.rollouts


def _load(folder, dataset_id, monkeypatch):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(folder))
    return minari.load_dataset(dataset_id)


def test_heuristic_rollouts_read_back_as_the_episodes_benchmark_runs(tmp_path, monkeypatch):
    args = [
        "rollouts",
        "--suite",
        "heldout",
        "--pipes",
        "3",
        "--seconds",
        "20",
        "--out",
        str(tmp_path),
        "--json",
    ]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["dataset_id"] == "pipefollow/heldout-heuristic-v0" and out["episodes"] == 3
    data = _load(tmp_path, out["dataset_id"], monkeypatch)
    assert data.total_episodes == 3 and data.total_steps == 60
    bench = CliRunner().invoke(main, ["benchmark", "--pipes", "3", "--seconds", "20", "--json"])
    returns = [e["return"] for e in json.loads(bench.stdout)["episodes"]]
    for ep, ret in zip(data.iterate_episodes(), returns, strict=True):
        assert ep.observations.shape == (21, 4) and ep.actions.shape == (20, 1)
        # the same episodes as benchmark's (Minari stores the rewards as float32)
        assert ep.rewards.sum() == pytest.approx(ret, rel=1e-6)
        assert ep.infos["pose"].shape == (21, 3) and ep.infos["current"].shape == (21, 2)
        assert ep.truncations[-1] and not ep.terminations.any()
        np.testing.assert_array_equal(ep.infos["pipe_in_view"][1:], ep.observations[1:, 1] >= 0.0)


def test_exploring_rollouts_of_a_policy_differ_from_deterministic_ones(tmp_path, monkeypatch):
    policy = tmp_path / "p"
    CliRunner().invoke(
        main, ["train", "--algorithm", "cacla", "--episodes", "3", "--out", str(policy), "--json"]
    )
    common = [
        "rollouts",
        "--controller",
        str(policy),
        "--pipes",
        "2",
        "--seconds",
        "10",
        "--out",
        str(tmp_path),
    ]
    assert CliRunner().invoke(main, [*common, "--name", "pipefollow/det-v0"]).exit_code == 0
    assert CliRunner().invoke(main, [*common, "--sigma", "0.5", "--name", "pipefollow/exp-v0"]).exit_code == 0
    det = next(iter(_load(tmp_path, "pipefollow/det-v0", monkeypatch).iterate_episodes()))
    exp = next(iter(_load(tmp_path, "pipefollow/exp-v0", monkeypatch).iterate_episodes()))
    assert not np.array_equal(det.actions, exp.actions)


def test_an_existing_dataset_is_not_replaced(tmp_path):
    args = ["rollouts", "--pipes", "1", "--seconds", "5", "--out", str(tmp_path)]
    assert CliRunner().invoke(main, args).exit_code == 0
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2 and "already holds the dataset" in res.stderr


def _replay(env, reset_kwargs, actions):
    obs = [env.reset(**reset_kwargs)[0]]
    ends = []
    for a in actions:
        o, _, term, trunc, _ = env.step(a)
        obs.append(o)
        ends.append((term, trunc))
    return np.array(obs), ends


@pytest.mark.parametrize("eval_env", [False, True])
def test_a_rollouts_dataset_recovers_an_environment_that_runs_its_episodes(tmp_path, monkeypatch, eval_env):
    from pipefollow.evaluation.rollouts import episode_reset

    # camera noise and misses draw from the environment's generator: only the same seed repeats them
    args = [
        "rollouts",
        "--pipes",
        "2",
        "--seconds",
        "12",
        "--camera-noise",
        "0.05",
        "--miss-prob",
        "0.1",
        "--current",
        "0.1,45",
        "--seed",
        "7",
        "--out",
        str(tmp_path),
        "--name",
        "pipefollow/noisy-v0",
    ]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    data = _load(tmp_path, "pipefollow/noisy-v0", monkeypatch)
    env = data.recover_environment(eval_env=eval_env)
    assert env.spec.max_episode_steps == 12 and env.spec.kwargs["disturbance"]["camera_noise"] == 0.05
    for k, episode in enumerate(data.iterate_episodes()):
        reset = episode_reset(data, k)
        assert reset["seed"] == 7 + k  # the seed of episode k: SEED + k
        obs, ends = _replay(env, reset, episode.actions)
        np.testing.assert_array_equal(obs, episode.observations)
        assert ends == [(False, False)] * 11 + [(False, True)]
        other, _ = _replay(env, {**reset, "seed": reset["seed"] + 100}, episode.actions)
        assert not np.array_equal(other, episode.observations)  # the noise is the seed's


# (not the image id: Minari 0.5 stores image spaces as JPEG through Pillow, which takes no (H, W, 1))
@pytest.mark.parametrize(
    "env_id", ["pipefollow/PipelineFollowing-v0", "pipefollow/PipelineFollowingRandom-v0"]
)
def test_minaris_own_data_collector_records_every_info_of_a_registered_id(tmp_path, monkeypatch, env_id):
    import gymnasium as gym

    import pipefollow.envs  # noqa: F401
    from pipefollow.envs.shell import SUMMARY_KEYS

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    with warnings.catch_warnings():  # Minari 0.5's TemporaryDirectory objects warn when collected
        warnings.simplefilter("ignore", ResourceWarning)
        env = minari.DataCollector(gym.make(env_id, episode_seconds=4), record_infos=True)
        for seed in (0, 1):
            env.reset(seed=seed)
            env.action_space.seed(seed)
            done = False
            while not done:
                *_, term, trunc, _ = env.step(env.action_space.sample())
                done = term or trunc
        data = env.create_dataset(
            dataset_id="test/collected-v0", algorithm_name="random", author="x", author_email="x@example.org",
            code_permalink="https://example.org", description="random actions", eval_env=env_id,
        )  # fmt: skip
        env.close()
        del env
        gc.collect()
    direct = gym.make(env_id, episode_seconds=4)
    for seed, episode in zip((0, 1), data.iterate_episodes(), strict=True):
        assert episode.observations.shape[0] == 5 and episode.truncations[-1]
        infos = episode.infos
        assert set(SUMMARY_KEYS) <= set(infos) and infos["pose"].shape == (5, 3)
        # the summary so far at every step, the episode's at its last, counted here independently
        in_view = infos["pipe_in_view"][1:]
        np.testing.assert_allclose(infos["episode_pipe_in_view"][1:], np.cumsum(in_view) / np.arange(1, 5))
        assert np.isnan(infos["episode_pipe_in_view"][0])
        np.testing.assert_array_equal(infos["episode_progress_m"], infos["progress_m"])
        # and the collector changed nothing: the same seed and actions give the same observations
        obs, _ = _replay(direct, {"seed": seed}, episode.actions)
        np.testing.assert_array_equal(obs, episode.observations)
