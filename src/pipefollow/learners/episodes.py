"""What the learners' compiled episode loops group beyond the episode protocol.

The protocol itself (the lost-pipe bookkeeping, the per-episode statistics, the grouped
:class:`~pipefollow.sim.episode.Tracks` and :class:`~pipefollow.sim.episode.Run`) is
:mod:`pipefollow.sim.episode`, shared with the environments and the benchmark. The learners' loops
also take :class:`Features`, the packed RBF grid of the state, a ``NamedTuple`` that numba passes
as one argument.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class Features(NamedTuple):
    """A packed RBF grid (:attr:`~pipefollow.learners.rbf.RBFGrid.packed`) and its form."""

    centres: np.ndarray
    offsets: np.ndarray
    widths: np.ndarray
    normalized: bool


def features_of(grid) -> Features:
    """The grouped argument of an :class:`~pipefollow.learners.rbf.RBFGrid`."""
    centres, offsets, widths = grid.packed
    return Features(centres, offsets, widths, grid.form == "normalized")
