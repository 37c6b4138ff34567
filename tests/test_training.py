"""The compiled training path equals the Gymnasium-environment path, number for number."""

import numpy as np
import pytest

from pipefollow.agents import make_agent
from pipefollow.env import PipelineFollowingEnv
from pipefollow.pipeline import builtin
from pipefollow.training import train, train_compiled

KINDS = {
    "cacla": dict(algorithm="cacla"),
    "cacla-skew": dict(algorithm="cacla", skew_deg=45.0),
    "supervised-skew": dict(algorithm="cacla", skew_deg=22.5, supervised=True),
    "sarsa": dict(algorithm="sarsa"),
}


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("pipeline", ["paper-left", "paper-validation"])
def test_compiled_path_equals_environment_path(kind, pipeline):
    pipe = builtin(pipeline)
    episodes = 12
    a = make_agent(rng=np.random.default_rng(3), **KINDS[kind])
    b = make_agent(rng=np.random.default_rng(3), **KINDS[kind])
    stats_env = train(PipelineFollowingEnv(pipe, 20), a, episodes)
    stats_fast = train_compiled(b, pipe, episodes, chunk=5)
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
    # both consumed the same random numbers
    assert a.rng.standard_normal() == b.rng.standard_normal()


def test_equivalence_covers_lost_pipe_updates():
    # with full exploration the AUV loses the pipe: the semi-Markov path must be exercised
    pipe = builtin("paper-left")
    a = make_agent("cacla", rng=np.random.default_rng(0))
    b = make_agent("cacla", rng=np.random.default_rng(0))
    stats_env = train(PipelineFollowingEnv(pipe, 20), a, 10, sigma_start=1.0, sigma_end=1.0)
    stats_fast = train_compiled(b, pipe, 10, sigma_start=1.0, sigma_end=1.0)
    assert stats_env[:, 3].sum() > 0  # some time was spent with the pipe lost
    np.testing.assert_allclose(stats_fast, stats_env, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-9)
