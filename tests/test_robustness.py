"""Robustness: fixed scenario sets, curves against current speed, and ``pipefollow robustness``."""

import csv
import json
import math
import shlex

import numpy as np
import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.evaluation import robustness as rb
from pipefollow.evaluation.benchmark import run_episodes
from pipefollow.learners.heuristic import Heuristic
from pipefollow.learners.los import LOS
from pipefollow.sim.disturbance import NO_DISTURBANCE, Disturbance, DisturbanceError, check
from pipefollow.sim.episode import STAT_BACK, STAT_IN_VIEW, STAT_NAMES, STAT_PROGRESS, STAT_RETURN, STAT_SWUM
from pipefollow.sim.pipeline import Pipeline
from pipefollow.sim.suites import get_suite, min_length_for
from pipefollow.training.compiled import run_episode

HELDOUT = get_suite("heldout")

# ---------------------------------------------------------------------------------------------
# Scenario sets: fixed, seeded, valid


@pytest.mark.parametrize("name", list(rb.SCENARIO_SETS))
def test_scenario_sets_are_fixed_valid_and_prefix_stable(name):
    def key(cases):
        return [(c.pipe.name, c.disturbance, c.noise_seed) for c in cases]

    a = key(rb.scenarios(name, HELDOUT, 12))
    assert a[:5] == key(rb.scenarios(name, HELDOUT, 5))  # pipe k's scenario does not depend on the count
    assert a == key(rb.scenarios(name, HELDOUT, 12))
    assert len({seed for _, _, seed in a}) == len(a)
    for c in rb.scenarios(name, HELDOUT, 12):
        check(c.disturbance)


def test_scenario_sets_hold_what_they_name():
    assert all(c.disturbance == NO_DISTURBANCE for c in rb.scenarios("calm", HELDOUT))
    current = rb.scenarios("current", HELDOUT)
    speeds = np.array([c.disturbance.current_speed for c in current])
    directions = np.degrees([c.disturbance.current_direction for c in current]) % 360.0
    assert speeds.min() >= 0.05 and speeds.max() <= 0.25
    assert np.histogram(directions, bins=4, range=(0, 360))[0].min() >= 15  # every quarter, 100 pipes
    buried = rb.scenarios("buried", HELDOUT)
    assert all(math.isfinite(c.disturbance.buried_from[1]) for c in buried)  # two stretches each
    sea = [c.disturbance for c in rb.scenarios("sea", HELDOUT)]
    assert all(d.current_time_constant == 30.0 and d.current_speed >= 0.05 for d in sea)


def test_the_curve_holds_each_pipes_direction_across_speeds():
    slow, fast = rb.curve_scenarios(0.05, HELDOUT, 8), rb.curve_scenarios(0.3, HELDOUT, 8)
    assert [c.disturbance.current_direction for c in slow] == [c.disturbance.current_direction for c in fast]
    assert {c.disturbance.current_speed for c in fast} == {0.3}
    assert all(c.disturbance == NO_DISTURBANCE for c in rb.curve_scenarios(0.0, HELDOUT, 8))


@pytest.mark.parametrize("bad", [-0.1, math.nan, math.inf, 2.5, "0.1"])
def test_a_bad_speed_is_refused(bad):
    with pytest.raises(DisturbanceError, match="current speed"):
        rb.curve_scenarios(bad, HELDOUT, 2)


def test_unknown_scenario_set_lists_the_sets():
    with pytest.raises(DisturbanceError, match="choose from calm, current, noise, misses, buried, sea"):
        rb.scenarios("storm", HELDOUT)


# ---------------------------------------------------------------------------------------------
# Running: the same numbers as the benchmark and the environment; the physics shows through


def test_calm_curve_point_is_the_benchmark():
    pipes = HELDOUT.pipes(6, min_length_for(60.0))
    expected = run_episodes(Heuristic(), pipes, 60.0)[0]
    got = rb.run_scenarios(Heuristic(), rb.curve_scenarios(0.0, HELDOUT, 6), 60.0)
    np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("name", ["current", "sea"])
def test_scenarios_equal_episodes_through_the_environment(name):
    cases = rb.scenarios(name, HELDOUT, 3, seconds=30.0)
    got = rb.run_scenarios(LOS(), cases, 30.0)
    for row, c in zip(got, cases, strict=True):
        env = PipelineFollowingEnv(c.pipe, 30.0, disturbance=c.disturbance)
        env.np_random = np.random.default_rng(np.random.SeedSequence([c.noise_seed, 0]))
        ep = run_episode(env, LOS())
        assert row[STAT_RETURN] == pytest.approx(ep.ret, abs=1e-9)
        assert row[STAT_IN_VIEW] == pytest.approx(ep.pipe_in_view)


def test_a_current_along_a_straight_pipe_carries_the_auv_but_less_than_its_speed():
    # eq. 16 drags on the speed through the water, the PD law damps the speed over ground: at steady
    # state a following current adds a part of V_c to the speed over ground, an opposing one takes
    # about as much away (the damping is close to linear at these speeds)
    pipe = Pipeline(np.array([[0.0, 0.0], [60.0, 0.0]]), "straight")
    v, seconds = 0.1, 40.0
    cases = [rb.Scenario(pipe, Disturbance(current_speed=s, current_direction=d), 0) for s, d in
             ((0.0, 0.0), (v, 0.0), (v, math.pi))]  # fmt: skip
    calm, following, opposing = rb.run_scenarios(Heuristic(), cases, seconds)[:, STAT_PROGRESS]
    gain, loss = following - calm, calm - opposing
    assert 0.2 * v * seconds < gain < v * seconds
    assert loss == pytest.approx(gain, rel=0.15)


# ---------------------------------------------------------------------------------------------
# Summaries


def test_summarize_by_hand():
    def rows(returns, in_view):
        out = np.zeros((len(returns), len(STAT_NAMES)))
        out[:, STAT_RETURN], out[:, STAT_IN_VIEW] = returns, in_view
        out[:, STAT_PROGRESS] = out[:, STAT_SWUM] = 20.0  # every metre covered along the pipe
        return out

    a = rows([1.0, 3.0, -5.0], [1.0, 0.96, 0.5])
    b = rows([3.0, 5.0, -1.0], [1.0, 0.9, 1.0])
    b[2, STAT_PROGRESS], b[2, STAT_BACK] = 4.0, 8.0  # in view, but 4 m of 20 m forward: it turned back
    h = rows([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    r = rb.summarize("x", [a, b], h, lengths=[50.0, 50.0, 50.0])
    # per pipe, the mean over the two policies: 2, 4, −3; mean 1
    assert r["mean_return"] == pytest.approx(1.0)
    assert r["seed_returns"] == [pytest.approx(-1 / 3), pytest.approx(7 / 3)]
    assert r["in_view_rate"] == pytest.approx(4 / 6)  # 0.9 and 0.5 miss the 95 %
    assert r["success_rate"] == pytest.approx(3 / 6)  # and b's third did not follow the pipe forward
    assert r["mean_progress_share"] == pytest.approx((5 + 4 / 20) / 6)
    assert r["turned_back"] == 1
    assert r["vs_heuristic"] == pytest.approx(1.0)
    assert r["ci95_low"] < 1.0 < r["ci95_high"]
    assert (r["policies"], r["episodes"]) == (2, 6)


def test_the_curve_is_a_row_per_controller_and_speed_with_the_heuristic_first():
    ctrl = {"los": [LOS()], "same": [Heuristic(), Heuristic()]}
    rows = rb.robustness_curve(ctrl, HELDOUT, speeds=(0.0, 0.2), n_pipes=4, seconds=20.0)
    assert [(r["current_speed"], r["controller"]) for r in rows] == [
        (0.0, "heuristic"), (0.0, "los"), (0.0, "same"), (0.2, "heuristic"), (0.2, "los"), (0.2, "same"),
    ]  # fmt: skip
    for k in (0, 3):  # two copies of the heuristic are the heuristic, with a difference of 0
        assert rows[k + 2]["mean_return"] == rows[k]["mean_return"]
        assert rows[k + 2]["vs_heuristic"] == 0.0


# ---------------------------------------------------------------------------------------------
# The command


def test_cli_writes_the_tables_and_the_figure(tmp_path):
    out = tmp_path / "rob"
    args = [
        "robustness",
        "--pipes",
        "4",
        "--seconds",
        "20",
        "--speeds",
        "0,0.2",
        "--scenarios",
        "calm,misses",
        "--controller",
        "los",
        "--controller",
        "h2=heuristic",
        "--out",
        str(out),
    ]
    args.append("--json")
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    result = json.loads(res.stdout)
    assert sorted(p.name for p in out.iterdir()) == sorted(["curve.csv", "scenarios.csv", "robustness.json",
                                                            "robustness.png", "provenance.json"])  # fmt: skip
    record = json.loads((out / "provenance.json").read_text())
    assert record["command"] == shlex.join(["pipefollow", *args]) and record["code"]["sources"]
    with open(out / "curve.csv") as f:
        curve = list(csv.DictReader(f))
    assert [(r["current_speed"], r["controller"]) for r in curve] == [
        (v, c) for v in ("0.0", "0.2") for c in ("heuristic", "los", "h2")
    ]
    # the calm point is the benchmark's number for the same pipes
    bench = run_episodes(Heuristic(), HELDOUT.pipes(4, min_length_for(20.0)), 20.0)[0]
    assert float(curve[0]["mean_return"]) == pytest.approx(bench[:, STAT_RETURN].mean(), rel=1e-6)
    assert [r["scenarios"] for r in result["scenarios"]] == ["calm"] * 3 + ["misses"] * 3
    assert (out / "robustness.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--speeds", "0,-0.1"], "current speed"),
        (["--speeds", "0,fast"], "--speeds"),
        (["--scenarios", "calm,storm"], "scenario set 'storm'"),
        (["--controller", "nothing.npz"], "nothing.npz"),
        (["--controller", "=heuristic"], "LABEL=SPEC"),
        (["--suite", "heldout", "--pipes", "101"], "--pipes 101"),
    ],
)
def test_cli_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, args, message):
    out = tmp_path / "rob"
    res = CliRunner().invoke(main, ["robustness", "--pipes", "2", *args, "--out", str(out)])
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pipefollow: error: ") and message in lines[0]
    assert not out.exists()
