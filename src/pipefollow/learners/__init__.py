"""Controllers and learners on the simulator's observation.

``rbf`` (eqs. 17–18), ``exploration`` (eqs. 8, 14), ``sums`` (fixed-order dot products),
``heuristic`` and ``los`` (fixed controllers), ``episodes`` (``Features``, the packed RBF grid
the compiled loops take; the episode protocol is ``sim.episode``), ``protocol`` (what a learner
module gives the layers above, the agents' base), the learners ``cacla`` (eqs. 5–8, 10–15; its
update, with the actor's step factor the actor-critic shares, in ``cacla_update``), ``sarsa``
(eq. 3) and ``actor_critic`` (eqs. 9, 11: CACLA's update, loop and agent class with another step
factor), ``registry`` (the learners by name), ``mlp`` (an exported network policy). May import
``files``, ``sim`` and ``perception``.
"""

from pipefollow.files.compile_cache import configure_numba_cache

configure_numba_cache()  # before any compiled module of this package is decorated
