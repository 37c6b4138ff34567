"""Disturbances and faults: ocean current, camera noise, missed detections, buried stretches."""

import json
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy import stats
from scipy.integrate import solve_ivp

from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim import decision as sim
from pipefollow.sim.camera import observe
from pipefollow.sim.controller import ControllerParams, pd_force
from pipefollow.sim.disturbance import (
    NO_DISTURBANCE,
    Disturbance,
    DisturbanceError,
    check,
    disturbance_from_dict,
    make_disturbance,
    noise_count,
    to_dict,
    vary_current,
)
from pipefollow.sim.dynamics import PAPER_AUV, coriolis_matrix, damping_matrix, mass_matrix
from pipefollow.sim.pipeline import Pipeline, builtin
from pipefollow.training.agents import make_agent
from pipefollow.training.compiled import run_episode, train_compiled

# ---------------------------------------------------------------------------------------------
# Off by default: the numbers of the code before disturbances existed, bit for bit

# computed with the code before this module existed (heuristic, 60 s, seed 0); the simulator's
# arithmetic has a fixed order (no fastmath, no BLAS), so these bits hold on every CPU target
BEFORE = {
    "paper-left": "-0x1.01120bd512efcp+6",
    "paper-validation": "-0x1.16440a7152f05p+6",
}
ZERO = Disturbance(current_speed=0.0, current_direction=1.3)  # a direction, but no speed


@pytest.mark.parametrize("pipeline", ["paper-left", "paper-validation"])
@pytest.mark.parametrize("disturbance", [None, ZERO])
def test_no_disturbance_reproduces_the_earlier_numbers(pipeline, disturbance):
    # pinned before episodes ended at the pipe's end (60 s reach past paper-left's): the paper's protocol
    paper = sim.PAPER_SIM._replace(end_at_pipe_end=False)
    env = PipelineFollowingEnv(pipeline, 60, params=paper, disturbance=disturbance)
    ep = run_episode(env, Heuristic(), seed=0)
    assert ep.ret == float.fromhex(BEFORE[pipeline])


def _trained_weights(params):
    agent = make_agent("cacla", supervised=True, skew_deg=22.5, rng=np.random.default_rng(5))
    train_compiled(agent, builtin("paper-left"), 30, chunk=10, params=params)
    return agent.weights


def test_a_current_of_zero_speed_trains_as_no_disturbance():
    # a direction with no speed must leave every number of a learning run as it is
    plain = _trained_weights(sim.PAPER_SIM)
    zero = _trained_weights(sim.PAPER_SIM._replace(disturbance=ZERO))
    assert np.array_equal(plain, zero)
    # and the run is not trivially equal: a current that flows changes it
    flowing = _trained_weights(
        sim.PAPER_SIM._replace(disturbance=Disturbance(current_speed=0.1, current_direction=1.3))
    )
    assert not np.array_equal(plain, flowing)


# ---------------------------------------------------------------------------------------------
# Ocean current

NO_THRUST = sim.PAPER_SIM._replace(controller=ControllerParams(0.0, 0.0, 0.0, 0.0, 0.0, 0.0))
STRAIGHT = Pipeline(np.array([[0.0, 0.0], [100.0, 0.0]]), "straight")


@pytest.mark.parametrize("psi_deg", [0.0, 37.0, 90.0, -140.0])
def test_current_alone_drifts_the_auv_with_the_water(psi_deg):
    # no thrust (all gains 0), at rest in the water: the AUV moves exactly with the current
    speed, beta = 0.3, math.radians(60.0)
    p = NO_THRUST._replace(disturbance=Disturbance(speed, beta))
    psi = math.radians(psi_deg)
    s = np.zeros(sim.STATE_SIZE)
    sim.init_state(s, STRAIGHT.points, STRAIGHT.cumulative, 10.0, 0.5, psi, p)
    for _ in range(5):
        sim.decide(s, 0.0, STRAIGHT.points, STRAIGHT.cumulative, p)
    t = 5.0
    assert_allclose(
        [s[sim.X], s[sim.Y]], [10.0 + speed * math.cos(beta) * t, 0.5 + speed * math.sin(beta) * t]
    )
    assert s[sim.PSI] == pytest.approx(psi, abs=1e-15)
    assert (s[sim.U], s[sim.V], s[sim.R]) == (0.0, 0.0, 0.0)  # ν_r stays 0
    # v_x is the surge speed over ground: the current's component along the heading
    assert s[sim.VX] == pytest.approx(speed * math.cos(beta - psi), abs=1e-15)


def test_current_model_equals_fossens_rigid_body_form():
    # Fossen (2021, §10.3): M_RB ν̇ + C_RB(ν)ν + M_A ν̇_r + C_A(ν_r)ν_r + D(ν_r)ν_r = τ, integrated
    # in ν (over ground) with ν_c = R(ψ)ᵀ v_c, must give the simulator's trajectory, which
    # integrates the lumped eq. 16 in ν_r.
    vn, ve = 0.15, -0.2
    wp = (2.0, 2.5)
    m, iz = PAPER_AUV.mass, PAPER_AUV.inertia
    m_rb = np.diag([m, m, iz])
    m_a = mass_matrix() - m_rb

    def c_rb(nu):
        u, v, r = nu
        return np.array([-m * r * v, m * r * u, 0.0])

    def rhs(_, y):
        x, yy, psi, u, v, r = y
        c, sn = math.cos(psi), math.sin(psi)
        nu = np.array([u, v, r])
        nu_c = np.array([c * vn + sn * ve, -sn * vn + c * ve, 0.0])
        nu_r = nu - nu_c
        nu_c_dot = np.array([r * nu_c[1], -r * nu_c[0], 0.0])  # constant in the earth frame
        tau = np.array(pd_force(x, yy, psi, u, v, r, wp[0], wp[1], 0.0, True, sim.PAPER_SIM.controller))
        c_a = coriolis_matrix(nu_r) @ nu_r - c_rb(nu_r)
        rest = tau - c_rb(nu) - c_a - damping_matrix(nu_r) @ nu_r + m_a @ nu_c_dot
        nu_dot = np.linalg.solve(m_rb + m_a, rest)
        return [c * u - sn * v, sn * u + c * v, r, *nu_dot]

    start_nu_r = np.array([0.2, -0.03, 0.04])
    psi0 = 0.3
    c0, s0 = math.cos(psi0), math.sin(psi0)
    nu0 = start_nu_r + [c0 * vn + s0 * ve, -s0 * vn + c0 * ve, 0.0]
    ref = solve_ivp(rhs, (0.0, 3.0), [0.0, 0.0, psi0, *nu0], rtol=1e-11, atol=1e-12).y[:, -1]

    p = sim.PAPER_SIM._replace(disturbance=Disturbance(math.hypot(vn, ve), math.atan2(ve, vn)))
    s = np.zeros(sim.STATE_SIZE)
    s[sim.PSI] = psi0
    s[sim.U], s[sim.V], s[sim.R] = start_nu_r
    for _ in range(300):
        sim.closed_loop_rk4(s, wp[0], wp[1], 0.0, True, 0.01, p, vn, ve)
    c, sn = math.cos(s[sim.PSI]), math.sin(s[sim.PSI])
    nu_c = [c * vn + sn * ve, -sn * vn + c * ve, 0.0]
    assert_allclose(s[[sim.X, sim.Y, sim.PSI]], ref[:3], atol=1e-8)
    assert_allclose(s[[sim.U, sim.V, sim.R]] + nu_c, ref[3:], atol=1e-8)


def test_varying_current_is_gauss_markov():
    d = make_disturbance(
        0.1, 90.0, current_time_constant=10.0, current_speed_sd=0.05, current_direction_sd_deg=20
    )
    phi = math.exp(-0.1)
    speed, direction = vary_current(0.3, 0.0, d, 1.0, 0.0, 0.0)  # no noise: decays to the mean
    assert speed == pytest.approx(0.1 + phi * 0.2)
    assert direction == pytest.approx(math.pi / 2 * (1 - phi))
    speed, _ = vary_current(0.1, 0.0, d, 1.0, 1.0, 0.0)
    assert speed == pytest.approx(0.1 + 0.05 * math.sqrt(1 - phi * phi))
    assert vary_current(0.0, 0.0, d, 1.0, -50.0, 0.0)[0] == 0.0  # never negative
    # stationary spread: over a long run the speed's s.d. approaches 0.05
    rng = np.random.default_rng(0)
    v, b, speeds = 0.1, d.current_direction, []
    for z in rng.standard_normal((20_000, 2)):
        v, b = vary_current(v, b, d, 1.0, z[0], z[1])
        speeds.append(v)
    assert np.std(speeds) == pytest.approx(0.05, rel=0.1)


# ---------------------------------------------------------------------------------------------
# Camera faults

SHORT = Pipeline(np.array([[1.0, 0.3], [2.0, 0.5]]), "inside")  # wholly inside the footprint


def reading(p, z, pipe=SHORT, pose=(0.0, 0.0, 0.0)):
    s = np.zeros(sim.STATE_SIZE)
    sim.init_state(s, pipe.points, pipe.cumulative, *pose, p, z)
    return s


def test_camera_noise_has_the_requested_sd():
    sd = 0.05
    p = sim.PAPER_SIM._replace(disturbance=Disturbance(camera_noise=sd))
    assert noise_count(p.disturbance) == 4
    exact = reading(sim.PAPER_SIM, None)[[sim.X1, sim.Y1, sim.X2, sim.Y_NEAR]]
    assert_allclose(exact, [0.5, 2.0, 0.3, 1.0], atol=1e-12)
    rng = np.random.default_rng(7)
    n = 2000
    samples = np.array(
        [reading(p, rng.standard_normal(4))[[sim.X1, sim.Y1, sim.X2, sim.Y_NEAR]] for _ in range(n)]
    )
    err = samples - exact
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n - 1)
    for k in range(4):
        assert lo < (n - 1) * err[:, k].var(ddof=1) / sd**2 < hi
        assert abs(err[:, k].mean()) < 4 * sd / math.sqrt(n)


def test_camera_noise_is_clamped_to_the_footprint():
    p = sim.PAPER_SIM._replace(disturbance=Disturbance(camera_noise=1.0))
    s = reading(p, np.array([10.0, 10.0, -10.0, -10.0]))
    assert (s[sim.X1], s[sim.Y1], s[sim.X2], s[sim.Y_NEAR]) == (1.0, 3.0, -1.0, 0.0)


def test_missed_detections_have_the_requested_probability():
    p = sim.PAPER_SIM._replace(disturbance=Disturbance(miss_prob=0.3))
    rng = np.random.default_rng(3)
    n = 2000
    misses = sum(reading(p, rng.standard_normal(1))[sim.MISSED] for _ in range(n))
    assert stats.binomtest(int(misses), n, 0.3).pvalue > 0.001
    always = sim.PAPER_SIM._replace(disturbance=Disturbance(miss_prob=1.0))
    assert reading(always, np.array([40.0]))[sim.IN_VIEW] == 0.0


def test_a_missed_detection_triggers_the_search_and_its_penalty():
    pipe = builtin("paper-left")
    pts, cum = pipe.points, pipe.cumulative
    p = sim.PAPER_SIM._replace(disturbance=Disturbance(miss_prob=0.5))
    see, miss = np.array([3.0]), np.array([-3.0])  # Φ(3) > 0.5 > Φ(−3)
    s = np.zeros(sim.STATE_SIZE)
    sim.init_state(s, pts, cum, 0.0, 0.0, pipe.start_heading, p, see)
    clean = s.copy()
    sim.init_state(clean, pts, cum, 0.0, 0.0, pipe.start_heading, sim.PAPER_SIM)
    r1 = sim.decide(s, 0.1, pts, cum, p, see)
    assert r1 == sim.decide(clean, 0.1, pts, cum, sim.PAPER_SIM)
    held = s[[sim.X1, sim.Y1, sim.X2]].copy()
    r2 = sim.decide(s, 0.1, pts, cum, p, miss)  # the camera misses the pipe at this decision's end
    assert r2 == -10.0 and s[sim.IN_VIEW] == 0.0 and s[sim.MISSED] == 1.0
    assert_allclose(s[[sim.X1, sim.Y1, sim.X2]], held)  # the last sighting is held
    x, y, psi = s[sim.X], s[sim.Y], s[sim.PSI]
    r3 = sim.decide(s, 0.1, pts, cum, p, see)  # the search flies this decision
    assert r3 == -10.0 and s[sim.OVERRIDDEN] == 1.0
    assert (s[sim.WP_X], s[sim.WP_Y]) == (x, y)  # held on the spot, turning
    side = 1.0 if held[0] >= 0.0 else -1.0
    assert s[sim.A_PREV] == side
    assert s[sim.PSI] - psi == pytest.approx(side * abs(s[sim.PSI] - psi))
    assert s[sim.IN_VIEW] == 1.0  # seen again


def test_env_miss_prob_one_loses_the_pipe_every_decision():
    env = PipelineFollowingEnv("paper-left", 5, disturbance={"miss_prob": 1.0})
    assert env.params.disturbance == Disturbance(miss_prob=1.0)
    _, info = env.reset(seed=0)
    assert not info["pipe_in_view"] and info["camera_missed"]
    for _ in range(5):
        _, r, _, _, info = env.step([0.0])
        assert r == -10.0 and info["overridden"]


NORTH = [[0.0, 0.0], [20.0, 0.0]]  # a straight pipe north from the origin


@pytest.mark.parametrize(
    ("buried", "seen", "expected"),
    [
        # AUV at 5 m heading north sees s ∈ [5, 8]; camera y = s − 5
        ([], True, (0.0, 3.0, 0.0, 0.0, 5.0, 8.0)),
        ([(6.0, 7.0)], True, (0.0, 1.0, 0.0, 0.0, 5.0, 6.0)),  # split: the piece at the progress
        ([(4.0, 6.5)], True, (0.0, 3.0, 0.0, 1.5, 6.5, 8.0)),  # the start is buried
        ([(1.0, 2.0), (6.0, 9.0)], True, (0.0, 1.0, 0.0, 0.0, 5.0, 6.0)),
        ([(4.0, 9.0)], False, (0.0,) * 6),  # all of the footprint's part
        ([(5.0, 8.0)], False, (0.0,) * 6),  # exactly the part in view
    ],
)
def test_buried_stretches_are_hidden_exactly(buried, seen, expected):
    pipe = Pipeline(np.array(NORTH))
    d = make_disturbance(buried=[list(b) for b in buried])
    got = observe(
        pipe.points, pipe.cumulative, 5.0, 0.0, 0.0, 5.0, sim.PAPER_SIM.camera, d.buried_from, d.buried_to
    )
    assert got[0] is seen
    assert_allclose(got[1:], expected, atol=1e-12)


def test_buried_stretch_splits_a_piece_across_a_corner():
    # L-shaped pipe: north 6 m, then east; the AUV at (4, 0) heading north sees both legs
    pipe = Pipeline(np.array([[0.0, 0.0], [6.0, 0.0], [6.0, 5.0]]))
    d = make_disturbance(buried=[[5.5, 6.5]])  # around the corner at s = 6
    seen, x1, y1, x2, y_near, s_near, s_far = observe(
        pipe.points, pipe.cumulative, 4.0, 0.0, 0.0, 4.0, sim.PAPER_SIM.camera, d.buried_from, d.buried_to
    )
    assert seen
    assert_allclose([x1, y1, x2, y_near, s_near, s_far], [0.0, 1.5, 0.0, 0.0, 4.0, 5.5], atol=1e-12)
    # progress past the corner: the second piece (east leg from 0.5 m to the edge at 1 m)
    seen, x1, y1, x2, y_near, s_near, s_far = observe(
        pipe.points, pipe.cumulative, 4.0, 0.0, 0.0, 7.0, sim.PAPER_SIM.camera, d.buried_from, d.buried_to
    )
    assert_allclose([x1, y1, x2, y_near, s_near, s_far], [1.0, 2.0, 0.5, 2.0, 6.5, 7.0], atol=1e-12)


# ---------------------------------------------------------------------------------------------
# Construction and checks


def test_make_disturbance_units_and_round_trip():
    d = make_disturbance(0.1, 90.0, camera_noise=0.05, miss_prob=0.02, buried=[[6.0, 7.5]])
    assert d.current_direction == pytest.approx(math.pi / 2)
    assert d.buried_from == (6.0, math.inf, math.inf, math.inf)
    assert disturbance_from_dict(to_dict(d)) == d
    assert check(d) is d
    assert to_dict(NO_DISTURBANCE)["buried"] == []


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ({"current_speed": -0.1}, "current_speed must be ≥ 0"),
        ({"current_speed": float("nan")}, "current_speed must be a finite number"),
        ({"current_speed": "fast"}, "current_speed must be a number"),
        ({"miss_prob": 1.5}, "miss_prob must be a probability"),
        ({"camera_noise": -0.01}, "camera_noise must be ≥ 0"),
        ({"current_speed_sd": 0.1}, "needs current_time_constant > 0"),
        ({"buried": [[3.0, 2.0]]}, r"buried\[0\] must have from < to"),
        ({"buried": [[1.0, 3.0], [2.0, 4.0]]}, "sorted and must not overlap"),
        ({"buried": [[0, 1]] * 5}, "at most 4"),
        ({"wind": 3}, "unknown key 'wind'"),
    ],
)
def test_disturbance_from_dict_rejects_bad_values(table, message):
    with pytest.raises(DisturbanceError, match=f"scenario: .*{message}"):
        disturbance_from_dict(table, "scenario")


def test_env_refuses_a_bad_record_and_compiled_training_needs_a_generator():
    with pytest.raises(DisturbanceError, match="miss_prob"):
        PipelineFollowingEnv(disturbance=Disturbance(miss_prob=2.0))
    agent = make_agent("cacla", rng=np.random.default_rng(0))
    params = sim.PAPER_SIM._replace(disturbance=Disturbance(camera_noise=0.1))
    with pytest.raises(ValueError, match="env_rng"):
        train_compiled(agent, builtin("paper-left"), 1, params=params)


# ---------------------------------------------------------------------------------------------
# Command line


def test_cli_evaluate_with_disturbances_is_seeded():
    from click.testing import CliRunner

    from pipefollow.cli import main

    runner = CliRunner()
    args = ["evaluate", "--current", "0.1,90", "--camera-noise", "0.05", "--miss-prob", "0.1", "--json"]
    first = json.loads(runner.invoke(main, args).stdout)
    again = json.loads(runner.invoke(main, args).stdout)
    plain = json.loads(runner.invoke(main, ["evaluate", "--json"]).stdout)
    assert first == again
    assert first["mean_return"] != plain["mean_return"]
    assert first["disturbance"]["current_direction_deg"] == pytest.approx(90.0)
    assert "disturbance" not in plain


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("--current", "-0.1,0"),
        ("--current", "nan,0"),
        ("--current", "0.1"),
        ("--current", "0.1;40"),
        ("--camera-noise", "-0.01"),
        ("--camera-noise", "inf"),
        ("--miss-prob", "1.01"),
        ("--miss-prob", "-0.5"),
    ],
)
@pytest.mark.parametrize("command", ["evaluate", "train"])
def test_cli_rejects_bad_disturbances(tmp_path, command, option, value):
    from click.testing import CliRunner

    from pipefollow.cli import main

    out = tmp_path / "out"
    extra = ["--algorithm", "cacla", "--episodes", "1", "--out", str(out)] if command == "train" else []
    res = CliRunner().invoke(main, [command, *extra, f"{option}={value}"])
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and option in lines[0]
    assert not out.exists()


def test_cli_train_with_disturbances(tmp_path):
    from click.testing import CliRunner

    from pipefollow.cli import main

    args = ["train", "--algorithm", "cacla", "--episodes", "5", "--current", "0.1,45", "--camera-noise"]
    res = [CliRunner().invoke(main, [*args, "0.05", "--out", str(tmp_path / k), "--json"]) for k in "ab"]
    assert res[0].exit_code == 0, res[0].output
    first, again = (json.loads(r.stdout) for r in res)
    assert first["returns"] == again["returns"]  # seeded
    assert first["disturbance"]["camera_noise"] == 0.05


def test_the_documented_toml_table_reads():
    import tomllib

    import pipefollow.sim.disturbance as mod

    doc = mod.disturbance_from_dict.__doc__
    table = doc[doc.index("[disturbance]") : doc.index("Raises:")]
    text = "\n".join(line.strip() for line in table.splitlines())
    d = disturbance_from_dict(tomllib.loads(text)["disturbance"], "example")
    assert d == make_disturbance(0.1, 90.0, camera_noise=0.05, miss_prob=0.02, buried=[[6.0, 7.5]])
