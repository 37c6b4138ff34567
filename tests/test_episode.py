"""The episode protocol (pipefollow.sim.episode): its layouts and its bookkeeping, by hand."""

import numpy as np
import pytest

from pipefollow.sim import decision as sim
from pipefollow.sim import episode as ep
from pipefollow.sim.pipeline import builtin


def test_every_column_and_slot_is_the_position_of_its_name():
    names = ("return", "pipe_in_view", "progress_m", "time_lost_s", "sum_e_dist2", "n_in_view", "swum_m",
             "back_m")  # fmt: skip
    assert ep.STAT_NAMES == names
    columns = (ep.STAT_RETURN, ep.STAT_IN_VIEW, ep.STAT_PROGRESS, ep.STAT_TIME_LOST, ep.STAT_SUM_E2,
               ep.STAT_N_SEEN, ep.STAT_SWUM, ep.STAT_BACK)  # fmt: skip
    assert [ep.STAT_NAMES[c] for c in columns] == list(ep.STAT_NAMES)
    # a training run's columns (its CSV) are the leading ones
    assert ep.TRAINING_STAT_NAMES == ("return", "pipe_in_view", "progress_m", "time_lost_s")
    slots = (ep.DECISIONS, ep.TOTAL, ep.SEEN, ep.E2, ep.PENDING, ep.ACC, ep.DISC, ep.SWUM, ep.BACK)
    assert sorted(slots) == list(range(ep.BOOK_SIZE)) == list(range(len(ep.BOOK_SLOTS)))
    assert ep.new_book().shape == (ep.BOOK_SIZE,) and ep.new_book(3).shape == (3, ep.BOOK_SIZE)


def test_carry_and_due_keep_one_pending_transition_by_hand():
    g = 0.5
    book = ep.new_book()
    assert not ep.due(book, True, True)  # nothing pending
    ep.carry(book, False, -10.0, g)  # lost before any decision in view: no transition
    assert book[ep.PENDING] == 0.0
    ep.carry(book, True, 2.0, g)  # in view: starts one
    assert (book[ep.PENDING], book[ep.ACC], book[ep.DISC]) == (1.0, 2.0, g)
    assert not ep.due(book, False, False) and ep.due(book, True, False) and ep.due(book, False, True)
    ep.carry(book, False, -10.0, g)
    ep.carry(book, False, -10.0, g)
    assert book[ep.ACC] == 2.0 + g * -10.0 + g**2 * -10.0 and book[ep.DISC] == g**3


def test_tally_and_close_episode_by_hand():
    book = ep.new_book()
    for r, in_view, e_dist in [(1.0, True, 0.1), (-10.0, False, 9.0), (0.5, True, -0.3), (-10.0, False, 0.0)]:
        ep.tally(book, r, in_view, e_dist)
    book[ep.SWUM], book[ep.BACK] = 3.25, 0.5
    stats = np.zeros((2, len(ep.STAT_NAMES)))
    ep.close_episode(stats, 1, book, 7.5, 1.0)
    assert stats[0].tolist() == [0.0] * 8
    expected = [-18.5, 0.5, 7.5, 2.0, 0.1**2 + 0.3**2, 2.0, 3.25, 0.5]
    assert stats[1].tolist() == pytest.approx(expected, abs=1e-15)
    training = np.zeros((1, len(ep.TRAINING_STAT_NAMES)))  # a training run's leading columns only
    ep.close_episode(training, 0, book, 7.5, 2.0)
    np.testing.assert_array_equal(training[0], [-18.5, 0.5, 7.5, 4.0])
    np.testing.assert_array_equal(ep.statistics_row(book, 7.5, 1.0), stats[1])


def test_the_environments_decision_counts_and_ends_without_the_reward():
    pipe = builtin("paper-left")
    s, book = np.zeros(sim.STATE_SIZE), ep.new_book()
    packed = sim.pack_params(sim.PAPER_SIM)
    sim.init_state_packed(s, pipe.points, pipe.cumulative, 0.0, 0.0, pipe.start_heading, packed)
    ends, sum_e2 = [], 0.0
    for _ in range(3):
        r, ended = ep.decide_packed(s, 0.0, pipe.points, pipe.cumulative, packed, np.zeros(0), book, 3)
        ends.append(ended)
        assert r > -10.0 and s[sim.IN_VIEW]  # straight ahead along the first leg: the pipe stays in view
        sum_e2 += s[sim.E_DIST] * s[sim.E_DIST]
    assert ends == [ep.GOES_ON, ep.GOES_ON, ep.TIME_LIMIT]
    assert (book[ep.DECISIONS], book[ep.SEEN], book[ep.E2], book[ep.TOTAL]) == (3.0, 3.0, sum_e2, 0.0)


def test_end_of_by_hand_the_pipe_end_within_half_a_metre_and_before_the_time_limit():
    cum = np.array([0.0, 4.0, 10.0])  # a pipe 10 m long
    s, book = np.zeros(sim.STATE_SIZE), ep.new_book()
    ends, paper = sim.PAPER_SIM, sim.PAPER_SIM._replace(end_at_pipe_end=False)
    assert ends.end_at_pipe_end and ep.END_MARGIN_M == 0.5
    book[ep.DECISIONS] = 3
    s[sim.PROGRESS_MAX] = 9.49  # 0.51 m short of the end
    assert ep.end_of(book, s, cum, ends, 5) == ep.GOES_ON
    s[sim.PROGRESS_MAX] = 9.5  # 0.5 m short: reached
    assert ep.end_of(book, s, cum, ends, 5) == ep.PIPE_END
    assert ep.end_of(book, s, cum, paper, 5) == ep.GOES_ON  # the paper's reading goes on
    book[ep.DECISIONS] = 5  # the time limit in the same decision: the end of the pipe comes first
    assert ep.end_of(book, s, cum, ends, 5) == ep.PIPE_END
    assert ep.end_of(book, s, cum, paper, 5) == ep.TIME_LIMIT


def test_bootstrap_is_none_from_the_pipe_end_and_the_books_factor_otherwise():
    book = ep.new_book()
    book[ep.DISC] = 0.8**3
    assert ep.bootstrap(book, ep.GOES_ON) == ep.bootstrap(book, ep.TIME_LIMIT) == 0.8**3
    assert ep.bootstrap(book, ep.PIPE_END) == 0.0


def test_travel_adds_the_straight_distance_and_the_progress_lost_in_view_by_hand():
    book, s = ep.new_book(), np.zeros(sim.STATE_SIZE)
    s[sim.X], s[sim.Y], s[sim.PROGRESS], s[sim.IN_VIEW] = 3.0, 4.0, 2.0, 1.0
    ep.travel(book, s, 0.0, 0.0, 2.5)  # moved 5 m, lost 0.5 m of progress, pipe in view
    assert (book[ep.SWUM], book[ep.BACK]) == (5.0, 0.5)
    s[sim.IN_VIEW] = 0.0
    ep.travel(book, s, 3.0, 0.0, 3.0)  # 4 m more; progress lost with the pipe out of view: not counted
    assert (book[ep.SWUM], book[ep.BACK]) == (9.0, 0.5)
    s[sim.IN_VIEW] = 1.0
    ep.travel(book, s, 3.0, 4.0, 1.0)  # progress gained: nothing lost
    assert (book[ep.SWUM], book[ep.BACK]) == (9.0, 0.5)


def test_hold_poses_keeps_the_last_pose_after_an_early_end():
    poses = np.zeros((2, 5, 3))
    book = ep.new_book()
    book[ep.DECISIONS] = 2
    poses[1, :3] = [[0.0, 0.0, 0.0], [1.0, 0.5, 0.1], [2.0, 1.0, 0.2]]
    ep.hold_poses(poses, 1, book)
    np.testing.assert_array_equal(poses[1, 3:], [[2.0, 1.0, 0.2]] * 2)
    assert not poses[0].any()
    ep.hold_poses(np.zeros((0, 1, 3)), 0, book)  # no poses recorded: nothing to do
