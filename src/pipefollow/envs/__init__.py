"""The Gymnasium environments and their pictures.

``env`` (``pipefollow/PipelineFollowing-v0``), ``vector_env`` (its batched vector version),
``render`` (the Fig. 2 view) and ``animation``.

They compose the simulator's stages; they know no learner. May import ``files`` and ``sim``.
"""

from pipefollow.files.compile_cache import configure_numba_cache

configure_numba_cache()  # before any compiled module of this package is decorated
