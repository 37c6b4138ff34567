"""Evaluation of controllers on suites of pipes.

``benchmark`` (every suite pipe, beside the heuristic), ``stats`` (IQM, bootstrap confidence
intervals, paired differences), ``compare`` (learners over training seeds × pipes, as rliable
defines it), ``robustness`` (scenario sets, curves against current speed), ``rollouts`` (Minari
datasets), ``vision`` (the detector's report and calibration) and ``plot``.

May import every layer below: ``files``, ``sim``, ``perception``, ``learners``, ``readings``,
``envs``, ``training``.
"""

from pipefollow.files.compile_cache import configure_numba_cache

configure_numba_cache()  # before any compiled module of this package is decorated
