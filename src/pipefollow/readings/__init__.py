"""The decision layer: named readings of the points the paper leaves open.

``points`` names each open point, its choices and the paper's words, and parses reading ids;
``apply`` turns a :class:`Readings` into the parameter records of the layers below. May import
``files``, ``sim`` and ``learners``; nothing above.
"""

from pipefollow.readings.apply import (
    action_grid,
    cacla_params,
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
    "OPEN_POINTS",
    "POINTS",
    "REPORT_ONLY",
    "OpenPoint",
    "ReadingError",
    "Readings",
    "action_grid",
    "cacla_params",
    "parse",
    "sigma_scale",
    "sim_params",
    "skew_gamma",
    "state_grid",
    "table_markdown",
]
