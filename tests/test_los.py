"""Line-of-sight guidance on the visible pipe: hand-computed actions and a run on paper-left."""

import json
import math

import pytest
from click.testing import CliRunner

from pipefollow.cli import main
from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.learners.los import DEFAULT_LOOKAHEAD, LOS, los_action
from pipefollow.training.compiled import run_episode

D = 1.5  # lookahead (m)
QUARTER = math.pi / 2


@pytest.mark.parametrize(
    ("ends", "expected"),
    [
        ((0.0, 3.0, 0.0, 0.0), 0.0),  # straight ahead, on the pipe
        ((0.5, 3.0, 0.5, 0.0), math.atan(0.5 / D) / QUARTER),  # pipe 0.5 m to starboard, parallel
        ((-0.5, 3.0, -0.5, 0.0), -math.atan(0.5 / D) / QUARTER),  # and to port
        ((1.0, math.sqrt(3.0), 0.0, 0.0), 1.0 / 3.0),  # through the AUV at 30° to starboard
        # entering on the port edge at 45°: the line y = x + 2 passes √2 m to port of the AUV
        ((0.0, 2.0, -1.0, 1.0), (math.pi / 4 - math.atan(math.sqrt(2.0) / D)) / QUARTER),
        ((0.5, 0.5, 0.5, 2.0), 1.0),  # running backwards on the starboard side: turn hard to it
        ((0.4, 1.2, 0.4, 1.2), math.atan2(0.4, 1.2) / QUARTER),  # a single point: head for it
    ],
)
def test_los_action_by_hand(ends, expected):
    assert los_action(*ends, D) == pytest.approx(expected, abs=1e-12)


def test_los_saturates_and_the_agent_assumes_y_near_zero():
    assert los_action(-1.0, 0.2, -1.0, 0.0, 0.1) == pytest.approx(-math.atan(10.0) / QUARTER)
    assert los_action(1.0, 0.0, 1.0, 3.0, D) == 1.0  # pipe running back on the starboard side
    agent = LOS(D)
    assert agent.act([0.3, 2.5, -0.2, 0.4]) == los_action(0.3, 2.5, -0.2, 0.0, D)
    assert LOS().lookahead == DEFAULT_LOOKAHEAD
    with pytest.raises(ValueError, match="lookahead"):
        LOS(0.0)


def test_los_follows_paper_left():
    ep = run_episode(PipelineFollowingEnv("paper-left", 20), LOS(), seed=0)
    assert ep.pipe_in_view == 1.0
    assert ep.progress_m > 4.4
    assert ep.ret == pytest.approx(-10.33, abs=0.01)  # measured; the heuristic gets −10.22


def test_cli_evaluate_los():
    runner = CliRunner()
    res = runner.invoke(main, ["evaluate", "--controller", "los", "--lookahead", "1.5", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["controller"] == "los"
    assert out["mean_return"] == pytest.approx(-10.33, abs=0.01)
    for args in (
        ["--controller", "heuristic", "--lookahead", "2"],
        ["--controller", "los", "--lookahead", "0"],
    ):
        res = runner.invoke(main, ["evaluate", *args])
        assert res.exit_code == 2
        assert "--lookahead" in res.stderr and len(res.stderr.strip().splitlines()) == 1


def test_los_runs_inside_compiled_loops():
    import numpy as np
    from numba import njit

    from pipefollow.sim import decision as sim
    from pipefollow.sim.pipeline import builtin

    @njit
    def episode(s, points, cum, p, n, lookahead):
        total = 0.0
        for _ in range(n):
            a = los_action(s[sim.X1], s[sim.Y1], s[sim.X2], 0.0, lookahead) if s[sim.IN_VIEW] else 0.0
            total += sim.decide(s, a, points, cum, p)
        return total

    pipe = builtin("paper-left")
    s = np.zeros(sim.STATE_SIZE)
    sim.init_state(s, pipe.points, pipe.cumulative, 0.0, 0.0, pipe.start_heading, sim.PAPER_SIM)
    total = episode(s, pipe.points, pipe.cumulative, sim.PAPER_SIM, 20, DEFAULT_LOOKAHEAD)
    env_path = run_episode(PipelineFollowingEnv("paper-left", 20), LOS(), seed=0).ret
    assert total == pytest.approx(env_path, abs=1e-12)
