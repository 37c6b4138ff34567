"""Readings: named choices for the points the paper leaves open (docs/design.md, "Readings").

Where the paper can be read in more than one way and the choice can change a verdict, each way
is a *reading* with a name. A reading id is ``key=value`` (``skew_step=weights``); several join
with ``,`` (``skew_step=weights,start_speed=cruise``). :class:`Readings` holds one value per open
point; the defaults are the project's readings. :mod:`pipefollow.readings.apply` turns a :class:`Readings`
into the parameter records of the layers below.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable
from dataclasses import dataclass

from pipefollow.learners.rbf import FORMS, WIDTHS

# The AUV's steady surge speed with the waypoint straight ahead (action 0), with the paper's
# model and gains: the start speed of the ``cruise`` reading (m/s). Measured by simulation and
# checked in the tests against the analytic surge balance.
CRUISE_SPEED = 0.476


class ReadingError(ValueError):
    """A reading id that cannot be used; the message names it and what is allowed."""


@dataclass(frozen=True)
class OpenPoint:
    """One point the paper leaves open.

    Attributes:
        key: the reading's key.
        choices: the allowed values (``()`` for a number).
        default: the project's reading.
        paper: the paper's words that leave the point open.
        meaning: what the choices mean.
    """

    key: str
    choices: tuple[str, ...]
    default: str
    paper: str
    meaning: str


OPEN_POINTS: tuple[OpenPoint, ...] = (
    OpenPoint(
        "skew_step",
        ("gamma", "weights"),
        "gamma",
        'eq. 15: φ_γ = φ_γ + Γ(sgn(δ) sgn(a − A(s)) Δγ); "22.5° equals absolute value of 0.5" (§4.2)',
        "gamma: γ(s) itself moves by Δγ (w_γ += Δγ·sgn·sgn·φ/‖φ‖²); weights: the weights move by "
        "Δγ·sgn·sgn·φ(s), so γ(s) moves by Δγ‖φ‖² (≈ 0.08 Δγ with normalized features)",
    ),
    OpenPoint(
        "skew_sample",
        ("location", "centred", "moments"),
        "location",
        'eq. 14 gives the density with parameters μ, σ, γ; "keeping the current estimate μ of the '
        'optimal action fixed" (§2.3)',
        "location: a = A(s) + σz, A(s) and σ the location and scale (the mean moves by σδ√(2/π)); "
        "centred: z shifted to mean 0; moments: z standardized to mean 0 and s.d. 1",
    ),
    OpenPoint(
        "gamma_max",
        (),
        "1",
        '"Γ caps updates of φ_α at α_max = 1 in all cases" (§4.1)',
        "the cap −γ_max ≤ γ(s) ≤ γ_max, in units of γ",
    ),
    OpenPoint(
        "skew_unit",
        ("deg45", "rad"),
        "deg45",
        'Δγ = (11.25°, 22.5°, 45°) (§4.1); "γ = 22.5° skew (equals absolute value of 0.5 in relation to '
        'Fig. 1)" (§4.2)',
        "deg45: 45° is one unit of γ (22.5° ↦ 0.5); rad: Δγ in radians (22.5° ↦ 0.393)",
    ),
    OpenPoint(
        "start_speed",
        ("rest", "cruise"),
        "rest",
        "the paper does not say how an episode starts",
        f"rest: u = 0 at the start; cruise: u = {CRUISE_SPEED} m/s, the steady speed with action 0",
    ),
    OpenPoint(
        "pipe_end",
        ("end", "continue"),
        "end",
        "the paper's pipes are longer than its episodes; it does not say what happens at a pipe's end",
        "end: reaching the pipe's far end (progress within 0.5 m of its length) ends the episode, a "
        "terminal state; continue: the episode runs its time, and every decision past the end loses "
        "the pipe (−10)",
    ),
    OpenPoint(
        "rbf",
        FORMS,
        "normalized",
        "eq. 18: ρ = exp(−‖x − c‖²/σ) = Π_j exp(−(x_j − c_ij)²/σ_j)",
        "normalized: Gaussians exp(−d²/(2σ_j²)) divided by their sum; literal: eq. 18 as printed, "
        "unnormalized",
    ),
    OpenPoint(
        "rbf_width",
        WIDTHS,
        "half-spacing",
        '"the width is calculated as half the largest distance between centers" (§4)',
        "half-spacing: σ_j is half the largest gap between neighbouring centres; half-range: half the "
        "distance between the outermost centres",
    ),
    OpenPoint(
        "sigma_unit",
        ("normalized", "rad"),
        "normalized",
        '"The exploration factor starts at σ = 1 and decreases linearly per episode towards σ = 0.01" (§4)',
        "normalized: σ in action units (1 ↦ 90° of waypoint bearing); rad: σ in radians of bearing",
    ),
    OpenPoint(
        "k_update",
        ("every", "positive"),
        "every",
        'eq. 13: k(s) = k(s) + Γ_k(Δ_k); "States that have been visited more often can yield more '
        'trust" (§2.2)',
        "every: k(s) grows at every update of a visited state; positive: only when δ > 0",
    ),
    OpenPoint(
        "k_step",
        ("weights", "k"),
        "weights",
        "eq. 13: k(s) = k(s) + Γ_k(Δ_k), with k(s) an RBF network (§4.1)",
        "weights: the weights move by Δk·φ(s), so k(s) moves by Δk‖φ‖²; k: k(s) itself moves by Δk",
    ),
    OpenPoint(
        "converge_in_view",
        (),
        "0.95",
        '"converged to a successful policy" (§5.1) is not defined',
        "the fraction of decisions, averaged over the last 50 training episodes, that must end with "
        "the pipe in view",
    ),
    OpenPoint(
        "converge_progress_m",
        (),
        "4",
        '"converged to a successful policy" (§5.1) is not defined',
        "the mean arc length along the pipe (m) the last 50 training episodes must reach",
    ),
)

POINTS = {p.key: p for p in OPEN_POINTS}
REPORT_ONLY = ("converge_in_view", "converge_progress_m")  # readings that change no training


@dataclass(frozen=True)
class Readings:
    """One value per open point; the defaults are the project's readings (docs/design.md)."""

    skew_step: str = "gamma"
    skew_sample: str = "location"
    gamma_max: float = 1.0
    skew_unit: str = "deg45"
    start_speed: str = "rest"
    pipe_end: str = "end"
    rbf: str = "normalized"
    rbf_width: str = "half-spacing"
    sigma_unit: str = "normalized"
    k_update: str = "every"
    k_step: str = "weights"
    converge_in_view: float = 0.95
    converge_progress_m: float = 4.0

    @property
    def id(self) -> str:
        """The canonical id: the non-default readings as ``key=value`` joined by ``,``; else ``default``."""
        parts = [f"{k}={_text(v)}" for k, v in self.changes().items()]
        return ",".join(parts) or "default"

    def changes(self) -> dict[str, object]:
        """The readings that differ from the defaults, in the order of :data:`OPEN_POINTS`."""
        return {
            p.key: getattr(self, p.key)
            for p in OPEN_POINTS
            if getattr(self, p.key) != getattr(DEFAULT, p.key)
        }

    @property
    def training(self) -> Readings:
        """The readings a run trains under: these with the report-only ones (:data:`REPORT_ONLY`) reset."""
        return dataclasses.replace(self, **{k: getattr(DEFAULT, k) for k in REPORT_ONLY})


DEFAULT = Readings()


def _text(v: object) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def _value(point: OpenPoint, text: str, source: str) -> object:
    if point.choices:
        if text not in point.choices:
            raise ReadingError(
                f"{source}: '{point.key}' must be one of {', '.join(point.choices)}, got '{text}'"
            )
        return text
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if point.key == "converge_in_view":
        ok, what = 0.0 <= v <= 1.0, "a fraction from 0 to 1"
    elif point.key == "converge_progress_m":
        ok, what = 0.0 <= v < math.inf, "a finite number of metres ≥ 0"
    else:  # gamma_max
        ok, what = 0.0 < v <= 100.0, "a number in (0, 100]"
    if not ok:
        raise ReadingError(f"{source}: '{point.key}' must be {what}, got '{text}'")
    return v


def parse(ids: Iterable[str] | str, base: Readings = DEFAULT, source: str = "reading") -> Readings:
    """Apply reading ids (``key=value``, several joined by ``,``; ``default`` adds nothing) to ``base``.

    Raises:
        ReadingError: an unknown key, a missing ``=``, or a value that is not allowed.
    """
    if isinstance(ids, str):
        ids = [ids]
    changes: dict[str, object] = {}
    for rid in ids:
        for item in str(rid).split(","):
            item = item.strip()
            if item in ("", "default"):
                continue
            key, sep, text = item.partition("=")
            key, text = key.strip(), text.strip()
            if not sep:
                raise ReadingError(f"{source} '{rid}': expected key=value, got '{item}'")
            if key not in POINTS:
                raise ReadingError(f"{source} '{rid}': unknown key '{key}'; known: {', '.join(POINTS)}")
            changes[key] = _value(POINTS[key], text, f"{source} '{rid}'")
    return dataclasses.replace(base, **changes)


def table_markdown() -> str:
    """The open points as a markdown table: key, choices (default first, in bold), paper's words."""
    rows = [
        "| reading | choices (default in bold) | what they mean | the paper's words |",
        "|---|---|---|---|",
    ]
    for p in OPEN_POINTS:
        choices = (
            ", ".join(f"**{c}**" if c == p.default else c for c in p.choices) or f"a number (**{p.default}**)"
        )
        rows.append(f"| `{p.key}` | {choices} | {p.meaning} | {p.paper} |")
    return "\n".join(rows)
