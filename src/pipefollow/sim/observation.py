"""What a learner observes: the paper's state, or it and what the vehicle's own sensors measure.

The paper's state is the camera's ``(x1, y1, x2, v_x)`` (§4). A vehicle also measures its motion:
a DVL reads its velocity over ground (the sway part shows the drift a current causes), a gyro its
yaw rate. The named states add those readings (state slots :data:`~pipefollow.sim.decision.DVL_SWAY`
and :data:`~pipefollow.sim.decision.GYRO_R`, noisy as the disturbance's ``dvl_noise`` and
``gyro_noise`` say):

===================  ====================================================  ======================
name                 observation                                           units
===================  ====================================================  ======================
``paper``            x1, y1, x2, v_x (the default; the reproduction's)     m, m, m, m/s
``paper+drift``      … and the DVL's sway velocity over ground v_y         … m/s
``paper+yaw``        … and the gyro's yaw rate r                           … rad/s
``paper+drift+yaw``  … and both                                            … m/s, rad/s
===================  ====================================================  ======================

An observation is the state's slots :func:`slots` in this order; every path takes it from there
(the environments, the learners' compiled loops), so they observe the same numbers.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.sim import decision as sim


class Component(NamedTuple):
    """One entry of an observation."""

    name: str
    slot: int  # its slot in the simulation state
    unit: str
    low: float  # the observation space's bounds (the camera's footprint; speeds a bound, not a limit)
    high: float
    description: str


# The paper's four (x1, y1, x2, v_x), then what the motion sensors add; bounds of the camera's are
# set by the camera's footprint (:func:`bounds`).
PAPER = (
    Component("x1", sim.X1, "m", np.nan, np.nan, "far end of the visible pipe, lateral (starboard +)"),
    Component("y1", sim.Y1, "m", np.nan, np.nan, "far end of the visible pipe, forward"),
    Component("x2", sim.X2, "m", np.nan, np.nan, "near end of the visible pipe, lateral (starboard +)"),
    Component("v_x", sim.VX, "m/s", -1.0, 1.0, "surge speed over ground"),
)
DRIFT = Component("v_y", sim.DVL_SWAY, "m/s", -1.0, 1.0, "DVL: sway velocity over ground (starboard +)")
YAW = Component("r", sim.GYRO_R, "rad/s", -1.0, 1.0, "gyro: yaw rate (clockwise +)")

STATES: dict[str, tuple[Component, ...]] = {
    "paper": PAPER,
    "paper+drift": (*PAPER, DRIFT),
    "paper+yaw": (*PAPER, YAW),
    "paper+drift+yaw": (*PAPER, DRIFT, YAW),
}
STATE_NAMES = tuple(STATES)
PAPER_STATE = "paper"


def components(state: str) -> tuple[Component, ...]:
    """The entries of the observation of ``state``.

    Raises:
        ValueError: an unknown name (``state must be one of paper, paper+drift, …, got 'x'``).
    """
    try:
        return STATES[state]
    except (KeyError, TypeError):
        raise ValueError(f"state must be one of {', '.join(STATE_NAMES)}, got {state!r}") from None


def slots(state: str) -> np.ndarray:
    """The state slots of the observation of ``state`` (read-only int64), in its order."""
    out = np.array([c.slot for c in components(state)], dtype=np.int64)
    out.setflags(write=False)
    return out


def bounds(state: str, camera) -> tuple[np.ndarray, np.ndarray]:
    """The observation space's ``(low, high)`` of ``state``: the camera's footprint, the speeds' bounds."""
    w, depth = camera.half_width, camera.depth
    camera_bounds = [(-w, w), (0.0, depth), (-w, w)]
    lows, highs = [], []
    for k, c in enumerate(components(state)):
        lo, hi = camera_bounds[k] if k < len(camera_bounds) else (c.low, c.high)
        lows.append(lo)
        highs.append(hi)
    return np.array(lows), np.array(highs)


def units(state: str) -> tuple[str, ...]:
    """The units of the observation of ``state`` (``("m", "m", "m", "m/s")``)."""
    return tuple(c.unit for c in components(state))


def names(state: str) -> tuple[str, ...]:
    """The names of the observation's entries (``("x1", "y1", "x2", "v_x")``)."""
    return tuple(c.name for c in components(state))


@njit(cache=True)
def observe(s, state_slots, out):
    """The observation of state ``s``: ``out[i] = s[state_slots[i]]``; returns ``out``."""
    for i in range(state_slots.shape[0]):
        out[i] = s[state_slots[i]]
    return out


def observation_of(states: np.ndarray, state: str) -> np.ndarray:
    """The observation of one state or a batch (rows) under ``state`` (a new float64 array)."""
    return np.asarray(states)[..., slots(state)]
