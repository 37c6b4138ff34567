import json

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.evaluation import benchmark as bm
from pipefollow.learners.mlp import MLPPolicy
from pipefollow.sim.suites import get_suite
from pipefollow.training.policy_files import PolicyError, load_policy, save_policy


def random_mlp(rng, output="clip", hidden=(64, 64), activation="tanh"):
    sizes = [4, *hidden, 1]
    weights = [rng.normal(size=(o, i)) / np.sqrt(i) for i, o in zip(sizes[:-1], sizes[1:], strict=True)]
    biases = [rng.normal(size=o) * 0.1 for o in sizes[1:]]
    acts = [activation] * len(hidden) + ["identity"]
    return MLPPolicy(weights, biases, acts, output=output, trained_by="ppo")


def reference(policy, obs):
    """Independent forward pass: one observation at a time, plain Python floats."""
    scaling = zip(obs, policy.obs_offset, policy.obs_scale, strict=True)
    h = [(float(o) - float(off)) * float(sc) for o, off, sc in scaling]
    for w, b, act in zip(policy.weights, policy.biases, policy.activations, strict=True):
        h = [sum(float(w[j, i]) * h[i] for i in range(len(h))) + float(b[j]) for j in range(w.shape[0])]
        if act == "tanh":
            h = [float(np.tanh(v)) for v in h]
        elif act == "relu":
            h = [max(v, 0.0) for v in h]
    y = h[0]
    if policy.output == "tanh":
        return -1.0 + (np.tanh(y) + 1.0)
    return min(max(y, -1.0), 1.0)


@pytest.mark.parametrize("output,activation", [("clip", "tanh"), ("tanh", "relu")])
def test_compiled_forward_matches_an_independent_reference(output, activation):
    rng = np.random.default_rng(1)
    policy = random_mlp(rng, output, activation=activation)
    obs = rng.uniform([-1, 0, -1, -1], [1, 3, 1, 1], size=(40, 4)) * 2.0  # also outside the box
    batch = policy.predict(obs)[:, 0]
    acts = np.array([policy.act(o) for o in obs])
    ref = np.array([reference(policy, o) for o in obs])
    np.testing.assert_allclose(acts, ref, atol=1e-12)
    np.testing.assert_allclose(batch, ref, atol=1e-12)
    assert np.all(np.abs(acts) <= 1.0)
    assert np.any(np.abs(acts) == 1.0) == (output == "clip")  # large inputs saturate the clip only


def test_round_trip_without_pickle(tmp_path):
    rng = np.random.default_rng(2)
    policy = random_mlp(rng, "tanh")
    path = save_policy(policy, tmp_path / "p.npz", hyperparameters={"gamma": 0.95}, seed=3)
    with np.load(path, allow_pickle=False) as z:
        assert str(z["algorithm"]) == "mlp" and int(z["format_version"]) == 4
        assert json.loads(str(z["params"])) == {"gamma": 0.95}
    loaded = load_policy(path)
    assert loaded.name == "PPO, MLP 64×64" and loaded.hyperparameters == {"gamma": 0.95}
    obs = rng.uniform([-1, 0, -1, -1], [1, 3, 1, 1], size=(20, 4))
    assert [loaded.act(o) for o in obs] == [policy.act(o) for o in obs]


def test_network_that_does_not_fit_the_spaces_is_refused(tmp_path):
    rng = np.random.default_rng(3)
    path = save_policy(random_mlp(rng), tmp_path / "ok.npz")
    with np.load(path) as z:
        data = dict(z)
    bad_in = dict(data, layer0_weight=np.zeros((64, 3)))
    np.savez(tmp_path / "in.npz", **bad_in)
    with pytest.raises(PolicyError, match=r"in\.npz.*observation gives 4 values") as e:
        load_policy(tmp_path / "in.npz")
    assert "\n" not in str(e.value)
    for command in ("evaluate", "benchmark"):  # on the command line: one line, exit 2
        res = CliRunner().invoke(main, [command, "--controller", str(tmp_path / "in.npz")])
        assert res.exit_code == 2 and len(res.stderr.strip().splitlines()) == 1
        assert res.stderr.startswith(f"pipefollow: error: policy file '{tmp_path / 'in.npz'}'")
    bad_out = dict(data, layer2_weight=np.zeros((2, 64)), layer2_bias=np.zeros(2))
    np.savez(tmp_path / "out.npz", **bad_out)
    with pytest.raises(PolicyError, match="gives 2 outputs, the action space has 1"):
        load_policy(tmp_path / "out.npz")
    np.savez(tmp_path / "nan.npz", **dict(data, layer1_bias=np.full(64, np.nan)))
    with pytest.raises(PolicyError, match="NaN"):
        load_policy(tmp_path / "nan.npz")
    np.savez(tmp_path / "missing.npz", **{k: v for k, v in data.items() if k != "layer1_bias"})
    with pytest.raises(PolicyError, match="missing or malformed"):
        load_policy(tmp_path / "missing.npz")


def test_compiled_benchmark_equals_the_environment_path():
    rng = np.random.default_rng(4)
    policy = random_mlp(rng, "clip")
    pipes = get_suite("heldout").pipes(6, 46.0)
    compiled, poses = bm.run_episodes(policy, pipes, 30.0)
    env_out, env_poses = np.zeros_like(compiled), np.zeros_like(poses)
    bm._env_episodes(policy, pipes, 30.0, bm.sim.PAPER_SIM, env_out, env_poses)
    np.testing.assert_allclose(compiled, env_out, rtol=0, atol=1e-9)
    np.testing.assert_allclose(poses, env_poses, rtol=0, atol=1e-9)
    assert len(set(np.round(compiled[:, 0], 6))) > 1  # the policy acts: returns differ by pipe
