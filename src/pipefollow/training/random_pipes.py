"""Training on a new random pipe every episode, in compiled code (``random[:FAMILY]``).

Episode ``e`` draws its pipe from a training family of :mod:`pipefollow.sim.suites`; the pipes of a
chunk of episodes are generated in Python, concatenated into one array with offsets
(:class:`~pipefollow.sim.episode.Tracks`), and the chunk runs in one call of the learner's
compiled loop, episode ``e`` on pipe ``e``.
"""

from __future__ import annotations

import numpy as np

from pipefollow.files.paper_training import EPISODE_SECONDS
from pipefollow.sim.episode import tracks_of
from pipefollow.training.compiled import train_chunks


def train_random_compiled(
    agent, suite, episodes: int, *, pipe_rng: np.random.Generator, **options
) -> np.ndarray:
    """:func:`train_compiled` on a new pipe of the training family ``suite`` every episode.

    Episode ``e``'s pipe is ``suite.draw(pipe_rng, ...)``, drawn in episode order; each chunk's
    pipes are generated before its compiled call and concatenated into one array. Without random
    disturbances the numbers equal :func:`train` on ``PipelineFollowingEnv("random:NAME",
    episode_seconds)`` whose generator ``np_random`` is ``pipe_rng`` (tested). Random disturbances
    (required ``env_rng``) draw from ``env_rng``, a stream of their own, where the environment
    draws them from ``np_random`` between its pipes. With a ``randomization`` each episode draws its
    disturbances from ``env_rng`` before its pipe; with ``pipe_rng`` the same generator as
    ``env_rng`` the numbers then equal the environment's with the randomization (tested). ``options``
    are the keywords of :func:`~pipefollow.training.compiled.train_chunks` with its defaults. Returns
    (episodes, 4) statistics.
    """
    from pipefollow.sim.suites import min_length_for

    min_length = min_length_for(options.get("episode_seconds", EPISODE_SECONDS))

    def tracks_for(lo: int, hi: int):
        return tracks_of([suite.draw(pipe_rng, min_length) for _ in range(lo, hi)])

    return train_chunks(agent, episodes, tracks_for, **options)
