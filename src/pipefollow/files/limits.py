"""Bounds that keep a run finite, checked where the user's numbers come in.

Here, at the bottom of the package, because the environments, the experiment files and the
command line's options all check against them, and the options are built without loading numba:
the module imports nothing.
"""

MAX_EPISODE_SECONDS = 86_400.0  # the longest episode (s): a day at sea, far beyond any use
MAX_EPISODES = 10_000_000  # the most episodes of a training run or a phase
MAX_REPEATS = 100_000  # the most repeats (seeds) of an experiment
