"""The paper's training run in numbers: how many episodes, and how long each lasts.

Here, at the bottom of the package, because every layer reads these defaults (the environment,
training, evaluation, the experiment files) and so do the command line's help texts, which must
not load numba: the module imports nothing.
"""

TRAINING_EPISODES = 500  # training episodes of a run, and of each phase of a trial (paper §4.1)
EPISODE_SECONDS = 20.0  # length of a training episode (s): 20 decisions of 1 s (paper §4)
TEST_EPISODE_SECONDS = 60.0  # the validation episode (paper §4.2, Table 1); every episode on a test pipe
TRAINING_PIPELINES = ("paper-left", "paper-right")  # the paper's training pipes (§4.1, §4.2)
