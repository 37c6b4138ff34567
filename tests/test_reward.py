"""Eq. 19 and the lost-pipe penalty (paper §4)."""

import pytest

from pipefollow.sim.reward import LOST_REWARD, reward


@pytest.mark.parametrize(
    ("v_x", "e_dist", "e_angl", "action", "previous", "expected"),
    [
        (0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        (0.45, 0.0, 0.0, 0.2, 0.2, 0.45),  # on the pipe, steady action: the speed alone
        # 0.4 - 0.09 - 0.04 - 0.25 = 0.02
        (0.4, 0.3, -0.2, 0.5, 0.0, 0.02),
        # -0.1 - 0.25 - 0.16 - (0.5 - (-1))² = -0.51 - 2.25 = -2.76
        (-0.1, -0.5, 0.4, 0.5, -1.0, -2.76),
        # worst in view: v_x = -0.25, e_dist = 1, e_angl = π/2, a from -1 to 1: -0.25-1-2.4674-4
        (-0.25, 1.0, 1.5707963267948966, 1.0, -1.0, -7.7174011002),
    ],
)
def test_eq19_at_hand_values(v_x, e_dist, e_angl, action, previous, expected):
    assert reward(v_x, e_dist, e_angl, action, previous) == pytest.approx(expected, abs=1e-9)


def test_worst_in_view_reward_is_above_the_lost_penalty():
    # the paper's −10 per decision with the pipe out of view is what the environment pays (test_env)
    worst = reward(-0.25, 1.0, -3.141592653589793 / 2, -1.0, 1.0)
    assert worst > LOST_REWARD


def test_action_term_is_symmetric():
    assert reward(0.3, 0.1, 0.2, 0.7, -0.1) == reward(0.3, -0.1, -0.2, -0.1, 0.7)
