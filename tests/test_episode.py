"""The episode protocol (pipefollow.sim.episode): its layouts and its bookkeeping, by hand."""

import numpy as np
import pytest

from pipefollow.sim import decision as sim
from pipefollow.sim import episode as ep
from pipefollow.sim.pipeline import builtin


def test_every_column_and_slot_is_the_position_of_its_name():
    names = ("return", "pipe_in_view", "progress_m", "time_lost_s", "sum_e_dist2", "n_in_view")
    assert ep.STAT_NAMES == names
    columns = (ep.STAT_RETURN, ep.STAT_IN_VIEW, ep.STAT_PROGRESS, ep.STAT_TIME_LOST, ep.STAT_SUM_E2,
               ep.STAT_N_SEEN)  # fmt: skip
    assert [ep.STAT_NAMES[c] for c in columns] == list(ep.STAT_NAMES)
    # a training run's columns (its CSV) are the leading ones
    assert ep.TRAINING_STAT_NAMES == ("return", "pipe_in_view", "progress_m", "time_lost_s")
    slots = (ep.DECISIONS, ep.TOTAL, ep.SEEN, ep.E2, ep.PENDING, ep.ACC, ep.DISC)
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
    stats = np.zeros((2, len(ep.STAT_NAMES)))
    ep.close_episode(stats, 1, book, 7.5, 1.0)
    assert stats[0].tolist() == [0.0] * 6
    assert stats[1].tolist() == pytest.approx([-18.5, 0.5, 7.5, 2.0, 0.1**2 + 0.3**2, 2.0], abs=1e-15)
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
    assert ends == [False, False, True]
    assert (book[ep.DECISIONS], book[ep.SEEN], book[ep.E2], book[ep.TOTAL]) == (3.0, 3.0, sum_e2, 0.0)
