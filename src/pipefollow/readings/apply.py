"""What a reading means for the layers below: parameter records of the learners, features and simulation.

Every path — the compiled trainer, the Gymnasium environment, the report — turns a
:class:`~pipefollow.readings.points.Readings` into parameters through these functions, so a
reading is applied the same way everywhere.
"""

from __future__ import annotations

import math

from pipefollow.learners import cacla
from pipefollow.learners.cacla import CaclaParams
from pipefollow.learners.exploration import skew_step_to_gamma
from pipefollow.learners.rbf import ACTION_CENTRES, STATE_CENTRES, RBFGrid
from pipefollow.readings.points import CRUISE_SPEED, DEFAULT, Readings
from pipefollow.sim.decision import PAPER_SIM, SimParams


def skew_gamma(skew_deg: float, r: Readings = DEFAULT) -> float:
    """Δγ of eq. 15 from degrees to units of γ under the ``skew_unit`` reading.

    Raises:
        ValueError: ``skew_deg`` negative or not finite.
    """
    gamma = skew_step_to_gamma(skew_deg)  # 45° is one unit of γ; checks the value
    return math.radians(skew_deg) if r.skew_unit == "rad" else gamma


def cacla_params(r: Readings = DEFAULT, skew_deg: float = 0.0, **fields) -> CaclaParams:
    """CACLA's parameter record under ``r``, with Δγ from degrees and other ``fields`` as given."""
    return CaclaParams(
        skew=skew_gamma(skew_deg, r),
        gamma_max=r.gamma_max,
        skew_sample={
            "location": cacla.SAMPLE_LOCATION,
            "centred": cacla.SAMPLE_CENTRED,
            "moments": cacla.SAMPLE_MOMENTS,
        }[r.skew_sample],
        skew_step=cacla.STEP_GAMMA if r.skew_step == "gamma" else cacla.STEP_WEIGHTS,
        k_update=cacla.K_EVERY if r.k_update == "every" else cacla.K_POSITIVE,
        k_step=cacla.STEP_GAMMA if r.k_step == "k" else cacla.STEP_WEIGHTS,
        **fields,
    )


def state_grid(r: Readings = DEFAULT) -> RBFGrid:
    """The 1,764-feature state grid under the ``rbf`` and ``rbf_width`` readings."""
    return RBFGrid(STATE_CENTRES, form=r.rbf, width=r.rbf_width)


def action_grid(r: Readings = DEFAULT) -> RBFGrid:
    """SARSA's 13-centre action grid under the ``rbf`` and ``rbf_width`` readings."""
    return RBFGrid((ACTION_CENTRES,), form=r.rbf, width=r.rbf_width)


def sim_params(r: Readings = DEFAULT, base: SimParams = PAPER_SIM) -> SimParams:
    """The simulation's parameters under the ``start_speed`` reading."""
    return base._replace(start_speed=CRUISE_SPEED if r.start_speed == "cruise" else 0.0)


def sigma_scale(r: Readings = DEFAULT) -> float:
    """Factor from the paper's σ to normalized action units: 1, or 1/(π/2) for σ in radians."""
    return 2.0 / math.pi if r.sigma_unit == "rad" else 1.0
