"""The heuristic controller of paper §4.1, also the supervisor of supervised CACLA.

It sets the waypoint in the exact direction of the far visible end of the pipe:
``a_SUP = atan2(x1, y1) / 90°``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def heuristic_action(x1, y1):
    """Normalized action pointing the waypoint at the far visible end ``(x1, y1)``."""
    a = math.atan2(x1, y1) / (0.5 * math.pi)
    return min(1.0, max(-1.0, a))


class Heuristic:
    """The heuristic as an agent: ``act`` looks at the pipe, ``update`` learns nothing."""

    algorithm = "heuristic"
    name = "heuristic"

    def act(self, observation: np.ndarray, explore: bool = False) -> float:
        """Action for an observation ``(x1, y1, x2, v_x)``."""
        return heuristic_action(float(observation[0]), float(observation[1]))

    def begin_episode(self, sigma: float) -> None:
        """Nothing to prepare: the heuristic does not explore."""

    def update(self, *args, **kwargs) -> None:
        """Nothing to learn."""
