"""Distributions over disturbances, drawn per episode: domain randomization and seeded scenarios.

A :class:`Randomization` describes, per kind of disturbance of :mod:`pipefollow.sim.disturbance`,
where an episode's value comes from; :func:`draw` turns it, with a ``numpy.random.Generator``, into
one :class:`~pipefollow.sim.disturbance.Disturbance` — the record the environment and the compiled
loops already take. Ranges are uniform: ``[low, high]`` (a single number means that value always).

* **Current**: speed uniform in ``current_speed`` (m/s), direction uniform in
  ``current_direction_deg`` (towards, clockwise from north; ``[0, 360]`` is every direction); the
  Gauss–Markov variation around them (time constant ``current_time_constant`` s, stationary
  s.d. ``current_speed_sd`` m/s and ``current_direction_sd_deg``) is the same every episode.
* **Camera**: noise s.d. uniform in ``camera_noise`` (m), miss probability uniform in ``miss_prob``.
* **Buried stretches**: the arc-length region ``buried_region_m`` is cut into ``buried_count``
  equal cells; each cell holds, with probability ``buried_prob``, one stretch of length uniform in
  ``buried_length_m``, at a uniform place inside the cell (so stretches are sorted and disjoint).

Random numbers: one draw consumes exactly :data:`DRAWS` uniforms, ``rng.random(DRAWS)``, whatever is
switched on — ``u[0]`` speed, ``u[1]`` direction, ``u[2]`` camera noise, ``u[3]`` miss probability,
then per buried cell ``k`` the three ``u[4 + 3k : 7 + 3k]`` (present, length, place). So the same
generator gives the same episodes on every path, and switching one kind on or off does not shift
the others. :func:`from_uniforms` is the pure map from those numbers to the record.

Presets (:data:`PRESETS`) name typical seas, and ``vision`` the vision camera's calibrated sensor
model (clear water to turbidity 0.2); a TOML table or dict (:func:`from_dict`) can start from
one (``preset = "moderate"``) and change single fields. Bad input (an unknown key or preset, a range
with ``high < low``, a negative speed or spread, a probability outside [0, 1]) raises
:class:`~pipefollow.sim.disturbance.DisturbanceError` with one line naming the field.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from pipefollow.sim.disturbance import MAX_BURIED, NO_BURIAL, NO_DISTURBANCE, Disturbance, DisturbanceError

DRAWS = 4 + 3 * MAX_BURIED  # uniforms consumed by one draw (module docstring)
# the most standard normals a camera reading consumes (current, camera noise, miss, motion sensors)
MAX_NOISE = 2 + 4 + 1 + 2

Range = tuple[float, float]


@dataclass(frozen=True)
class Randomization:
    """Where each episode's disturbances come from (all off by default; ranges are uniform)."""

    current_speed: Range = (0.0, 0.0)  # V_c (m/s)
    current_direction_deg: Range = (0.0, 360.0)  # β_c (degrees towards, clockwise from north)
    current_time_constant: float = 0.0  # T_c (s) of the Gauss–Markov variation; 0 = constant
    current_speed_sd: float = 0.0  # stationary s.d. of V_c around the episode's speed (m/s)
    current_direction_sd_deg: float = 0.0  # stationary s.d. of β_c around its direction (degrees)
    camera_noise: Range = (0.0, 0.0)  # s.d. of the end-point noise (m)
    miss_prob: Range = (0.0, 0.0)  # probability of a missed detection per camera reading
    buried_prob: float = 0.0  # probability that a cell of the buried region holds a stretch
    buried_count: int = 1  # cells of the buried region (1 to MAX_BURIED)
    buried_length_m: Range = (1.0, 1.0)  # length of a buried stretch (m)
    buried_region_m: Range = (5.0, 40.0)  # arc lengths where stretches can lie (m)

    @property
    def is_off(self) -> bool:
        """True when every draw is :data:`~pipefollow.sim.disturbance.NO_DISTURBANCE`."""
        return (
            self.current_speed[1] == 0.0
            and self.camera_noise[1] == 0.0
            and self.miss_prob[1] == 0.0
            and self.buried_prob == 0.0
        )


NONE = Randomization()

PRESETS: dict[str, Randomization] = {
    "none": NONE,
    # a light sea: weak currents from anywhere, a clean camera
    "mild": Randomization(current_speed=(0.0, 0.1), camera_noise=(0.0, 0.02), miss_prob=(0.0, 0.02)),
    # currents up to 0.2 m/s (≈ 40 % of the 0.48 m/s cruise speed) that wander, a noisy camera
    # that misses one reading in 20 at worst, and now and then a buried metre of pipe
    "moderate": Randomization(
        current_speed=(0.0, 0.2),
        current_time_constant=30.0,
        current_speed_sd=0.02,
        current_direction_sd_deg=10.0,
        camera_noise=(0.0, 0.05),
        miss_prob=(0.0, 0.05),
        buried_prob=0.25,
        buried_count=2,
        buried_length_m=(0.5, 1.5),
    ),
    # the vision camera's calibrated sensor model (docs/vision/calibration.json, the detector on the
    # held-out suite): its end-point error s.d. and miss rate from clear water to turbidity 0.2, where
    # the detector still finds the pipe in > 90 % of the frames; no current
    "vision": Randomization(camera_noise=(0.0272, 0.0629), miss_prob=(0.0369, 0.0686)),
    # the far end of the robustness curves: currents up to 0.3 m/s, a poor camera, more burial
    "harsh": Randomization(
        current_speed=(0.0, 0.3),
        current_time_constant=30.0,
        current_speed_sd=0.04,
        current_direction_sd_deg=20.0,
        camera_noise=(0.0, 0.1),
        miss_prob=(0.0, 0.1),
        buried_prob=0.5,
        buried_count=3,
        buried_length_m=(0.5, 2.0),
    ),
}

_RANGES = ("current_speed", "current_direction_deg", "camera_noise", "miss_prob", "buried_length_m",
           "buried_region_m")  # fmt: skip
KEYS = ("preset", *(f.name for f in fields(Randomization)))  # the keys of a TOML table


# ---------------------------------------------------------------------------------------------
# Drawing


def from_uniforms(r: Randomization, u) -> Disturbance:
    """The episode's :class:`Disturbance` for :data:`DRAWS` uniforms ``u`` in [0, 1) (module docstring)."""

    def pick(rng_: Range, x: float) -> float:
        return rng_[0] + float(x) * (rng_[1] - rng_[0])

    starts, ends = list(NO_BURIAL), list(NO_BURIAL)
    used = 0
    if r.buried_prob > 0.0:
        lo, hi = r.buried_region_m
        cell = (hi - lo) / r.buried_count
        for k in range(r.buried_count):
            present, length_u, place_u = u[4 + 3 * k : 7 + 3 * k]
            if present >= r.buried_prob:
                continue
            length = pick(r.buried_length_m, length_u)
            s0 = lo + k * cell + float(place_u) * (cell - length)
            starts[used], ends[used] = s0, s0 + length
            used += 1
    speed = pick(r.current_speed, u[0])
    varying = r.current_time_constant > 0.0 and speed > 0.0
    return Disturbance(
        current_speed=speed,
        current_direction=math.radians(pick(r.current_direction_deg, u[1])) if speed > 0.0 else 0.0,
        current_time_constant=r.current_time_constant if varying else 0.0,
        current_speed_sd=r.current_speed_sd if varying else 0.0,
        current_direction_sd=math.radians(r.current_direction_sd_deg) if varying else 0.0,
        camera_noise=pick(r.camera_noise, u[2]),
        miss_prob=pick(r.miss_prob, u[3]),
        buried_from=tuple(starts),
        buried_to=tuple(ends),
    )


def draw(r: Randomization, rng: np.random.Generator) -> Disturbance:
    """One episode's disturbances: :func:`from_uniforms` of ``rng.random(DRAWS)``."""
    return from_uniforms(r, rng.random(DRAWS))


# ---------------------------------------------------------------------------------------------
# Checks and parsing


def _number(value: Any, name: str, src: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise DisturbanceError(f"{src}{name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise DisturbanceError(f"{src}{name} must be a finite number, got {value}")
    return value


def _range(value: Any, name: str, src: str) -> Range:
    """A number ``x`` (→ ``(x, x)``) or a pair ``[low, high]`` with ``low ≤ high``."""
    if isinstance(value, list | tuple):
        if len(value) != 2:
            raise DisturbanceError(
                f"{src}{name} must be a number or a range [low, high], got {list(value)!r}"
            )
        lo, hi = _number(value[0], f"{name} low", src), _number(value[1], f"{name} high", src)
        if hi < lo:
            raise DisturbanceError(f"{src}{name} must have low ≤ high (a spread ≥ 0), got [{lo:g}, {hi:g}]")
        return lo, hi
    x = _number(value, name, src)
    return x, x


def check(r: Randomization, source: str = "") -> Randomization:
    """``r`` with its ranges as float pairs, checked; raises :class:`DisturbanceError` naming the field."""
    src = f"{source}: " if source else ""
    if not isinstance(r, Randomization):
        raise DisturbanceError(f"{src}randomization must be a Randomization, got {type(r).__name__}")
    values = {name: _range(getattr(r, name), name, src) for name in _RANGES}
    for name in ("current_speed", "camera_noise", "buried_length_m", "buried_region_m"):
        if values[name][0] < 0.0:
            raise DisturbanceError(f"{src}{name} must be ≥ 0, got low {values[name][0]:g}")
    for name in ("current_time_constant", "current_speed_sd", "current_direction_sd_deg"):
        values[name] = _number(getattr(r, name), name, src)
        if values[name] < 0.0:
            raise DisturbanceError(f"{src}{name} must be ≥ 0, got {values[name]:g}")
    lo, hi = values["miss_prob"]
    if lo < 0.0 or hi > 1.0:
        raise DisturbanceError(f"{src}miss_prob must lie in [0, 1], got [{lo:g}, {hi:g}]")
    values["buried_prob"] = _number(r.buried_prob, "buried_prob", src)
    if not 0.0 <= values["buried_prob"] <= 1.0:
        raise DisturbanceError(
            f"{src}buried_prob must be a probability in [0, 1], got {values['buried_prob']:g}"
        )
    count = r.buried_count
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_BURIED:
        raise DisturbanceError(f"{src}buried_count must be an integer from 1 to {MAX_BURIED}, got {count!r}")
    if (values["current_speed_sd"] > 0.0 or values["current_direction_sd_deg"] > 0.0) and values[
        "current_time_constant"
    ] <= 0.0:
        raise DisturbanceError(f"{src}current_time_constant must be > 0 (s) for a varying current")
    cell = (values["buried_region_m"][1] - values["buried_region_m"][0]) / count
    if values["buried_prob"] > 0.0 and (
        values["buried_length_m"][1] > cell or values["buried_length_m"][0] <= 0.0
    ):
        raise DisturbanceError(
            f"{src}buried_length_m must lie in (0, {cell:g}] m, the region's length over buried_count"
        )
    return replace(r, **values)


def preset(name: Any, source: str = "randomization") -> Randomization:
    """The preset called ``name``; raises :class:`DisturbanceError` listing the presets otherwise."""
    if not isinstance(name, str) or name not in PRESETS:
        raise DisturbanceError(f"{source}: unknown preset {name!r} (choose from {', '.join(PRESETS)})")
    return PRESETS[name]


def from_dict(d: Mapping[str, Any], source: str = "randomization") -> Randomization:
    """A randomization from a TOML table or JSON object with the keys :data:`KEYS`.

    ``preset`` (optional) is the starting point, the other keys change it; ranges are ``[low, high]``
    or a number. Example::

        [randomization]
        preset = "moderate"
        current_speed = [0.05, 0.25]   # m/s
        miss_prob = 0.02

    Raises:
        DisturbanceError: an unknown key or preset or a value out of range, named with ``source``.
    """
    if not isinstance(d, Mapping):
        raise DisturbanceError(f"{source}: must be a table, got {type(d).__name__}")
    unknown = sorted(set(d) - set(KEYS))
    if unknown:
        raise DisturbanceError(f"{source}: unknown key '{unknown[0]}'; allowed: {', '.join(KEYS)}")
    base = preset(d["preset"], source) if "preset" in d else NONE
    changes = {k: v for k, v in d.items() if k != "preset"}
    return check(replace(base, **changes), source)


def resolve(spec: Any, source: str = "randomization") -> Randomization:
    """A preset name or a table (:func:`from_dict`) → a checked :class:`Randomization`."""
    if isinstance(spec, Randomization):
        return check(spec, source)
    if isinstance(spec, Mapping):
        return from_dict(spec, source)
    return check(preset(spec, source), source)


NOT_BOTH = "give a disturbance or a randomization of the disturbances, not both"


def both_given(disturbance: Any, randomization: Any) -> bool:
    """Whether a fixed disturbance comes with a randomization, which draws each episode's own.

    Args:
        disturbance: a :class:`~pipefollow.sim.disturbance.Disturbance` (``NO_DISTURBANCE`` is
            none), a table of one (an empty table is none) or None.
        randomization: a randomization in any form :func:`resolve` takes, or None.
    """
    if randomization is None or disturbance is None or disturbance == NO_DISTURBANCE:
        return False
    return not (isinstance(disturbance, Mapping) and not disturbance)


def check_not_both(disturbance: Any, randomization: Any) -> None:
    """Refuse a fixed disturbance together with a randomization (:func:`both_given`).

    Raises:
        DisturbanceError: both are given.
    """
    if both_given(disturbance, randomization):
        raise DisturbanceError(NOT_BOTH)


def to_dict(r: Randomization) -> dict[str, Any]:
    """The table of ``r`` (inverse of :func:`from_dict`), ranges as lists."""
    return {f.name: list(v) if isinstance(v := getattr(r, f.name), tuple) else v for f in fields(r)}
