"""Training on a new random pipe every episode, in compiled code (``random[:FAMILY]``).

Episode ``e`` draws its pipe from a training family of :mod:`pipefollow.sim.suites`; the pipes of a
chunk of episodes are generated in Python, concatenated into one array with offsets, and the
chunk runs in one compiled call that reuses the one-pipe episode loops of
:mod:`pipefollow.training.compiled` pipe by pipe.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numba import njit

from pipefollow.learners import cacla as cacla_mod
from pipefollow.sim import decision as sim
from pipefollow.training.compiled import _cacla_episodes, _sarsa_episodes, compiled_setup


@njit(cache=True)
def _cacla_random_episodes(
    w, hp, points_all, cum_all, offsets, starts, simp, sigmas, n_decisions, centres, grid_offsets, widths,
    normalized, rng, stats, env_rng, dz,
):  # fmt: skip
    for e in range(sigmas.shape[0]):
        a, b = offsets[e], offsets[e + 1]
        _cacla_episodes(
            w, hp, points_all[a:b], cum_all[a:b], starts[e], simp, sigmas[e : e + 1], n_decisions, centres,
            grid_offsets, widths, normalized, rng, stats[e : e + 1], env_rng, dz,
        )  # fmt: skip


@njit(cache=True)
def _sarsa_random_episodes(
    W, alpha, discount, search_actions, search_psi, a_centres, a_width, a_normalized, points_all, cum_all,
    offsets, starts, simp, sigmas, n_decisions, centres, grid_offsets, widths, normalized, rng, stats,
    env_rng, dz,
):  # fmt: skip
    for e in range(sigmas.shape[0]):
        a, b = offsets[e], offsets[e + 1]
        _sarsa_episodes(
            W, alpha, discount, search_actions, search_psi, a_centres, a_width, a_normalized, points_all[a:b],
            cum_all[a:b], starts[e], simp, sigmas[e : e + 1], n_decisions, centres, grid_offsets, widths,
            normalized, rng, stats[e : e + 1], env_rng, dz,
        )  # fmt: skip


def train_random_compiled(
    agent,
    suite,
    episodes: int,
    *,
    pipe_rng: np.random.Generator,
    episode_seconds: float = 20.0,
    sigma_start: float = 1.0,
    sigma_end: float = 0.01,
    params: sim.SimParams = sim.PAPER_SIM,
    progress: Callable[[int], None] | None = None,
    chunk: int = 50,
    env_rng: np.random.Generator | None = None,
) -> np.ndarray:
    """:func:`train_compiled` on a new pipe of the training family ``suite`` every episode.

    Episode ``e``'s pipe is ``suite.draw(pipe_rng, ...)``, drawn in episode order; each chunk's
    pipes are generated before its compiled call and concatenated into one array. Without random
    disturbances the numbers equal :func:`train` on ``PipelineFollowingEnv("random:NAME",
    episode_seconds)`` whose generator ``np_random`` is ``pipe_rng`` (tested). Random disturbances
    (required ``env_rng``) draw from ``env_rng``, a stream of their own, where the environment
    draws them from ``np_random`` between its pipes. Returns (episodes, 4) statistics.
    """
    from pipefollow.sim.suites import min_length_for

    run = compiled_setup(agent, episodes, episode_seconds, sigma_start, sigma_end, params, env_rng)
    sigmas, n_decisions, stats, simp, env_rng, dz = run
    min_length = min_length_for(episode_seconds)
    centres, offsets, widths = agent.grid.packed
    normalized = agent.grid.form == "normalized"
    for lo in range(0, episodes, max(1, chunk)):
        hi = min(episodes, lo + max(1, chunk))
        pipes = [suite.draw(pipe_rng, min_length) for _ in range(lo, hi)]
        pipe_offsets = np.zeros(len(pipes) + 1, dtype=np.int64)
        pipe_offsets[1:] = np.cumsum([len(p.points) for p in pipes])
        pts = np.concatenate([p.points for p in pipes])
        cum = np.concatenate([p.cumulative for p in pipes])
        starts = np.array([[p.points[0, 0], p.points[0, 1], p.start_heading] for p in pipes])
        sig, out = sigmas[lo:hi], stats[lo:hi]
        if isinstance(agent, cacla_mod.Cacla):
            _cacla_random_episodes(
                agent.weights, cacla_mod.pack(agent.params), pts, cum, pipe_offsets, starts, simp, sig,
                n_decisions, centres, offsets, widths, normalized, agent.rng, out, env_rng, dz,
            )  # fmt: skip
        else:
            ac, _, aw = agent.action_grid.packed
            _sarsa_random_episodes(
                agent.weights, agent.params.alpha, agent.params.discount, agent.search_actions,
                agent.search_psi, ac, float(aw[0]), agent.action_grid.form == "normalized", pts, cum,
                pipe_offsets, starts, simp, sig, n_decisions, centres, offsets, widths, normalized,
                agent.rng, out, env_rng, dz,
            )  # fmt: skip
        if progress is not None:
            progress(hi)
    agent.begin_episode(sigmas[-1] if episodes else sigma_start)
    return stats
