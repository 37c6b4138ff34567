"""The simulator's compiled stages, lowest layer but ``files``.

``pipeline`` (polylines, arc length, projection) and ``suites`` (seeded families of random pipes,
held-out test suites); ``dynamics`` (eq. 16), ``controller`` (the PD waypoint law), ``camera``
(footprint, observation, tracking errors), ``reward`` (eq. 19), ``disturbance`` (current, camera
faults); ``decision`` chains them into one 1-second decision (20 RK4 steps) with the lost-pipe
search. Pure numba-compiled functions of arrays and immutable records. May import ``files`` only.
"""

from pipefollow.files.compile_cache import configure_numba_cache

configure_numba_cache()  # before any compiled module of this package is decorated
