"""The vector environment's batch: each sub-environment's pipe in padded arrays, one compiled decision of all.

:class:`PipeBatch` holds the sub-environments' pipeline sources and pipes, and their points and
arc lengths in arrays padded to the longest pipe (grown when a longer one is loaded): the form
that the compiled :func:`step_batch` takes, one call for the decision of every sub-environment
(:class:`~pipefollow.envs.vector_env.PipelineFollowingVectorEnv`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pipefollow.sim import episode as ep
from pipefollow.sim.pipe_names import is_points, pipeline_source
from pipefollow.sim.pipeline import Pipeline


@njit(cache=True)
def step_batch(states, actions, points, cum, n_points, packed, z, skip, rewards, books, max_n, ends):
    """One decision of every sub-environment not in ``skip``, counted in its book.

    ``packed[i]`` is sub-environment i's packed parameters (its own disturbances under a
    randomization), ``books[i]`` its episode's book (:mod:`pipefollow.sim.episode`).

    Actions are clipped to [-1, 1]; returns False (stepping nothing) if one is NaN. Writes the
    rewards and, in ``ends``, how each sub-environment's episode stands (``pipefollow.sim.episode.end_of``:
    0 going on, or the code of the end this decision reached).
    """
    for i in range(states.shape[0]):
        if math.isnan(actions[i]):
            return False
    for i in range(states.shape[0]):
        ends[i] = ep.GOES_ON
        if skip[i]:
            rewards[i] = 0.0
            continue
        n = n_points[i]
        a = min(1.0, max(-1.0, actions[i]))
        pts, cm = points[i, :n], cum[i, :n]
        rewards[i], ends[i] = ep.decide_packed(states[i], a, pts, cm, packed[i], z[i], books[i], max_n)
    return True


def pipeline_specs(pipeline, n: int) -> list:
    """One pipeline spec per sub-environment: ``pipeline`` for all, or its list of ``n``."""
    one = is_points(pipeline) or not isinstance(pipeline, list | tuple)
    specs = [pipeline] * n if one else list(pipeline)
    if len(specs) != n:
        raise ValueError(f"pipeline lists {len(specs)} specs for {n} sub-environments")
    return specs


class PipeBatch:
    """Each sub-environment's pipeline source (``suites``) and pipe (``pipelines``), and the pipes padded.

    ``points[i, :n_points[i]]`` and ``cum[i, :n_points[i]]`` are sub-environment i's points and
    their arc lengths (:meth:`of`); the rest of the row is padding.

    Args:
        specs: one pipeline spec per sub-environment (:func:`pipeline_specs`).
        seconds: the episode's length, for suite pipes (:func:`pipeline_source`).
    """

    def __init__(self, specs: list, seconds: float | None = None) -> None:
        n = len(specs)
        sources = [pipeline_source(s, seconds) for s in specs]
        self.suites = [suite for suite, _ in sources]
        self.pipelines = [pipe for _, pipe in sources]
        cap = max(len(p.points) for p in self.pipelines)
        self.points = np.zeros((n, cap, 2))
        self.cum = np.zeros((n, cap))
        self.n_points = np.zeros(n, dtype=np.int64)
        for i, pipe in enumerate(self.pipelines):
            self.load(i, pipe)

    def load(self, i: int, pipe: Pipeline) -> None:
        """Make ``pipe`` sub-environment ``i``'s, growing the padded arrays of all if it is longer."""
        m = len(pipe.points)
        if m > self.points.shape[1]:  # grow the buffers of all sub-environments
            n, cap = self.points.shape[0], max(m, 2 * self.points.shape[1])
            points, cum = np.zeros((n, cap, 2)), np.zeros((n, cap))
            points[:, : self.points.shape[1]] = self.points
            cum[:, : self.cum.shape[1]] = self.cum
            self.points, self.cum = points, cum
        self.points[i, :m] = pipe.points
        self.cum[i, :m] = pipe.cumulative
        self.n_points[i] = m
        self.pipelines[i] = pipe

    def of(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Sub-environment ``i``'s points and their arc lengths (views into the padded arrays)."""
        m = self.n_points[i]
        return self.points[i, :m], self.cum[i, :m]
