"""The water and camera settings of the rendered camera image: one frozen, validated record.

Every field is checked when the record is made: a NaN or a value outside its range raises a
one-line :class:`WaterError` (a ``ValueError``) naming the field. Presets for the closed-loop
table: :data:`WATER_PRESETS` (``clear``, ``moderate``, ``turbid``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, NamedTuple


class WaterError(ValueError):
    """A water or camera setting that cannot be used; the message names the field."""


class Water(NamedTuple):
    """Water and camera settings of the rendered image (units and ranges in the comments)."""

    turbidity: float = 0.1  # beam attenuation c (1/m), [0, 3]: contrast × exp(−c·path), veil rises
    light_falloff: float = 0.5  # share of the vehicle's light lost at the footprint's corners, [0, 0.95]
    blur: float = 0.6  # Gaussian blur σ of the optics (pixels), [0, 5]; turbid water adds scattering
    noise: float = 3.0  # sensor noise s.d. (grey levels), [0, 64]
    snow: float = 4.0  # marine-snow particles per frame (Poisson mean), [0, 200]
    burial: float = 0.0  # share of the pipe's width covered by sand, [0, 0.8]
    growth: float = 0.0  # share of the pipe's surface covered by marine growth, [0, 1]
    width: int = 64  # image columns (x from −1 m at column 0 to +1 m), [16, 1024]
    height: int = 96  # image rows (y from 3 m at row 0 to 0 m), [16, 1024]
    pipe_diameter: float = 0.25  # pipe diameter (m), (0.02, 1]
    altitude: float = 2.0  # camera height above the seabed (m), [0.5, 10]: the light's path length


_RANGES = {
    "turbidity": (0.0, 3.0, True),
    "light_falloff": (0.0, 0.95, True),
    "blur": (0.0, 5.0, True),
    "noise": (0.0, 64.0, True),
    "snow": (0.0, 200.0, True),
    "burial": (0.0, 0.8, True),
    "growth": (0.0, 1.0, True),
    "width": (16, 1024, True),
    "height": (16, 1024, True),
    "pipe_diameter": (0.02, 1.0, False),
    "altitude": (0.5, 10.0, True),
}

# every field's range as (low, high, low included), for tables of the settings
RANGES: Mapping[str, tuple[float, float, bool]] = MappingProxyType(_RANGES)

CLEAR = Water()
WATER_PRESETS = {
    "clear": CLEAR,
    "moderate": Water(turbidity=0.2, blur=0.9, noise=5.0, snow=12.0),
    "turbid": Water(turbidity=0.25, blur=1.2, noise=7.0, snow=25.0),
}


# the fields a preset sets (the others stay at the defaults of :class:`Water`), in --help and describe()
PRESET_FIELDS = tuple(
    f for f in Water._fields if any(getattr(w, f) != getattr(CLEAR, f) for w in WATER_PRESETS.values())
)
# how describe() words a field: (name before the value or "", unit after it)
_WORDS = {
    "turbidity": ("turbidity ", "/m"),
    "blur": ("blur ", " px"),
    "noise": ("noise ", " grey levels"),
    "snow": ("", " snow particles/frame"),
    "burial": ("", " of the width buried"),
    "growth": ("", " of the surface grown over"),
    "light_falloff": ("light falloff ", ""),
    "pipe_diameter": ("pipe ", " m"),
    "altitude": ("altitude ", " m"),
}


def describe(w: Water) -> str:
    """One line: the preset whose fields ``w`` has (or ``custom``) and the settings that make the image.

    The preset fields (:data:`PRESET_FIELDS`) always, the others where they differ from the default
    record, e.g. ``water moderate: turbidity 0.2/m, blur 0.9 px, noise 5 grey levels, snow 12 snow
    particles/frame``.
    """
    name = next(
        (k for k, p in WATER_PRESETS.items() if all(getattr(p, f) == getattr(w, f) for f in PRESET_FIELDS)),
        "custom",
    )
    parts = []
    for f in Water._fields:
        v = getattr(w, f)
        if f in PRESET_FIELDS or v != getattr(CLEAR, f):
            if f in ("width", "height"):
                continue
            before, after = _WORDS[f]
            parts.append(f"{before}{v:g}{after}")
    if (w.width, w.height) != (CLEAR.width, CLEAR.height):
        parts.append(f"{w.width}×{w.height} px image")
    return f"water {name}: " + ", ".join(parts)


def make_water(**fields: Any) -> Water:
    """A checked :class:`Water` from keyword fields (the others at their defaults)."""
    unknown = sorted(set(fields) - set(Water._fields))
    if unknown:
        raise WaterError(f"unknown water setting(s) {unknown}; allowed: {', '.join(Water._fields)}")
    return check(Water(**fields))


def check(w: Water) -> Water:
    """``w`` itself if every field is a number in its range; else a one-line :class:`WaterError`."""
    for name, (lo, hi, closed_low) in _RANGES.items():
        value = getattr(w, name)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise WaterError(f"water setting {name} must be a number, got {value!r}")
        if name in ("width", "height") and value != int(value):
            raise WaterError(f"water setting {name} must be a whole number of pixels, got {value}")
        low_ok = value >= lo if closed_low else value > lo
        if not (math.isfinite(value) and low_ok and value <= hi):
            bracket = "[" if closed_low else "("
            raise WaterError(f"water setting {name} must be in {bracket}{lo}, {hi}], got {value}")
    return w._replace(width=int(w.width), height=int(w.height))


def water_from(spec: Water | str | Mapping[str, Any] | None) -> Water:
    """A checked record from a record, a preset name or a mapping (``preset`` key allowed)."""
    if spec is None:
        return CLEAR
    if isinstance(spec, Water):
        return check(spec)
    if isinstance(spec, str):
        if spec not in WATER_PRESETS:
            raise WaterError(f"water preset {spec!r}: unknown (choose from {', '.join(WATER_PRESETS)})")
        return WATER_PRESETS[spec]
    if isinstance(spec, Mapping):
        fields = dict(spec)
        base = water_from(fields.pop("preset", None))
        unknown = sorted(set(fields) - set(Water._fields))
        if unknown:
            raise WaterError(f"unknown water setting(s) {unknown}; allowed: {', '.join(Water._fields)}")
        return check(base._replace(**fields))
    raise WaterError(f"water must be a preset name, a mapping or a Water record, got {type(spec).__name__}")
