"""Parameter records as flat float arrays for compiled code, with offsets computed from field names.

A ``NamedTuple`` handed from Python to a compiled function costs microseconds of argument checking
per call; a float64 array costs a fraction of that. :func:`pack` flattens a record (nested records
and tuple fields in field order) and :func:`offsets` says where each field starts, so the compiled
``unpack`` functions read fields by name (``a[OFFSET["dt"]]``), never by a hand-counted index.
"""

from __future__ import annotations

import numpy as np


def _is_record(value) -> bool:
    return isinstance(value, tuple) and hasattr(value, "_fields")


def size(value) -> int:
    """Floats that ``value`` takes when packed: 1 for a number, its length for a tuple, recursively."""
    if isinstance(value, tuple):
        return sum(size(v) for v in value)
    return 1


def offsets(record) -> dict[str, int]:
    """Field name → where the field starts in :func:`pack`'s array (sizes from ``record``'s values)."""
    out, at = {}, 0
    for name in record._fields:
        out[name] = at
        at += size(getattr(record, name))
    return out


def flatten(value) -> list[float]:
    """``value`` (a record, a tuple or a number) as a flat list of floats, in field order."""
    if isinstance(value, tuple):
        return [x for v in value for x in flatten(v)]
    return [float(value)]


def pack(record) -> np.ndarray:
    """``record`` as a float64 array (bools as 0/1, ints as floats)."""
    if not _is_record(record):
        raise TypeError(f"pack takes a NamedTuple record, got {type(record).__name__}")
    return np.array(flatten(record), dtype=np.float64)
