"""Training: episodes, compiled loops, policy files, run outputs and the deep-RL baselines.

Episodes through an environment, training in a learner's compiled loop (one pipe and a new random
pipe per episode), ``train_phases`` (the one way the command line and experiment trials train),
policy files, a run's output files, and the deep-RL baselines (``deep``, optional extra).

May import ``files``, ``sim``, ``perception``, ``learners``, ``readings`` and ``envs``.
"""

from pipefollow.files.compile_cache import configure_numba_cache

configure_numba_cache()  # before any compiled module of this package is decorated
