"""The reward of eq. 19 and the lost-pipe penalty (paper §4)."""

from __future__ import annotations

from numba import njit

LOST_REWARD = -10.0  # per decision while the pipe is lost (paper §4)


@njit(cache=True)
def reward(v_x, e_dist, e_angl, action, previous_action):
    """Eq. 19: ``R = v_x − e_dist² − e_angl² − (a − a_prev)²``, actions in normalized units."""
    da = action - previous_action
    return v_x - e_dist * e_dist - e_angl * e_angl - da * da
