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
    """A packed RBF grid (:attr:`~pipefollow.learners.rbf.RBFGrid.packed`), its form and its input.

    ``slots`` are the simulation state's slots the grid's input is taken from, in order (the
    observation of the learner's named state, :func:`pipefollow.sim.observation.slots`).
    """

    centres: np.ndarray
    offsets: np.ndarray
    widths: np.ndarray
    normalized: bool
    slots: np.ndarray


def features_of(grid, state: str = "paper") -> Features:
    """The grouped argument of an :class:`~pipefollow.learners.rbf.RBFGrid` observing the named ``state``.

    Raises:
        ValueError: the grid's dimensions are not the state's entries.
    """
    from pipefollow.sim.observation import slots

    centres, offsets, widths = grid.packed
    observed = slots(state)
    if observed.shape[0] != grid.ndim:
        raise ValueError(f"state {state!r} has {observed.shape[0]} entries, the RBF grid {grid.ndim}")
    return Features(centres, offsets, widths, grid.form == "normalized", observed)
