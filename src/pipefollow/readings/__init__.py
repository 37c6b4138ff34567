"""The decision layer: named readings of the points the paper leaves open.

``points`` names each open point, its choices and the paper's words, and parses reading ids;
``apply`` turns a :class:`Readings` into the parameter records of the layers below: the learners'
records and grids (``learner_inputs``), the simulation's (``sim_params``) and the σ scale. May import
``files``, ``sim`` and ``learners``; nothing above.
"""

from pipefollow.readings.apply import (
    LEARNER_INPUTS,
    SIM_READINGS,
    action_grid,
    actor_critic_params,
    cacla_params,
    learner_inputs,
    sarsa_params,
    sigma_scale,
    sim_params,
    skew_gamma,
    state_grid,
)
from pipefollow.readings.points import (
    CRUISE_SPEED,
    DEFAULT,
    OPEN_POINTS,
    POINTS,
    REPORT_ONLY,
    OpenPoint,
    ReadingError,
    Readings,
    parse,
    table_markdown,
)

__all__ = [
    "CRUISE_SPEED",
    "DEFAULT",
    "LEARNER_INPUTS",
    "OPEN_POINTS",
    "POINTS",
    "REPORT_ONLY",
    "SIM_READINGS",
    "OpenPoint",
    "ReadingError",
    "Readings",
    "action_grid",
    "actor_critic_params",
    "cacla_params",
    "learner_inputs",
    "parse",
    "sarsa_params",
    "sigma_scale",
    "sim_params",
    "skew_gamma",
    "state_grid",
    "table_markdown",
]
