"""Success as an inspector counts it (pipefollow.evaluation.success): by hand, and an AUV that turns back."""

import math

import numpy as np
import pytest

from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.evaluation import success as sc
from pipefollow.learners.heuristic import heuristic_action
from pipefollow.sim import episode as ep
from pipefollow.sim.pipeline import Pipeline


def row(in_view=1.0, progress=10.0, swum=12.0, back=0.0):
    out = np.zeros(len(ep.STAT_NAMES))
    out[ep.STAT_IN_VIEW], out[ep.STAT_PROGRESS] = in_view, progress
    out[ep.STAT_SWUM], out[ep.STAT_BACK] = swum, back
    return out


def test_the_definitions_on_hand_computed_statistics():
    cases = [  # (row, pipe length): progress share, reached the end, turned back, success
        ((row(), 50.0), 10 / 12, False, False, True),
        ((row(in_view=0.94), 50.0), 10 / 12, False, False, False),  # the pipe lost too often
        ((row(progress=5.0), 50.0), 5 / 12, False, False, False),  # less than half of 12 m forward
        ((row(progress=6.0), 50.0), 0.5, False, False, True),  # exactly half
        ((row(progress=6.0, swum=30.0), 10.0), 0.6, False, False, True),  # reachable capped by the length
        ((row(progress=7.5, swum=30.0), 8.0), 1.0, True, False, True),  # 0.5 m short of the end: reached
        ((row(progress=7.49, swum=30.0), 8.0), 7.49 / 8.0, False, False, True),
        ((row(progress=0.0, swum=0.0), 50.0), 1.0, False, False, True),  # nothing covered
        ((row(back=3.0), 50.0), 10 / 12, False, True, False),  # followed the pipe backwards 3 m
        ((row(back=2.99), 50.0), 10 / 12, False, False, True),
    ]
    for (r, length), share, end, back, ok in cases:
        fields = sc.episode_fields(r, length)
        assert fields["progress_share"] == pytest.approx(share, rel=1e-12), (r, length)
        assert (fields["reached_end"], fields["turned_back"], fields["success"]) == (end, back, ok), r
    rows = np.array([c[0][0] for c in cases])
    lengths = np.array([c[0][1] for c in cases])
    s = sc.summary(rows, lengths)
    assert s["success_rate"] == pytest.approx(7 / 10) and s["in_view_rate"] == pytest.approx(9 / 10)
    assert (s["reached_end"], s["turned_back"]) == (1, 1)
    assert s["mean_progress_share"] == pytest.approx(np.mean([c[1] for c in cases]))
    # several runs on the same pipes: the rows one after the other, the lengths repeated
    lost = rows.copy()
    lost[:, ep.STAT_IN_VIEW] = 0.0  # a second run that never keeps the pipe in view
    assert sc.summary_of_runs([rows, lost], lengths)["success_rate"] == pytest.approx(7 / 20)


def test_following_the_pipe_backwards_is_not_a_success():
    # 20 s of the heuristic along a straight pipe, a hard turn, then a controller that aims at the
    # near end of the pipe in view (y_near) instead of the far one: it follows the pipe back
    pipe = Pipeline(np.array([[0.0, 0.0], [60.0, 0.0]]), "straight")
    env = PipelineFollowingEnv(pipe, 60)
    obs, info = env.reset(seed=0)
    for t in range(60):
        if t < 20:
            a = heuristic_action(obs[0], obs[1])
        elif t < 23:
            a = 1.0
        else:
            a = math.atan2(obs[2], float(info["y_near"])) / (math.pi / 2)
        obs, _, terminated, truncated, info = env.step([a])
    assert truncated and not terminated
    stats = ep.statistics_row(env.book, float(info["progress_m"]), 1.0)
    assert stats[ep.STAT_IN_VIEW] >= 0.95  # the pipe in view all along: a success by the view alone
    assert stats[ep.STAT_BACK] > 5.0  # metres followed backwards, in view
    fields = sc.episode_fields(stats, pipe.length)
    assert fields["turned_back"] and not fields["success"]
    assert sc.in_view(stats)[0]
