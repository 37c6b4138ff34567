import numpy as np
import pytest

from pipefollow.training.agents import make_agent
from pipefollow.training.policy_files import PolicyError, load_policy, save_policy


@pytest.mark.parametrize("compress", [True, False])
@pytest.mark.parametrize(
    "kind", [dict(algorithm="sarsa"), dict(algorithm="cacla", skew_deg=22.5, supervised=True)]
)
def test_loaded_policy_acts_exactly_as_saved(tmp_path, kind, compress):
    import zipfile

    rng = np.random.default_rng(0)
    agent = make_agent(rng=rng, **kind)
    agent.weights[:] = rng.normal(size=agent.weights.shape) * 0.3
    path = save_policy(agent, tmp_path / "p.npz", compress=compress)
    with zipfile.ZipFile(path) as z:
        stored = z.getinfo("weights.npy").compress_type
    assert stored == (zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED)
    loaded = load_policy(path)
    assert loaded.params == agent.params
    np.testing.assert_array_equal(loaded.weights, agent.weights)
    for obs in rng.uniform([-1, 0, -1, -0.2], [1, 3, 1, 0.5], size=(50, 4)):
        assert loaded.act(obs, explore=False) == agent.act(obs, explore=False)
    with np.load(path, allow_pickle=False) as z:  # no pickled objects inside
        assert str(z["algorithm"]) == kind["algorithm"]
        assert str(z["package_version"])


def test_missing_foreign_corrupt_and_wrong_shape_files(tmp_path):
    with pytest.raises(PolicyError, match="no such file"):
        load_policy(tmp_path / "nope.npz")
    np.savez(tmp_path / "foreign.npz", weights=np.zeros(3))
    with pytest.raises(PolicyError, match="not a pipefollow policy"):
        load_policy(tmp_path / "foreign.npz")
    (tmp_path / "junk.npz").write_text("hello")
    with pytest.raises(PolicyError, match="not a readable"):
        load_policy(tmp_path / "junk.npz")
    agent = make_agent("cacla")
    path = save_policy(agent, tmp_path / "ok.npz")
    with np.load(path) as z:
        data = dict(z)
    data["weights"] = np.zeros((4, 10))
    np.savez(tmp_path / "shape.npz", **data)
    with pytest.raises(PolicyError, match=r"weights have shape \(4, 10\), expected \(4, 1764\)"):
        load_policy(tmp_path / "shape.npz")
    data["weights"] = np.full((4, 1764), np.nan)
    np.savez(tmp_path / "nan.npz", **data)
    with pytest.raises(PolicyError, match="NaN"):
        load_policy(tmp_path / "nan.npz")


def test_save_is_atomic_and_leaves_no_temporary_files(tmp_path):
    save_policy(make_agent("sarsa"), tmp_path / "a" / "p.npz")
    assert [p.name for p in (tmp_path / "a").iterdir()] == ["p.npz"]


@pytest.mark.parametrize("version", [1, 2])
def test_policy_files_before_format_3_are_refused_in_one_line(tmp_path, version):
    path = save_policy(make_agent("sarsa"), tmp_path / "p.npz")
    with np.load(path) as z:
        data = dict(z)
    data["format_version"] = np.array(version)
    np.savez(tmp_path / "old.npz", **data)
    message = f"old.npz': format version {version} is older than this pipefollow reads$"
    with pytest.raises(PolicyError, match=message):
        load_policy(tmp_path / "old.npz")


def test_written_files_get_the_usual_permissions(tmp_path):
    import os
    import stat

    path = save_policy(make_agent("cacla"), tmp_path / "p.npz")
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~mask


@pytest.mark.parametrize("content", [b"PK\x03\x04 not a zip", b"PK\x05\x06" + b"\x00" * 18, b"\x93NUMPY"])
def test_a_damaged_policy_file_is_refused_and_closed(tmp_path, content):
    import gc

    path = tmp_path / "bad.npz"
    path.write_bytes(content)
    with pytest.raises(PolicyError, match="bad.npz"):
        load_policy(path)
    gc.collect()  # an unclosed file would warn here (ResourceWarning; an error in this suite)
