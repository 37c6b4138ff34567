"""A line-of-sight (LOS) guidance controller on the visible pipe: a classical baseline.

Fossen's lookahead-based LOS steering (Fossen 2021, ch. 12) applied to the straight line through
the visible piece of pipe, in camera coordinates (x lateral, positive to starboard; y forward;
the AUV at the origin, heading along +y). The piece runs from its near end ``(x2, y_near)`` to
its far end ``(x1, y1)``, in the pipe's own direction. With

* the path angle ``π_p = atan2(x1 − x2, y1 − y_near)`` (relative to the heading, positive to
  starboard),
* the cross-track error ``e = y_near sin π_p − x2 cos π_p`` (the AUV's signed distance from the
  line, positive when the AUV is to starboard of the pipe),

the desired course relative to the heading is ``χ_d = π_p − atan(e / Δ)`` with the lookahead
distance Δ, and the action is ``a = χ_d / 90°`` clipped to [−1, 1]: the waypoint is put in the
desired course's direction.

The observation holds ``(x1, y1, x2, v_x)`` but not ``y_near``; :class:`LOS` takes
``y_near = 0``, which is exact whenever the pipe enters the footprint through its bottom edge (the
usual case while following). :func:`los_action` takes ``y_near`` for callers that have it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pipefollow.sim.controller import wrap_angle

DEFAULT_LOOKAHEAD = 1.5  # Δ (m), tuned on paper-left and paper-right (docs/decisions.md)


@njit(cache=True)
def los_action(x1, y1, x2, y_near, lookahead):
    """Normalized action of LOS guidance towards the line (x2, y_near) → (x1, y1), lookahead Δ (m)."""
    dx, dy = x1 - x2, y1 - y_near
    if dx == 0.0 and dy == 0.0:  # a single point in view: head for it
        chi_d = math.atan2(x1, y1)
    else:
        pi_p = math.atan2(dx, dy)  # path angle relative to the heading (rad)
        e = y_near * math.sin(pi_p) - x2 * math.cos(pi_p)  # cross-track error (m)
        chi_d = pi_p - math.atan(e / lookahead)
        chi_d = wrap_angle(chi_d)
    return min(1.0, max(-1.0, chi_d / (0.5 * math.pi)))


class LOS:
    """LOS guidance as an agent: ``act`` steers onto the visible pipe, ``update`` learns nothing.

    Args:
        lookahead: the lookahead distance Δ (m), > 0.
    """

    algorithm = "los"
    name = "LOS"

    def __init__(self, lookahead: float = DEFAULT_LOOKAHEAD) -> None:
        if not (math.isfinite(lookahead) and lookahead > 0.0):
            raise ValueError(f"lookahead must be a finite number > 0 (m), got {lookahead}")
        self.lookahead = float(lookahead)

    def act(self, observation: np.ndarray, explore: bool = False) -> float:
        """Action for an observation ``(x1, y1, x2, v_x)``, with ``y_near = 0``."""
        return los_action(
            float(observation[0]), float(observation[1]), float(observation[2]), 0.0, self.lookahead
        )

    def begin_episode(self, sigma: float) -> None:
        """Nothing to prepare: LOS does not explore."""

    def update(self, *args, **kwargs) -> None:
        """Nothing to learn."""
