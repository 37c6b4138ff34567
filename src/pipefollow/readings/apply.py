"""What a reading means for the layers below: parameter records of the learners, features and simulation.

Every path — the compiled trainer, the Gymnasium environment, the report — turns a
:class:`~pipefollow.readings.points.Readings` into parameters through these functions, so a
reading is applied the same way everywhere.
"""

from __future__ import annotations

import math

from pipefollow.learners import cacla, rbf
from pipefollow.learners.cacla import CaclaParams
from pipefollow.learners.rbf import RBFGrid
from pipefollow.readings.points import CRUISE_SPEED, DEFAULT, Readings
from pipefollow.sim.decision import PAPER_SIM, SimParams


def skew_gamma(skew_deg: float, r: Readings = DEFAULT) -> float:
    """Δγ of eq. 15 from degrees to units of γ under the ``skew_unit`` reading.

    Raises:
        ValueError: ``skew_deg`` negative or not finite.
    """
    return cacla.skew_in_gamma_units(skew_deg, r.skew_unit)


def cacla_params(r: Readings = DEFAULT, skew_deg: float = 0.0, **fields) -> CaclaParams:
    """CACLA's parameter record under ``r``, with Δγ from degrees and other ``fields`` as given."""
    return cacla.params_under(r, skew_deg, **fields)


def state_grid(r: Readings = DEFAULT) -> RBFGrid:
    """The 1,764-feature state grid under the ``rbf`` and ``rbf_width`` readings."""
    return rbf.state_grid(r.rbf, r.rbf_width)


def action_grid(r: Readings = DEFAULT) -> RBFGrid:
    """SARSA's 13-centre action grid under the ``rbf`` and ``rbf_width`` readings."""
    return rbf.action_grid(r.rbf, r.rbf_width)


def sim_params(r: Readings = DEFAULT, base: SimParams = PAPER_SIM) -> SimParams:
    """The simulation's parameters under the ``start_speed`` reading."""
    return base._replace(start_speed=CRUISE_SPEED if r.start_speed == "cruise" else 0.0)


def sigma_scale(r: Readings = DEFAULT) -> float:
    """Factor from the paper's σ to normalized action units: 1, or 1/(π/2) for σ in radians."""
    return 2.0 / math.pi if r.sigma_unit == "rad" else 1.0
