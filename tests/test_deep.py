"""PPO and SAC through Stable-Baselines3 (extra 'deep'): short trainings only."""

import json
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

import pipefollow.training
from pipefollow.cli import main
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.training.policy_files import load_policy

pytestmark = pytest.mark.deep


def _sb3():
    return pytest.importorskip("stable_baselines3")


def random_obs(n, seed=0):
    # the observation box and beyond it (saturating the networks)
    return np.random.default_rng(seed).uniform([-2, -1, -2, -2], [2, 4, 2, 2], size=(n, 4))


@pytest.mark.slow  # ≈ 20 s; training and export also run in test_cli_trains_ppo_and_sac_...
@pytest.mark.parametrize("algorithm", ["ppo", "sac"])
def test_exported_actor_equals_the_models_deterministic_predict(algorithm):
    _sb3()
    from pipefollow.training.deep import train_deep

    small = dict(n_envs=2, n_steps=64, batch_size=64) if algorithm == "ppo" else dict(learning_starts=100)
    run = train_deep(algorithm, "random:mixed", steps=256, seconds=20, seed=3, **small)
    assert run.steps >= 256 and len(run.returns) >= 1
    from pipefollow.training.deep import export_policy

    obs = random_obs(500)
    expected = run.model.predict(obs, deterministic=True)[0][:, 0]
    np.testing.assert_allclose(run.policy.predict(obs)[:, 0], expected, rtol=0, atol=1e-6)
    np.testing.assert_allclose([run.policy.act(o) for o in obs], expected, rtol=0, atol=1e-6)
    assert len(set(np.round(expected, 4))) > 100  # a real function of the observation, not a constant
    # a larger output layer drives the actions to the bounds: PPO's clip, SAC's tanh
    head = run.model.policy.action_net if algorithm == "ppo" else run.model.actor.mu
    head.weight.data *= 20.0
    expected = run.model.predict(obs, deterministic=True)[0][:, 0]
    assert np.mean(np.abs(expected) > 0.9) > 0.2
    np.testing.assert_allclose(export_policy(run.model, algorithm).predict(obs)[:, 0], expected, atol=1e-6)


def test_same_seed_same_training():
    _sb3()
    from pipefollow.training.deep import train_deep

    runs = [
        train_deep("ppo", "random:easy", steps=128, seconds=10, seed=5, n_envs=2, n_steps=64, batch_size=64)
        for _ in "ab"
    ]
    assert runs[0].returns == runs[1].returns
    for w0, w1 in zip(runs[0].policy.weights, runs[1].policy.weights, strict=True):
        np.testing.assert_array_equal(w0, w1)


def test_adapter_equals_dummy_vec_env_of_single_environments():
    _sb3()
    from stable_baselines3.common.vec_env import DummyVecEnv

    from pipefollow.envs.vector_env import PipelineFollowingVectorEnv
    from pipefollow.training.deep import SB3VecEnv

    kw = dict(episode_seconds=4, start_lateral_noise=0.2)
    ours = SB3VecEnv(PipelineFollowingVectorEnv(3, "random:mixed", **kw))
    ref = DummyVecEnv([lambda: PipelineFollowingEnv("random:mixed", **kw) for _ in range(3)])
    ours.seed(9), ref.seed(9)
    np.testing.assert_array_equal(ours.reset(), ref.reset())
    rng = np.random.default_rng(0)
    dones = 0
    for _ in range(13):
        a = rng.uniform(-1, 1, size=(3, 1)).astype(np.float32)
        o1, r1, d1, i1 = ours.step(a)
        o2, r2, d2, i2 = ref.step(a)
        np.testing.assert_allclose(o1, o2, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(r1.astype(np.float32), r2)  # DummyVecEnv keeps float32 rewards
        np.testing.assert_array_equal(d1, d2)
        for x, y, d in zip(i1, i2, d1, strict=True):
            if d:
                dones += 1
                np.testing.assert_allclose(x["terminal_observation"], y["terminal_observation"], atol=1e-12)
                assert x["TimeLimit.truncated"] and y["TimeLimit.truncated"]
    assert dones == 9


def test_cli_trains_ppo_and_sac_and_the_policies_run_without_torch(tmp_path):
    _sb3()
    runner = CliRunner()
    for algorithm in ("ppo", "sac"):
        out = tmp_path / algorithm
        args = ["train", "--algorithm", algorithm, "--pipeline", "random:easy", "--seconds", "10"]
        if algorithm == "ppo":  # the disturbance options reach the training environment
            args += ["--current", "0.1,45", "--camera-noise", "0.05"]
        res = runner.invoke(main, [*args, "--steps", "200", "--seed", "1", "--out", str(out), "--json"])
        assert res.exit_code == 0, res.output
        result = json.loads(res.stdout)
        assert set(result) >= {"policy", "returns", "steps", "wall_s"}
        assert ("disturbance" in result) == (algorithm == "ppo")
        res = runner.invoke(main, ["evaluate", "--controller", result["policy"], "--json"])
        assert res.exit_code == 0, res.output
        assert json.loads(res.stdout)["mean_progress_m"] > 0
        assert result["steps"] >= 200 and result["wall_s"] > 0 and len(result["returns"]) >= 1
        hp = json.loads((out / "hyperparameters.json").read_text())
        assert (
            hp["algorithm"] == algorithm
            and hp["hyperparameters"]["gamma"] == {"ppo": 0.8, "sac": 0.95}[algorithm]
        )
        assert load_policy(result["policy"]).trained_by == algorithm
    # loading and benchmarking a policy file with torch and Stable-Baselines3 unimportable
    code = (
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] in ('torch', 'stable_baselines3'):\n"
        "            raise ImportError(name)\n"
        "sys.meta_path.insert(0, Block())\n"
        "from pipefollow.training.policy_files import load_policy\n"
        "from pipefollow.evaluation.benchmark import benchmark\n"
        "from pipefollow.sim.suites import get_suite\n"
        f"p = load_policy({str(tmp_path / 'sac' / 'policy.npz')!r})\n"
        "s = benchmark(p, get_suite('heldout'), controller='sac', seconds=20, n_pipes=5).summary\n"
        "print(p.name, s['n_episodes'], 'torch' in sys.modules)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["SAC,", "MLP", "64×64", "5", "False"]


def test_without_the_extra_ppo_is_a_one_line_error(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "stable_baselines3", None)  # makes the import fail
    monkeypatch.delitem(sys.modules, "pipefollow.training.deep", raising=False)
    monkeypatch.delattr(pipefollow.training, "deep", raising=False)
    res = CliRunner().invoke(main, ["train", "--algorithm", "ppo", "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "pip install 'pipefollow[deep]'" in lines[0], res.stderr
    assert lines[0].startswith("pipefollow: error: ")
    assert not (tmp_path / "o").exists()


def test_deep_options_are_checked(tmp_path):
    runner = CliRunner()
    res = runner.invoke(main, ["train", "--algorithm", "sac", "--episodes", "5", "--out", str(tmp_path)])
    assert res.exit_code == 2 and "--episodes not available with --algorithm sac" in res.stderr
    res = runner.invoke(main, ["train", "--algorithm", "cacla", "--steps", "5", "--out", str(tmp_path)])
    assert res.exit_code == 2 and "--steps applies to --algorithm ppo and sac only" in res.stderr
    _sb3()
    res = runner.invoke(
        main, ["train", "--algorithm", "ppo", "--pipeline", "nope", "--out", str(tmp_path / "x")]
    )
    assert res.exit_code == 2 and "nope" in res.stderr and not (tmp_path / "x").exists()
