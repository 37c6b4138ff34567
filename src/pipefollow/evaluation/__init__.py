"""Evaluation of controllers on suites of pipes.

``benchmark`` (every suite pipe, beside the heuristic), ``stats`` (IQM, bootstrap confidence
intervals, paired differences) and ``plot``.

May import every layer below: ``files``, ``sim``, ``learners``, ``readings``, ``envs``, ``training``.
"""

from pipefollow.files.compile_cache import configure_numba_cache

configure_numba_cache()  # before any compiled module of this package is decorated
