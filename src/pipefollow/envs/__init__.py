"""The Gymnasium environments and their pictures.

``shell`` (what both environments share: arguments, spaces, reset options, the start of an
episode, infos, the episode summary), ``env`` (``pipefollow/PipelineFollowing-v0``), ``vector_env``
(its batched vector version), ``vector_batch`` (its sub-environments' pipes in padded arrays and
their compiled decision), ``render`` (the Fig. 2 view) and ``animation``.

They compose the simulator's stages and the camera; they know no learner. May import ``files``,
``sim`` and ``perception``.

Importing this package registers the environment's ids with Gymnasium (:data:`pipefollow.ENV_IDS`,
:func:`pipefollow.register_envs`): the paper's training, its image, vision, random-pipe and
validation configurations, each with its episode's ``max_episode_steps``; so
``gymnasium.make("pipefollow.envs:pipefollow/PipelineFollowingRandom-v0")`` finds one in any process.
"""

from pipefollow import register_envs
from pipefollow.files.compile_cache import configure_numba_cache

configure_numba_cache()  # before any compiled module of this package is decorated
register_envs()
