"""The benchmark: compiled episodes equal the environment's; its statistics match independent computation."""

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner
from scipy import stats as sps

from pipefollow.cli import main
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.evaluation.benchmark import _env_episodes, _rms, benchmark, heuristic_camera, run_episodes
from pipefollow.evaluation.stats import N_RESAMPLES, bootstrap_ci
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim.suites import get_suite
from pipefollow.training.agents import make_agent
from pipefollow.training.policy_files import save_policy

KEYS = {
    "controller", "suite", "n_episodes", "mean_return", "ci95_mean", "iqm_return", "ci95_iqm",
    "success_rate", "mean_pipe_in_view", "rms_e_dist", "mean_progress_m", "episodes",
    "in_view_rate", "mean_progress_share", "reached_end", "turned_back", "lost_pipes",
}  # fmt: skip


def _random_agent(kind, seed=1):
    rng = np.random.default_rng(seed)
    if kind == "heuristic":
        return Heuristic()
    if kind == "sarsa":
        agent = make_agent("sarsa", rng=rng)
    else:
        agent = make_agent("cacla", supervised=kind == "supervised", rng=rng)
    agent.weights[...] = rng.normal(0.0, 0.5, agent.weights.shape)
    return agent


@pytest.mark.parametrize("kind", ["heuristic", "cacla", "supervised", "sarsa"])
def test_compiled_episodes_equal_the_environment(kind):
    agent = _random_agent(kind)
    pipes = get_suite("heldout").pipes(4)
    res, poses = run_episodes(agent, pipes, 30.0)
    env_res, env_poses = np.zeros_like(res), np.zeros_like(poses)
    _env_episodes(agent, pipes, 30.0, PipelineFollowingEnv().params, env_res, env_poses)
    np.testing.assert_allclose(res, env_res, rtol=0, atol=1e-9)
    np.testing.assert_allclose(poses, env_poses, rtol=0, atol=1e-9)


def test_summary_matches_an_independent_computation():
    agent = _random_agent("supervised", seed=4)
    agent.weights[3] = 0.6  # trust the learned actor partly: differs from the heuristic
    run = benchmark(agent, get_suite("heldout"), controller="x", seconds=40.0, n_pipes=30, seed=3)
    s = run.summary
    assert set(s) == KEYS | {"vs_heuristic"}
    eps = s["episodes"]
    ret = np.array([e["return"] for e in eps])
    view = np.array([e["pipe_in_view"] for e in eps])
    assert s["n_episodes"] == 30 and [e["name"] for e in eps][:2] == ["heldout-000", "heldout-001"]
    assert s["mean_return"] == pytest.approx(ret.mean(), abs=1e-12)
    assert s["iqm_return"] == pytest.approx(sps.trim_mean(ret, 0.25), abs=1e-12)
    assert s["iqm_return"] == pytest.approx(np.sort(ret)[7:23].mean(), abs=1e-12)  # the middle 16 of 30
    # success: in view at ≥ 95 % and progress ≥ half the distance covered (the straight lines between
    # the recorded poses), capped by the pipe's length; none of these pipes is short enough to end
    swum = np.hypot(*np.diff(run.poses[:, :, :2], axis=1).transpose(2, 0, 1)).sum(axis=1)
    progress = np.array([e["progress_m"] for e in eps])
    lengths = np.array([p.length for p in run.pipes])
    share = progress / np.minimum(swum, lengths)
    np.testing.assert_allclose([e["progress_share"] for e in eps], share, rtol=1e-12)
    assert s["success_rate"] == np.mean((view >= 0.95) & (share >= 0.5))
    assert s["in_view_rate"] == np.mean(view >= 0.95) and s["reached_end"] == 0
    assert s["mean_progress_share"] == pytest.approx(share.mean(), rel=1e-12)
    assert s["mean_pipe_in_view"] == pytest.approx(view.mean())
    assert s["lost_pipes"] == np.sum(view < 0.8) and 0 < s["lost_pipes"] < 30
    n_seen = view * 40
    rms = np.array([e["rms_e_dist"] for e in eps], dtype=float)
    pooled = math.sqrt(np.nansum(rms**2 * n_seen) / n_seen.sum())
    assert s["rms_e_dist"] == pytest.approx(pooled, rel=1e-12)
    ci = sps.bootstrap((ret,), np.mean, n_resamples=N_RESAMPLES, method="BCa", rng=np.random.default_rng(3))
    assert s["ci95_mean"] == [ci.confidence_interval.low, ci.confidence_interval.high]
    assert s["ci95_mean"][0] < s["mean_return"] < s["ci95_mean"][1]
    # the IQM's interval: percentiles of the IQMs of pipes resampled with replacement (rliable's
    # stratified bootstrap with the pipes as runs of one task); its centre is near the IQM
    lo, hi = s["ci95_iqm"]
    assert lo < s["iqm_return"] < hi
    idx = np.random.default_rng(0).integers(0, 30, size=(4000, 30))
    ref = np.percentile(sps.trim_mean(ret[idx], 0.25, axis=1), [2.5, 97.5])
    assert abs(lo - ref[0]) < 0.1 * (hi - lo) and abs(hi - ref[1]) < 0.1 * (hi - lo)
    diff = ret - run.heuristic_returns
    h = benchmark(Heuristic(), get_suite("heldout"), controller="heuristic", seconds=40.0, n_pipes=30)
    np.testing.assert_array_equal(run.heuristic_returns, [e["return"] for e in h.summary["episodes"]])
    v = s["vs_heuristic"]
    assert v["mean_diff"] == pytest.approx(diff.mean(), abs=1e-12)
    assert v["win_rate"] == np.mean(diff > 0)
    assert 0.0 < v["win_rate"] < 1.0
    cid = sps.bootstrap((diff,), np.mean, n_resamples=N_RESAMPLES, method="BCa", rng=np.random.default_rng(3))
    assert v["ci95_diff"] == [cid.confidence_interval.low, cid.confidence_interval.high]


def test_ci_contains_the_mean_and_shrinks_with_more_pipes():
    widths = []
    for n in (10, 100):
        s = benchmark(Heuristic(), get_suite("heldout"), controller="heuristic", n_pipes=n).summary
        lo, hi = s["ci95_mean"]
        assert lo < s["mean_return"] < hi
        widths.append(hi - lo)
    assert widths[1] < 0.6 * widths[0]


def test_a_controller_acting_as_the_heuristic_has_a_paired_difference_of_exactly_zero():
    agent = make_agent("cacla", supervised=True, rng=np.random.default_rng(0))  # k(s) = 0: the supervisor
    s = benchmark(agent, get_suite("heldout-hard"), controller="x", n_pipes=20).summary
    assert s["vs_heuristic"] == {"mean_diff": 0.0, "ci95_diff": [0.0, 0.0], "win_rate": 0.0}
    assert bootstrap_ci([2.5] * 7) == (2.5, 2.5)


def test_rms_e_dist_is_none_without_a_decision_in_view():
    assert _rms(0.0, 0.0) is None
    assert _rms(8.0, 2.0) == 2.0


def test_cli_benchmark_json_and_plot(tmp_path):
    agent = _random_agent("cacla", seed=2)
    policy = save_policy(agent, tmp_path / "p.npz")
    plot = tmp_path / "b.png"
    args = ["benchmark", "--controller", str(policy), "--suite", "heldout-easy", "--pipes", "5"]
    res = CliRunner().invoke(main, [*args, "--seconds", "20", "--json", "--plot", str(plot)])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert set(out) == KEYS | {"vs_heuristic", "readings", "plot"} and out["readings"] == "default"
    assert out["plot"] == str(plot)
    assert set(out["vs_heuristic"]) == {"mean_diff", "ci95_diff", "win_rate"}
    assert set(out["episodes"][0]) == {"name", "return", "pipe_in_view", "progress_m", "rms_e_dist",
                                       "progress_share", "reached_end", "turned_back", "success"}  # fmt: skip
    assert out["controller"] == str(policy) and out["suite"] == "heldout-easy" and out["n_episodes"] == 5
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    res = CliRunner().invoke(main, ["benchmark", "--pipes", "3", "--json"])
    assert res.exit_code == 0 and set(json.loads(res.stdout)) == KEYS | {"readings"}


def test_cli_benchmark_with_a_current_camera_noise_and_los():
    args = [
        "benchmark",
        "--controller",
        "los",
        "--lookahead",
        "1.2",
        "--suite",
        "heldout-easy",
        "--pipes",
        "4",
    ]
    args += ["--seconds", "20", "--current", "0.1,45", "--camera-noise", "0.05", "--miss-prob", "0.02"]
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["disturbance"]["camera_noise"] == 0.05 and out["n_episodes"] == 4
    assert out == json.loads(CliRunner().invoke(main, [*args, "--json"]).stdout)  # seeded
    other = json.loads(CliRunner().invoke(main, [*args, "--json", "--seed", "1"]).stdout)
    assert other["mean_return"] != out["mean_return"]  # the noise follows --seed
    bad = CliRunner().invoke(main, ["benchmark", "--lookahead", "1.0", "--pipes", "2"])
    assert bad.exit_code == 2 and "--lookahead applies to --controller los only" in bad.stderr


@pytest.mark.parametrize("kind", ["heuristic", "los", "cacla", "sarsa"])
def test_compiled_episodes_equal_the_environment_under_random_disturbances(kind):
    from pipefollow.learners.los import LOS
    from pipefollow.sim import decision as sim
    from pipefollow.sim.disturbance import make_disturbance

    agent = LOS(1.3) if kind == "los" else _random_agent(kind)
    params = sim.PAPER_SIM._replace(
        disturbance=make_disturbance(0.1, 120.0, camera_noise=0.05, miss_prob=0.03)
    )
    pipes = get_suite("heldout").pipes(3)
    res, poses = run_episodes(agent, pipes, 30.0, params, noise_seed=7)
    env_res, env_poses = np.zeros_like(res), np.zeros_like(poses)
    _env_episodes(agent, pipes, 30.0, params, env_res, env_poses, noise_seed=7)
    np.testing.assert_allclose(res, env_res, rtol=0, atol=1e-9)
    np.testing.assert_allclose(poses, env_poses, rtol=0, atol=1e-9)
    clean, _ = run_episodes(agent, pipes, 30.0, noise_seed=7)
    assert not np.allclose(clean, res)  # the disturbances changed the episodes


@pytest.mark.parametrize(
    "args",
    [
        ["--suite", "nope"],
        ["--controller", "missing.npz"],
        ["--suite", "heldout", "--pipes", "101"],
        ["--seconds", "nan"],
    ],
)
def test_cli_benchmark_bad_input(tmp_path, args):
    plot = tmp_path / "b.png"
    res = CliRunner().invoke(main, ["benchmark", *args, "--plot", str(plot)])
    assert res.exit_code == 2, res.output
    assert res.stderr.startswith("pipefollow: error: ") and res.stderr.count("\n") == 1
    assert not plot.exists()


def test_cli_benchmark_refuses_a_plot_format_before_any_episode(tmp_path, monkeypatch):
    import pipefollow.evaluation.benchmark as bm

    def no_episodes(*args, **kwargs):
        raise AssertionError("episodes ran before the --plot check")

    monkeypatch.setattr(bm, "run_episodes", no_episodes)
    plot = tmp_path / "b.xyz"
    res = CliRunner().invoke(main, ["benchmark", "--pipes", "2", "--plot", str(plot)])
    assert res.exit_code == 2, res.output
    assert "--plot" in res.stderr and "xyz" in res.stderr and res.stderr.count("\n") == 1
    assert not plot.exists()


def test_cli_benchmark_plot_in_the_format_its_suffix_names(tmp_path):
    svg = tmp_path / "b.svg"
    res = CliRunner().invoke(main, ["benchmark", "--pipes", "2", "--seconds", "5", "--plot", str(svg)])
    assert res.exit_code == 0, res.output
    assert b"<svg" in svg.read_bytes()[:500]


def test_with_a_sensor_the_reference_is_the_heuristic_through_the_same_sensor_and_the_second_the_ideal():
    from pipefollow.learners.los import LOS
    from pipefollow.perception.water import CLEAR

    suite, sonar = get_suite("heldout-sharp"), {"camera": "ideal", "sensor": "sonar", "water": CLEAR}
    kw = {"seconds": 20.0, "n_pipes": 6}
    run = benchmark(LOS(1.2), suite, controller="los", camera=sonar, **kw)
    h_sonar = benchmark(Heuristic(), suite, controller="heuristic", camera=sonar, **kw)
    h_ideal = benchmark(Heuristic(), suite, controller="heuristic", **kw)
    # each reference is the heuristic's own benchmark with that sensor, on the same pipes and noise
    np.testing.assert_array_equal(run.heuristic_returns, h_sonar.returns)
    np.testing.assert_array_equal(run.ideal_returns, h_ideal.returns)
    assert not np.array_equal(h_sonar.returns, h_ideal.returns)  # the sonar changes the heuristic's episodes
    s = run.summary
    for key, ref in (("vs_heuristic", h_sonar.returns), ("vs_heuristic_ideal", h_ideal.returns)):
        d = run.returns - ref
        assert s[key]["mean_diff"] == pytest.approx(d.mean(), abs=1e-12)
        assert s[key]["win_rate"] == np.mean(d > 0)
    # the heuristic through a sensor: compared with the ideal camera's heuristic only (not with itself)
    assert "vs_heuristic" not in h_sonar.summary
    d = h_sonar.returns - h_ideal.returns
    assert h_sonar.summary["vs_heuristic_ideal"]["mean_diff"] == pytest.approx(d.mean(), abs=1e-12)
    # without a camera there is one reference, the heuristic on the ideal camera
    plain = benchmark(LOS(1.2), suite, controller="los", **kw)
    assert "vs_heuristic_ideal" not in plain.summary
    np.testing.assert_array_equal(plain.heuristic_returns, h_ideal.returns)


class StillOnImages:
    """Acts on the image it is given (checked to be the environment's); a fixed action."""

    def begin_episode(self, sigma):
        pass

    def act(self, obs, explore=False):
        assert obs.shape == (96, 64, 1) and obs.dtype == np.uint8
        return 0.0


def test_a_controller_on_images_is_compared_with_the_heuristic_through_the_same_camera_on_its_vector():
    # the heuristic reads end points, not pixels: its reference keeps the camera and water, not the image
    from pipefollow.perception.water import CLEAR

    suite, kw = get_suite("heldout"), {"seconds": 6.0, "n_pipes": 2}
    pixels = {"camera": "vision", "observation": "image", "water": CLEAR}
    run = benchmark(StillOnImages(), suite, controller="still", camera=pixels, **kw)
    vectors = {"camera": "vision", "water": CLEAR}
    through = benchmark(Heuristic(), suite, controller="heuristic", camera=vectors, **kw)
    np.testing.assert_array_equal(run.heuristic_returns, through.returns)
    assert run.summary["camera"] == "vision" and "vs_heuristic_ideal" in run.summary


def test_a_controller_on_the_ideal_cameras_image_is_compared_with_the_heuristic_on_the_ideal_camera():
    # the image of clear water with the exact camera's in-view decision (examples/ppo_pixels.py's row
    # "ideal"): the heuristic's reference reads the ideal camera's end points, where water does nothing
    from pipefollow.perception.water import CLEAR

    suite, kw = get_suite("heldout"), {"seconds": 6.0, "n_pipes": 2}
    pixels = {"camera": "ideal", "observation": "image", "water": CLEAR}
    run = benchmark(StillOnImages(), suite, controller="still", camera=pixels, **kw)
    ideal = benchmark(Heuristic(), suite, controller="heuristic", **kw)
    np.testing.assert_array_equal(run.heuristic_returns, ideal.returns)
    assert heuristic_camera(pixels) == {"camera": "ideal"}
    assert heuristic_camera({"camera": "ideal", "sensor": "sonar", "water": CLEAR})["water"] == CLEAR


def test_cli_benchmark_with_a_sensor_prints_both_references():
    args = [
        "benchmark",
        "--controller",
        "los",
        "--sensor",
        "sonar",
        "--suite",
        "heldout-sharp",
        "--pipes",
        "3",
    ]
    res = CliRunner().invoke(main, [*args, "--seconds", "20"])
    assert res.exit_code == 0, res.output
    same = [line for line in res.stdout.splitlines() if "through the same sensor" in line]
    ideal = [line for line in res.stdout.splitlines() if "on the ideal camera" in line]
    assert len(same) == 1 and len(ideal) == 1 and same[0].lstrip().startswith("vs heuristic")
