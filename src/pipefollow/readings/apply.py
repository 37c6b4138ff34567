"""What a reading means for the layers below: parameter records of the learners, features and simulation.

Every path — the compiled trainer, the Gymnasium environment, the report — turns a
:class:`~pipefollow.readings.points.Readings` into parameters through these functions, so a
reading is applied the same way everywhere; the learners receive plain records and grids.
:func:`learner_inputs` gives a learner of the registry what its ``make`` takes.
"""

from __future__ import annotations

import math

from pipefollow.learners.actor_critic import ACTOR_UPDATES, ActorCriticParams
from pipefollow.learners.cacla_act import CaclaParams
from pipefollow.learners.cacla_update import (
    ACTOR_REPEATS,
    K_EVERY,
    K_POSITIVE,
    SAMPLE_CENTRED,
    SAMPLE_LOCATION,
    SAMPLE_MOMENTS,
    STEP_GAMMA,
    STEP_WEIGHTS,
)
from pipefollow.learners.exploration import skew_step_to_gamma
from pipefollow.learners.protocol import option_code
from pipefollow.learners.rbf import ACTION_CENTRES, RBFGrid, state_centres
from pipefollow.learners.sarsa import SarsaParams
from pipefollow.readings.points import CRUISE_SPEED, DEFAULT, Readings
from pipefollow.sim.decision import PAPER_SIM, SimParams

SKEW_SAMPLES = {"location": SAMPLE_LOCATION, "centred": SAMPLE_CENTRED, "moments": SAMPLE_MOMENTS}


def skew_gamma(skew_deg: float, r: Readings = DEFAULT) -> float:
    """Δγ of eq. 15 from degrees to units of γ under the ``skew_unit`` reading (``deg45`` or ``rad``).

    Raises:
        ValueError: ``skew_deg`` negative or not finite.
    """
    gamma = skew_step_to_gamma(skew_deg)  # 45° is one unit of γ; checks the value
    return math.radians(skew_deg) if r.skew_unit == "rad" else gamma


def cacla_params(r: Readings = DEFAULT, skew_deg: float = 0.0, **fields) -> CaclaParams:
    """CACLA's parameter record under ``r``, with Δγ from degrees and other ``fields`` as given.

    The readings set ``skew`` (``skew_unit``), ``gamma_max``, ``skew_sample``, ``skew_step``,
    ``k_update`` and ``k_step``; ``fields`` are the record's others (step sizes, options as codes).

    Raises:
        ValueError: ``skew_deg`` negative or not finite, or ``critic_lambda`` outside [0, 1].
    """
    lam = fields.get("critic_lambda", 0.0)
    if not 0.0 <= lam <= 1.0:
        raise ValueError(f"critic_lambda must be in [0, 1], got {lam!r}")
    return CaclaParams(
        skew=skew_gamma(skew_deg, r),
        gamma_max=r.gamma_max,
        skew_sample=SKEW_SAMPLES[r.skew_sample],
        skew_step=STEP_GAMMA if r.skew_step == "gamma" else STEP_WEIGHTS,
        k_update=K_EVERY if r.k_update == "every" else K_POSITIVE,
        k_step=STEP_GAMMA if r.k_step == "k" else STEP_WEIGHTS,
        **fields,
    )


def actor_critic_params(r: Readings = DEFAULT, actor_update: int = ACTOR_UPDATES["delta"],
                        **fields) -> ActorCriticParams:  # fmt: skip
    """The actor-critic's record under ``r``: CACLA's without skew, and the actor's step factor (a code)."""
    return ActorCriticParams(*cacla_params(r, 0.0, **fields), actor_update=actor_update)


def sarsa_params(r: Readings = DEFAULT, **fields) -> SarsaParams:
    """SARSA's record under ``r``: no reading changes it (the readings reach SARSA through its grids)."""
    return SarsaParams(**fields)


def state_grid(r: Readings = DEFAULT, state: str = "paper") -> RBFGrid:
    """The state grid of the named ``state`` under the ``rbf`` and ``rbf_width`` readings.

    The paper's state has 1,764 features; each entry a measured state adds multiplies them by 5
    (:func:`~pipefollow.learners.rbf.state_centres`).
    """
    return RBFGrid(state_centres(state), form=r.rbf, width=r.rbf_width)


def action_grid(r: Readings = DEFAULT) -> RBFGrid:
    """SARSA's 13-centre action grid under the ``rbf`` and ``rbf_width`` readings."""
    return RBFGrid((ACTION_CENTRES,), form=r.rbf, width=r.rbf_width)


def _cacla_inputs(r: Readings, *, actor_repeats: str = "once", skew_deg: float = 0.0, state: str = "paper",
                  **fields) -> dict:  # fmt: skip
    repeats = option_code("actor_repeats", ACTOR_REPEATS, actor_repeats)
    params = cacla_params(r, skew_deg, actor_repeats=repeats, **fields)
    return {"params": params, "grid": state_grid(r, state)}


def _actor_critic_inputs(r: Readings, *, actor_update: str = "delta", state: str = "paper", **fields) -> dict:
    update = option_code("actor_update", ACTOR_UPDATES, actor_update)
    return {"params": actor_critic_params(r, update, **fields), "grid": state_grid(r, state)}


def _sarsa_inputs(r: Readings, state: str = "paper", **fields) -> dict:
    return {"params": sarsa_params(r, **fields), "grid": state_grid(r, state), "action_grid": action_grid(r)}


# Learner name (learners.registry) → its inputs under the readings, from its options and record fields
LEARNER_INPUTS = {"cacla": _cacla_inputs, "ac": _actor_critic_inputs, "sarsa": _sarsa_inputs}


def learner_inputs(algorithm: str, r: Readings = DEFAULT, **options) -> dict:
    """What learner ``algorithm``'s ``make`` takes under ``r``: its parameter record and RBF grids.

    ``options`` are the learner's options (``skew_deg``, ``actor_repeats``, ``actor_update`` by
    name), the named ``state`` it observes (its grid) and fields of its record (step sizes,
    ``supervised``, ``critic_lambda``).

    Raises:
        ValueError: an unknown option value (``actor_repeats must be one of once, var, got …``).
    """
    return LEARNER_INPUTS[algorithm](r, **options)


# The readings the simulation reads (the keys :func:`sim_params` applies): the only ones that can
# change a deterministic evaluation of a saved policy or a fixed controller.
SIM_READINGS = ("start_speed", "pipe_end")


def sim_params(r: Readings = DEFAULT, base: SimParams = PAPER_SIM) -> SimParams:
    """The simulation's parameters under the readings of :data:`SIM_READINGS` (start speed, pipe end)."""
    return base._replace(
        start_speed=CRUISE_SPEED if r.start_speed == "cruise" else 0.0,
        end_at_pipe_end=r.pipe_end == "end",
    )


def sigma_scale(r: Readings = DEFAULT) -> float:
    """Factor from the paper's σ to normalized action units: 1, or 1/(π/2) for σ in radians."""
    return 2.0 / math.pi if r.sigma_unit == "rad" else 1.0
