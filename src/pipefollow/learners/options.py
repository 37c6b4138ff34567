"""The learners' options, one table: :data:`LEARNER_OPTIONS`.

Every option a learner of the registry takes — its switches (skew, supervision, CACLA+Var, the
critic's trace), its step sizes, the σ schedule and the state it observes — is one
:class:`LearnerOption` here, with its default, its allowed values, its unit and source and the
learners that take it. The layers above build from this table alone: the options of
``pipefollow train`` (:func:`pipefollow.cli.options.learner_options`), the fields of an experiment
file's trial (:class:`pipefollow.experiments.schema.TrialConfig`), their checks, the listing of
``pipefollow trials`` and the options a policy file shows. An option is added here once.

Groups:

* ``switch``: an option of the learners that name it in their ``LearnerKind.options``; its default
  is the off value, and setting it for another learner is an error;
* ``step``: a field of a learner's parameter record (its ``LearnerKind.step_sizes``);
* ``schedule``: how training runs the learner (the σ schedule), for every learner;
* ``state``: what the learner observes (:mod:`pipefollow.sim.observation`), for every learner.

A training phase may set the options of :data:`PHASE_OPTIONS` for its own episodes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from pipefollow.learners.cacla_act import PAPER_CACLA
from pipefollow.learners.exploration import SIGMA_END, SIGMA_START
from pipefollow.learners.sarsa import PAPER_SARSA
from pipefollow.sim.observation import STATE_NAMES

GROUPS = ("switch", "step", "schedule", "state")


@dataclass(frozen=True)
class LearnerOption:
    """One option of the learners.

    Attributes:
        name: its key in experiment files and ``make_agent`` (``critic_lambda``).
        default: its default, the paper's value (a switch's: off).
        group: one of :data:`GROUPS`.
        help: its meaning, unit and source (one line).
        low, high: the allowed range of a number (None: unbounded); ``low_open``, ``high_open``
            exclude the end.
        choices: the allowed names of a text option.
        flag: its command-line option (default: ``--`` and the name with dashes).
    """

    name: str
    default: Any
    group: str
    help: str
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    choices: tuple[str, ...] = ()
    flag: str = ""

    @property
    def option(self) -> str:
        """The command-line option (``--critic-lambda``)."""
        return self.flag or "--" + self.name.replace("_", "-")

    @property
    def kind(self) -> type:
        """The type of its values: ``bool``, ``float`` or ``str``."""
        return type(self.default)

    def allowed(self) -> str:
        """What values it takes, in words (``in [0, 1]``, ``one of once, var``)."""
        if self.kind is bool:
            return "true or false"
        if self.kind is str:
            return f"one of {', '.join(self.choices)}"
        if self.low is not None and self.high is not None:
            left, right = "(" if self.low_open else "[", ")" if self.high_open else "]"
            return f"in {left}{self.low:g}, {self.high:g}{right}"
        if self.low is not None:
            return f"{'>' if self.low_open else '≥'} {self.low:g}"
        return "a finite number"

    def check(self, value: Any) -> Any:
        """``value`` as the option takes it (a number as float); raises ``ValueError`` naming the option.

        Raises:
            ValueError: e.g. ``critic_lambda must be in [0, 1], got 1.5``.
        """
        bad = ValueError(f"{self.name} must be {self.allowed()}, got {value!r}")
        if self.kind is bool:
            if not isinstance(value, bool):
                raise bad
            return value
        if self.kind is str:
            if value not in self.choices:
                raise bad
            return value
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise ValueError(f"{self.name} must be a finite number, got {value!r}")
        value = float(value)
        if self.low is not None and (value < self.low or (self.low_open and value == self.low)):
            raise bad
        if self.high is not None and (value > self.high or (self.high_open and value == self.high)):
            raise bad
        return value


def _number(name, default, group, help, low=None, high=None, **kw) -> LearnerOption:
    return LearnerOption(name, float(default), group, help, low, high, **kw)


_UNIT = dict(low=0.0, high=1.0, low_open=True)  # a step size or discount: (0, 1]

LEARNER_OPTIONS: tuple[LearnerOption, ...] = (
    _number(
        "skew_deg",
        0.0,
        "switch",
        "CACLA skew step Δγ (deg, eq. 15): 11.25, 22.5 or 45 in the paper; 0 = Gaussian exploration (eq. 8)",
        0.0,
        180.0,
        flag="--skew",
    ),
    LearnerOption(
        "supervised",
        False,
        "switch",
        "the heuristic as supervisor: supervised CACLA (eqs. 10-13) or actor-critic (eq. 11)",
    ),
    LearnerOption(
        "actor_update",
        "delta",
        "switch",
        "actor-critic: the actor's step factor on (a - A(s)): delta (eq. 9), positive (max(δ, 0): eq. 7's "
        "max term alone) or sign (sgn δ: eq. 7's sign term alone)",
        choices=("delta", "positive", "sign"),
    ),
    LearnerOption(
        "actor_repeats",
        "once",
        "switch",
        "CACLA, beyond the paper: one actor update per δ > 0 (once, eq. 7) or ⌈δ/√var⌉ of them, var a "
        "running variance of δ (var: CACLA+Var, Van Hasselt & Wiering 2007)",
        choices=("once", "var"),
    ),
    _number(
        "critic_lambda",
        0.0,
        "switch",
        "beyond the paper: λ of the critic's TD(λ) trace; 0 = TD(0) (eqs. 5-6)",
        0.0,
        1.0,
    ),
    _number("alpha_v", PAPER_CACLA.alpha_v, "step", "critic step size α_V (paper §4)", **_UNIT),
    _number("alpha_pi", PAPER_CACLA.alpha_pi, "step", "actor step size α_π (paper §4)", **_UNIT),
    _number("alpha_q", PAPER_SARSA.alpha, "step", "SARSA step size α (paper §4)", **_UNIT),
    _number("discount", PAPER_CACLA.discount, "step", "discount factor γ_d (paper §4)", **_UNIT),
    _number(
        "delta_k",
        PAPER_CACLA.delta_k,
        "step",
        "supervised learners: increment Δk of k(s) per visit (paper §4.1)",
        0.0,
    ),
    _number(
        "forgetting",
        PAPER_CACLA.forgetting,
        "step",
        "supervised learners: per-update decay of k's weights; the paper uses none",
        0.0,
        1.0,
        high_open=True,
    ),
    _number(
        "var_rate",
        PAPER_CACLA.var_rate,
        "step",
        "CACLA+Var: rate β of the running variance of δ, "
        "var ← (1 - β) var + β δ² (Van Hasselt & Wiering 2007)",
        **_UNIT,
    ),
    _number(
        "sigma_start",
        SIGMA_START,
        "schedule",
        "exploration σ of the first episode, normalized action units (paper §4: 1)",
        0.0,
    ),
    _number(
        "sigma_end",
        SIGMA_END,
        "schedule",
        "exploration σ of the last episode (paper §4: 0.01); σ falls linearly in between",
        0.0,
    ),
    LearnerOption(
        "state",
        "paper",
        "state",
        "what the learner observes: paper = (x1, y1, x2, v_x) (§4); +drift adds the DVL's sway velocity "
        "over ground (m/s), +yaw the gyro's yaw rate (rad/s) (pipefollow.sim.observation)",
        choices=STATE_NAMES,
    ),
)
OPTION = {o.name: o for o in LEARNER_OPTIONS}
# The options a training phase may set for its own episodes (an experiment file's phase ``learner``
# table): the step sizes and the switches that change neither the weights' shape, the features nor
# the random numbers drawn (not the skew, the supervisor or the state).
PHASE_OPTIONS = ("actor_repeats", "critic_lambda", *(o.name for o in LEARNER_OPTIONS if o.group == "step"))
DEFAULTS = {o.name: o.default for o in LEARNER_OPTIONS}
# The switches with their off values: set for a learner that does not take them, they are refused.
SWITCHES = {o.name: o.default for o in LEARNER_OPTIONS if o.group == "switch"}


def check_value(name: str, value: Any) -> Any:
    """``value`` of option ``name`` checked (:meth:`LearnerOption.check`); raises ``ValueError``."""
    return OPTION[name].check(value)


def check_schedule(sigma_start: float, sigma_end: float) -> None:
    """σ may only fall: ``sigma_start ≥ sigma_end``; raises ``ValueError`` naming sigma_start."""
    if sigma_start < sigma_end:
        raise ValueError(f"sigma_start must be ≥ sigma_end ({sigma_end:g}), got {sigma_start:g}")


def describe(values: dict[str, Any]) -> str:
    """The options of ``values`` away from their defaults (``skew 22.5°, critic_lambda 0.9``)."""
    parts = []
    for o in LEARNER_OPTIONS:
        v = values.get(o.name, o.default)
        if v != o.default:
            shown = f"{v:g}" if isinstance(v, float) else str(v)
            if o.name == "skew_deg":  # as the labels say it
                parts.append(f"skew {shown}°")
            else:
                parts.append(o.name if v is True else f"{o.name} {shown}")
    return ", ".join(parts)
