"""The Gymnasium environments and their pictures.

``shell`` (what both environments share: arguments, spaces, reset options, the start of an
episode, infos, the episode summary), ``env`` (``pipefollow/PipelineFollowing-v0``), ``vector_env``
(its batched vector version), ``render`` (the Fig. 2 view) and ``animation``.

They compose the simulator's stages and the camera; they know no learner. May import ``files``,
``sim`` and ``perception``.

Importing this package registers the environment with Gymnasium (:func:`pipefollow.register_envs`),
so that ``gymnasium.make("pipefollow.envs:pipefollow/PipelineFollowing-v0")`` finds it in any process.
"""

from pipefollow import register_envs
from pipefollow.files.compile_cache import configure_numba_cache

configure_numba_cache()  # before any compiled module of this package is decorated
register_envs()
