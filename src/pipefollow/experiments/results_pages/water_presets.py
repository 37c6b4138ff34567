"""The perception page's table of the water presets, generated from the code.

Every field of :class:`~pipefollow.perception.water.Water` with its unit, range and default, and
its value in each preset of :data:`~pipefollow.perception.water.WATER_PRESETS` (**bold**: differs
from the clear water's).
"""

from __future__ import annotations

from pipefollow.experiments.results_pages.markdown import table
from pipefollow.perception.water import CLEAR, RANGES, WATER_PRESETS, Water

UNITS = {
    "turbidity": "1/m",
    "light_falloff": "share",
    "blur": "px",
    "noise": "grey levels",
    "snow": "per frame",
    "burial": "share",
    "growth": "share",
    "width": "px",
    "height": "px",
    "pipe_diameter": "m",
    "altitude": "m",
}


def presets_table() -> str:
    """Every field of :class:`Water` per preset, with the field's unit and range; generated from the code."""
    rows = []
    for field in Water._fields:
        lo, hi, closed = RANGES[field]
        values = []
        for w in WATER_PRESETS.values():
            v = getattr(w, field)
            text = f"{v:g}"
            values.append(f"**{text}**" if v != getattr(CLEAR, field) and w is not CLEAR else text)
        rows.append(
            (
                f"`{field}`",
                UNITS.get(field, ""),
                f"{'[' if closed else '('}{lo:g}, {hi:g}]",
                f"{getattr(Water(), field):g}",
                *values,
            )
        )
    return table(("field", "unit", "range", "default", *(f"`{p}`" for p in WATER_PRESETS)), rows)
