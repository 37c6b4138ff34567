"""Radial-basis-function features on a grid of centres (paper §4, eqs. 17–18).

The network of eq. 17 is linear in the activations ``ρ(‖x − c_i‖)`` of the centres ``c_i`` of a
full grid. The Gaussian of eq. 18 factorizes over the dimensions, so a feature vector is the outer
product of one short activation vector per dimension: 7 · 6 · 7 · 6 = 1,764 state features cost
26 exponentials and 1,764 multiplications.

Two forms (docs/design.md, "RBF network"):

* ``"normalized"`` (default): per dimension ``g_i = exp(−(x − c_i)² / (2σ_j²))``, divided by their
  sum. The sum over the full grid factorizes per dimension, so normalizing each dimension
  normalizes the product: the features sum to 1 and a step size α moves a prediction by at most α.
* ``"literal"``: eq. 18 as printed, per dimension ``exp(−(x − c_i)² / σ_j)``, unnormalized.

``σ_j`` is half the largest spacing between consecutive centres of dimension ``j`` (the paper's
"half the largest distance between centers"; the ``half-range`` width reads it as half the distance
between the outermost centres). Inputs outside the grid are clipped to its range, dimension by
dimension.

The compiled functions :func:`dim_activations` and :func:`grid_features` work on plain arrays
(:attr:`RBFGrid.packed`) so that the agents and the compiled training loop share them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit

FORMS = ("normalized", "literal")
WIDTHS = ("half-spacing", "half-range")  # σ_j: half the largest spacing, or half the span of the centres


def _frozen(a) -> np.ndarray:
    """A read-only float64 copy of ``a``."""
    out = np.array(a, dtype=np.float64)
    out.setflags(write=False)
    return out


# Centres in observation order (x1, y1, x2, v_x) (paper §4; docs/design.md, "centres").
STATE_CENTRES: tuple[np.ndarray, ...] = (
    _frozen([-1.0, -0.8, -0.4, 0.0, 0.4, 0.8, 1.0]),  # x1: far end of the pipe, lateral (m)
    _frozen([0.0, 0.375, 1.125, 1.875, 2.625, 3.0]),  # y1: far end of the pipe, forward (m)
    _frozen([-1.0, -0.8, -0.4, 0.0, 0.4, 0.8, 1.0]),  # x2: near end of the pipe, lateral (m)
    _frozen([-0.25, -0.156, 0.031, 0.219, 0.406, 0.5]),  # v_x: surge speed (m/s)
)
# Centres of what the motion sensors add to the state (beyond the paper; pipefollow.sim.observation):
# five per entry, evenly spaced over the 1st-99th percentiles the heuristic meets on the held-out
# pipes, calm and in a 0.1 m/s current (|v_y|, |r| ≤ 0.33): a state entry multiplies the features by 5.
MEASURED_CENTRES: dict[str, np.ndarray] = {
    "v_y": _frozen([-0.3, -0.15, 0.0, 0.15, 0.3]),  # DVL sway velocity over ground (m/s)
    "r": _frozen([-0.3, -0.15, 0.0, 0.15, 0.3]),  # gyro yaw rate (rad/s)
}
# SARSA's action centres (paper §4.1; the 13th, 0°, is inferred from the stated 22,932 features).
ACTION_CENTRES_DEG = _frozen(
    [-90.0, -81.0, -63.0, -45.0, -27.0, -9.0, 0.0, 9.0, 27.0, 45.0, 63.0, 81.0, 90.0]
)
ACTION_CENTRES = _frozen(ACTION_CENTRES_DEG / 90.0)  # in normalized action units (a = 1 ↦ 90°)


@njit(cache=True)
def dim_activations(x, centres, width, normalized, out):
    """Activations of one dimension's centres at ``x`` into ``out`` (length of ``centres``).

    ``x`` is first clipped to ``[centres[0], centres[-1]]``. Normalized form: Gaussians
    ``exp(−(x − c_i)² / (2σ²))`` divided by their sum; literal form (eq. 18 as printed):
    ``exp(−(x − c_i)² / σ)``.

    Args:
        x: the input coordinate.
        centres: strictly increasing centres of this dimension.
        width: σ of this dimension.
        normalized: normalized (True) or literal (False) form.
        out: float64 array receiving the activations.
    """
    n = centres.shape[0]
    x = min(max(x, centres[0]), centres[n - 1])
    if normalized:
        scale = 1.0 / (2.0 * width * width)
        total = 0.0
        for i in range(n):
            d = x - centres[i]
            g = math.exp(-d * d * scale)
            out[i] = g
            total += g
        # The nearest centre is at most σ away, so total ≥ exp(−1/2): no division by zero.
        inv = 1.0 / total
        for i in range(n):
            out[i] *= inv
    else:
        scale = 1.0 / width
        for i in range(n):
            d = x - centres[i]
            out[i] = math.exp(-d * d * scale)


@njit(cache=True)
def _outer_in_place(act, offsets, j0, j1, dst):
    """Outer product (C order) of the activations of dimensions ``j0 … j1−1`` into ``dst``.

    ``dst[:m]`` holds the product of the dimensions so far; each next dimension spreads entry
    ``i`` to ``i·n_j … i·n_j + n_j − 1``. Walking ``i`` downwards reads every entry before a
    write can reach it, so no second buffer is needed.
    """
    lo = offsets[j0]
    m = offsets[j0 + 1] - lo
    for i in range(m):
        dst[i] = act[lo + i]
    for j in range(j0 + 1, j1):
        lo = offsets[j]
        nj = offsets[j + 1] - lo
        for i in range(m - 1, -1, -1):
            v = dst[i]
            base = i * nj
            for k in range(nj):
                dst[base + k] = v * act[lo + k]
        m *= nj


@njit(cache=True)
def grid_features(x, centres_flat, offsets, widths, normalized, out):
    """Features of the full grid at ``x`` into ``out``: the product of per-dimension activations.

    Eq. 18 is a product over dimensions, so ``out`` (length ``Π n_j``) is the outer product of
    the activation vectors, in C order (the first dimension varies slowest, as ``np.kron`` gives).
    It is built as the outer product of two halves, ``head ⊗ tail``, whose long contiguous inner
    loop the compiler vectorizes (≈4× faster than growing it one dimension at a time).

    Args:
        x: the input, one entry per dimension (trusted: finite, right length).
        centres_flat: the centres of all dimensions, concatenated.
        offsets: dimension ``j``'s centres are ``centres_flat[offsets[j]:offsets[j + 1]]``.
        widths: σ_j per dimension.
        normalized: normalized (True) or literal (False) form.
        out: float64 array of length ``Π n_j`` receiving the features.
    """
    ndim = offsets.shape[0] - 1
    n_act = offsets[ndim]
    half = (ndim + 1) // 2
    n_head = 1
    for j in range(half):
        n_head *= offsets[j + 1] - offsets[j]
    n_tail = 1
    for j in range(half, ndim):
        n_tail *= offsets[j + 1] - offsets[j]
    # One small scratch (26 + 42 + 42 numbers for the state grid): activations, head, tail.
    scratch = np.empty(n_act + n_head + n_tail)
    act = scratch[:n_act]
    for j in range(ndim):
        lo, hi = offsets[j], offsets[j + 1]
        dim_activations(x[j], centres_flat[lo:hi], widths[j], normalized, act[lo:hi])
    if half == ndim:  # one dimension
        for i in range(n_act):
            out[i] = act[i]
        return
    head = scratch[n_act : n_act + n_head]
    tail = scratch[n_act + n_head :]
    _outer_in_place(act, offsets, 0, half, head)
    _outer_in_place(act, offsets, half, ndim, tail)
    for i in range(n_head):
        h = head[i]
        base = i * n_tail
        for k in range(n_tail):
            out[base + k] = h * tail[k]


@njit(cache=True)
def features_if_finite(x, centres_flat, offsets, widths, normalized, out):
    """:func:`grid_features` if every entry of ``x`` is finite (returns True), else False."""
    for j in range(x.shape[0]):
        if not math.isfinite(x[j]):
            return False
    grid_features(x, centres_flat, offsets, widths, normalized, out)
    return True


@dataclass(frozen=True, eq=False)
class RBFGrid:
    """A grid of Gaussian RBF centres and the form of its activations (eqs. 17–18).

    Attributes:
        centres: one strictly increasing array of at least two finite centres per input
            dimension, in the input's order. Stored as read-only float64 arrays.
        form: ``"normalized"`` (docs/design.md; features sum to 1) or ``"literal"`` (eq. 18 as
            printed, unnormalized).
        width: σ_j of each dimension: ``"half-spacing"`` (half the largest spacing between
            consecutive centres) or ``"half-range"`` (half the distance between the outermost).
    """

    centres: tuple[np.ndarray, ...]
    form: str = "normalized"
    width: str = "half-spacing"

    def __post_init__(self) -> None:
        if isinstance(self.centres, np.ndarray | str) or not hasattr(self.centres, "__len__"):
            raise ValueError("centres must be a sequence of 1-D arrays, one per input dimension")
        if len(self.centres) == 0:
            raise ValueError("centres must have at least one dimension")
        dims = []
        for j, c in enumerate(self.centres):
            try:
                a = np.array(c, dtype=np.float64)
            except (TypeError, ValueError):
                raise ValueError(f"centres[{j}] must be numbers") from None
            if a.ndim != 1 or a.size < 2:
                raise ValueError(
                    f"centres[{j}] must be a 1-D array of at least 2 centres, got shape {a.shape}"
                )
            if not np.all(np.isfinite(a)):
                raise ValueError(f"centres[{j}] must be finite")
            if not np.all(np.diff(a) > 0.0):
                raise ValueError(f"centres[{j}] must be strictly increasing")
            a.setflags(write=False)
            dims.append(a)
        if self.form not in FORMS:
            raise ValueError(f"form must be one of {', '.join(map(repr, FORMS))}, got {self.form!r}")
        if self.width not in WIDTHS:
            raise ValueError(f"width must be one of {', '.join(map(repr, WIDTHS))}, got {self.width!r}")
        object.__setattr__(self, "centres", tuple(dims))
        if self.width == "half-spacing":
            widths = _frozen([0.5 * np.max(np.diff(a)) for a in dims])
        else:
            widths = _frozen([0.5 * (a[-1] - a[0]) for a in dims])
        offsets = np.zeros(len(dims) + 1, dtype=np.int64)
        offsets[1:] = np.cumsum([a.size for a in dims])
        offsets.setflags(write=False)
        object.__setattr__(self, "_packed", (_frozen(np.concatenate(dims)), offsets, widths))
        object.__setattr__(self, "_normalized", self.form == "normalized")
        object.__setattr__(self, "_n_features", int(np.prod([a.size for a in dims])))

    @property
    def widths(self) -> np.ndarray:
        """σ_j per dimension (see ``width``)."""
        return self._packed[2]

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of centres per dimension."""
        return tuple(a.size for a in self.centres)

    @property
    def ndim(self) -> int:
        """Number of input dimensions."""
        return len(self.centres)

    @property
    def n_features(self) -> int:
        """Number of features, the product of :attr:`shape`."""
        return self._n_features

    @property
    def packed(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(centres_flat, offsets, widths)`` for :func:`grid_features` (read-only arrays)."""
        return self._packed

    def features(self, x, out: np.ndarray | None = None) -> np.ndarray:
        """φ(x), the grid's features at ``x`` (a new array, or written into ``out``).

        Args:
            x: one finite value per dimension.
            out: optional float64 array of length :attr:`n_features` to write into.

        Returns:
            The features, ``out`` if given.

        Raises:
            ValueError: ``x`` has the wrong number of entries or a non-finite one, or ``out``
                does not fit.
        """
        x = np.asarray(x, dtype=np.float64)
        if x.shape != (len(self.centres),):
            raise ValueError(
                f"x must have {len(self.centres)} entries (one per dimension), got shape {x.shape}"
            )
        if out is None:
            out = np.empty(self._n_features)
        elif not isinstance(out, np.ndarray) or out.shape != (self._n_features,) or out.dtype != np.float64:
            raise ValueError(f"out must be a float64 array of shape ({self._n_features},)")
        c, o, w = self._packed
        if not features_if_finite(x, c, o, w, self._normalized, out):
            raise ValueError(f"x must be finite, got {x}")
        return out

    def to_dict(self) -> dict[str, Any]:
        """Plain lists and strings (JSON-ready): ``{"centres": [[...], ...], "form": ..., "width": ...}``."""
        return {"centres": [a.tolist() for a in self.centres], "form": self.form, "width": self.width}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> RBFGrid:
        """Inverse of :meth:`to_dict`."""
        return cls(tuple(d["centres"]), d.get("form", "normalized"), d.get("width", "half-spacing"))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, RBFGrid):
            return NotImplemented
        return (
            self.form == other.form
            and self.width == other.width
            and len(self.centres) == len(other.centres)
            and all(np.array_equal(a, b) for a, b in zip(self.centres, other.centres, strict=True))
        )

    def __hash__(self) -> int:
        return hash((self.form, self.width, tuple(tuple(a.tolist()) for a in self.centres)))


STATE_GRID = RBFGrid(STATE_CENTRES)  # 1,764 state features


def state_centres(state: str = "paper") -> tuple[np.ndarray, ...]:
    """The grid's centres for the named ``state`` (:mod:`pipefollow.sim.observation`).

    The paper's four dimensions, then :data:`MEASURED_CENTRES` of each entry the state adds
    (1,764 × 5 per entry).
    """
    from pipefollow.sim.observation import components

    extra = components(state)[len(STATE_CENTRES) :]
    return STATE_CENTRES + tuple(MEASURED_CENTRES[c.name] for c in extra)


ACTION_GRID = RBFGrid((ACTION_CENTRES,))  # 13 action features
