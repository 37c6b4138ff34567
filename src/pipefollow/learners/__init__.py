"""Controllers and learners on the simulator's observation.

``rbf`` (eqs. 17–18), ``exploration`` (eqs. 8, 14), ``sums`` (fixed-order dot products),
``heuristic`` and ``los`` (fixed controllers), ``cacla`` (eqs. 5–8, 10–15), ``sarsa`` (eq. 3),
``mlp`` (an exported network policy). May import ``files`` and ``sim``.
"""

from pipefollow.files.compile_cache import configure_numba_cache

configure_numba_cache()  # before any compiled module of this package is decorated
