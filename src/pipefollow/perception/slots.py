"""The observation slots a sensor writes into the simulation state: one sighting of the pipe.

Every sensor of the environments (the vision camera, raw or tracked, the sonar, the fused sensor)
reports the visible piece by its ends; :func:`sighting_of` adds the tracking errors and the side,
and :func:`write_sighting` puts a sighting and the in-view flag into the state's slots. While the
pipe is lost a sensor writes its last sighting again, as the exact camera keeps its last one.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from pipefollow.sim import decision as sim
from pipefollow.sim.camera import tracking_errors


class Sighting(NamedTuple):
    """The observation slots of the simulation state a detection fills (camera metres, radians)."""

    x1: float = 0.0  # the far end
    y1: float = 0.0
    x2: float = 0.0  # the near end's lateral position ...
    y_near: float = 0.0  # ... and its forward position
    e_dist: float = 0.0  # tracking errors (sim.camera.tracking_errors)
    e_angl: float = 0.0
    side: float = 1.0  # the side the pipe was last seen on: +1 starboard (x1 ≥ 0), −1 port


def sighting_of(x1: float, y1: float, x2: float, y_near: float, side: float | None = None) -> Sighting:
    """The sighting of a piece from its ends, with its tracking errors.

    The side is the far end's (+1 starboard, −1 port) unless ``side`` is given.
    """
    e_dist, e_angl = tracking_errors(x1, y1, x2, y_near)
    if side is None:
        side = 1.0 if x1 >= 0.0 else -1.0
    return Sighting(x1, y1, x2, y_near, e_dist, e_angl, side)


def write_sighting(s: np.ndarray, last: Sighting, in_view: bool) -> None:
    """``last`` into the state's observation slots and ``in_view`` into its in-view flag."""
    s[sim.X1], s[sim.Y1], s[sim.X2], s[sim.Y_NEAR] = last.x1, last.y1, last.x2, last.y_near
    s[sim.E_DIST], s[sim.E_ANGL], s[sim.LAST_SIDE] = last.e_dist, last.e_angl, last.side
    s[sim.IN_VIEW] = 1.0 if in_view else 0.0


def observed(states: np.ndarray, dtype, slots: np.ndarray | None = None) -> np.ndarray:
    """The observations of one state or a batch (rows), as a new array of ``dtype``.

    The paper's leading four slots ``(x1, y1, x2, v_x)``, or ``slots`` (a named state's,
    :mod:`pipefollow.sim.observation`).
    """
    return (states[..., :4] if slots is None else states[..., slots]).astype(dtype)


__all__ = ["Sighting", "observed", "sighting_of", "write_sighting"]
