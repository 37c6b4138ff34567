"""Episodes and training: through the Gymnasium environment, and as one compiled loop.

Both paths follow the same protocol (docs/design.md):

* one decision per second; the agent acts only while the pipe is in view, otherwise the search
  behaviour flies the AUV and the agent's action is ignored;
* a decision whose next state sees the pipe gives an ordinary one-step update; while the pipe is
  lost no update is made, and when it is back in view (or the episode ends) one semi-Markov
  update ``δ = Σ γ^j r_j + γ^n V(s_reacq) − V(s)`` is made from the last state in view;
* the 20-s end is a time limit: agents bootstrap from the last state; the pipe's far end (reading
  ``pipe_end=end``, :func:`pipefollow.sim.episode.end_of`) is a terminal state: nothing to bootstrap;
* exploration σ falls linearly from ``sigma_start`` to ``sigma_end`` over the episodes.

The compiled path (:func:`train_compiled`) runs the agent's learner's own compiled loop
(the protocol of :mod:`pipefollow.sim.episode`), which composes the same compiled stage and update
functions as the environment and agent classes, consumes the same random numbers in the same
order, and so gives the same trajectory, returns and weights (tested to 1e-9). The agent's
generator drives exploration; a second generator, ``env_rng``, plays the environment's
``np_random``: one block of standard normals per camera reading (the reset's and each decision's)
for the random disturbances. The compiled path starts without start noise, for which the
environment would draw uniforms.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pipefollow.files.paper_training import EPISODE_SECONDS
from pipefollow.learners.exploration import SIGMA_END, SIGMA_START, sigma_schedule
from pipefollow.learners.registry import learner_of
from pipefollow.sim import decision as sim
from pipefollow.sim import episode as ep
from pipefollow.sim.episode import TRAINING_STAT_NAMES, Run, Tracks, no_poses, tracks_of
from pipefollow.sim.pipeline import Pipeline


@dataclass(frozen=True)
class EpisodeStats:
    """What one episode gave.

    Attributes:
        ret: accumulated reward.
        pipe_in_view: fraction of decisions that ended with the pipe in view.
        progress_m: arc length reached along the pipe (m).
        time_lost_s: time with the pipe out of view at decision ends (s).
        poses: (decisions + 1, 3) poses (x, y, ψ) if recorded, else None.
        sum_e_dist2: Σ e_dist² over the decisions that ended with the pipe in view (m²).
        n_in_view: number of those decisions.
        swum_m: distance covered over ground, decision end to decision end (m).
        back_m: progress lost in decisions that ended with the pipe in view (m): following backwards.
    """

    ret: float
    pipe_in_view: float
    progress_m: float
    time_lost_s: float
    poses: np.ndarray | None = None
    sum_e_dist2: float = 0.0
    n_in_view: int = 0
    swum_m: float = 0.0
    back_m: float = 0.0

    @classmethod
    def from_row(cls, row: np.ndarray, poses: np.ndarray | None = None) -> EpisodeStats:
        """The statistics of a row of :data:`pipefollow.sim.episode.STAT_NAMES`, and the poses."""
        return cls(float(row[ep.STAT_RETURN]), float(row[ep.STAT_IN_VIEW]), float(row[ep.STAT_PROGRESS]),
                   float(row[ep.STAT_TIME_LOST]), poses, float(row[ep.STAT_SUM_E2]),
                   int(row[ep.STAT_N_SEEN]), float(row[ep.STAT_SWUM]), float(row[ep.STAT_BACK]))  # fmt: skip

    def as_full_row(self) -> tuple[float, ...]:
        """The columns of :data:`pipefollow.sim.episode.STAT_NAMES`."""
        row = [0.0] * len(ep.STAT_NAMES)
        row[ep.STAT_RETURN], row[ep.STAT_IN_VIEW] = self.ret, self.pipe_in_view
        row[ep.STAT_PROGRESS], row[ep.STAT_TIME_LOST] = self.progress_m, self.time_lost_s
        row[ep.STAT_SUM_E2], row[ep.STAT_N_SEEN] = self.sum_e_dist2, float(self.n_in_view)
        row[ep.STAT_SWUM], row[ep.STAT_BACK] = self.swum_m, self.back_m
        return tuple(row)

    def as_row(self) -> tuple[float, ...]:
        """A training run's columns (``sim.episode.TRAINING_STAT_NAMES``): return to time lost."""
        return self.as_full_row()[: len(TRAINING_STAT_NAMES)]


def run_episode(
    env,
    agent,
    *,
    learn: bool = False,
    explore: bool = False,
    sigma: float = 0.0,
    seed: int | None = None,
    options: dict | None = None,
) -> EpisodeStats:
    """Run one episode of ``agent`` in a :class:`~pipefollow.envs.env.PipelineFollowingEnv`.

    With ``learn`` the agent is updated as described in the module docstring. The statistics
    count what the exact camera saw (its ``true_`` infos under the vision camera).
    """
    agent.begin_episode(sigma if explore else 0.0)
    obs, info = env.reset(seed=seed, options=options)
    decision_s = sim.decision_seconds(env.unwrapped.params)
    gamma = agent.discount if learn else 0.0
    book = ep.new_book()
    pending = None  # the observation and action of the pending transition (its rewards in book)
    done = False
    while not done:
        visible = bool(info["pipe_in_view"])
        a = agent.act(obs, explore=explore) if visible else 0.0
        next_obs, r, terminated, truncated, info = env.step([a])
        in_view = bool(info.get("true_pipe_in_view", info["pipe_in_view"]))
        e_dist = float(info.get("true_e_dist", info["e_dist"])) if in_view else 0.0
        ep.tally(book, r, in_view, e_dist)
        done = terminated or truncated
        if learn:
            if visible:
                pending = (obs, a)
            ep.carry(book, visible, r, gamma)
            if ep.due(book, bool(info["pipe_in_view"]), done):
                discount = 0.0 if terminated else book[ep.DISC]
                agent.update(pending[0], pending[1], book[ep.ACC], next_obs, discount)
                book[ep.PENDING] = 0.0
        obs = next_obs
    trail = np.array(env.unwrapped.trail)
    travelled = env.unwrapped.book  # the distances the environment's decisions measured
    book[ep.SWUM], book[ep.BACK] = travelled[ep.SWUM], travelled[ep.BACK]
    return EpisodeStats.from_row(ep.statistics_row(book, info["progress_m"], decision_s), trail)


def train(
    env,
    agent,
    episodes: int,
    *,
    sigma_start: float = SIGMA_START,
    sigma_end: float = SIGMA_END,
    callback: Callable[[int, EpisodeStats], None] | None = None,
    seed: int | None = None,
) -> np.ndarray:
    """Train ``agent`` for ``episodes`` episodes in ``env``; returns (episodes, 4) statistics.

    ``seed`` seeds the environment's first reset (None: it goes on with its generator).

    Raises:
        ValueError: ``env`` observes another named state than ``agent`` (``env.setup.state``).
    """
    observed = getattr(getattr(env, "setup", None), "state", None)
    if observed is not None and observed != getattr(agent, "state", observed):
        raise ValueError(f"the environment observes state {observed!r}, the agent {agent.state!r}")
    stats = np.empty((episodes, len(TRAINING_STAT_NAMES)))
    for e, sigma in enumerate(sigma_schedule(episodes, sigma_start, sigma_end)):
        first = seed if e == 0 else None
        stats_e = run_episode(env, agent, learn=True, explore=True, sigma=float(sigma), seed=first)
        stats[e] = stats_e.as_row()
        if callback is not None:
            callback(e, stats_e)
    return stats


# ---------------------------------------------------------------------------------------------
# The compiled path: each learner's own episode loop (the protocol of pipefollow.sim.episode)


def compiled_setup(agent, episodes, episode_seconds, sigma_start, sigma_end, params, env_rng):
    """What every compiled training loop needs, after checking the agent and the disturbances.

    Returns ``(the agent's learner, σ per episode, decisions per episode, an empty (episodes, 4)
    statistics array, packed parameters, the disturbances' generator, an array for their normals)``.

    Raises:
        ValueError: random disturbances without a seeded ``env_rng``.
        TypeError: an agent without a compiled loop, or supervised by another than the heuristic.
    """
    from pipefollow.sim.disturbance import check, noise_count

    kind = learner_of(agent)
    if kind is None:
        raise TypeError(f"no compiled training loop for {type(agent).__name__}")
    kind.check(agent)
    check(params.disturbance)
    dz = np.zeros(noise_count(params.disturbance))
    if env_rng is None:
        if dz.size:
            raise ValueError("params.disturbance has random parts: pass a seeded env_rng")
        env_rng = np.random.default_rng(0)  # not drawn from: no random parts
    sigmas = sigma_schedule(episodes, sigma_start, sigma_end)
    n_decisions = sim.decisions_in(episode_seconds, params)
    return (
        kind,
        sigmas,
        n_decisions,
        np.empty((episodes, len(TRAINING_STAT_NAMES))),
        sim.pack_params(params),
        env_rng,
        dz,
    )


def train_chunks(
    agent,
    episodes: int,
    tracks_for: Callable[[int, int], Tracks],
    *,
    episode_seconds: float = EPISODE_SECONDS,
    sigma_start: float = SIGMA_START,
    sigma_end: float = SIGMA_END,
    params: sim.SimParams = sim.PAPER_SIM,
    progress: Callable[[int], None] | None = None,
    chunk: int = 50,
    env_rng: np.random.Generator | None = None,
    randomization=None,
) -> np.ndarray:
    """Train ``agent`` in its learner's compiled loop, ``chunk`` episodes per call.

    ``tracks_for(lo, hi)`` gives the pipes of episodes ``lo`` to ``hi`` (one pipe for all, or one
    each). Reports the episodes done to ``progress``. Returns (episodes, 4) statistics.

    With a ``randomization`` (:class:`~pipefollow.sim.randomization.Randomization`, domain
    randomization) every episode draws its disturbances from ``env_rng`` before its pipe, as the
    environment's reset draws them from ``np_random``, and runs in a call of its own.
    """
    if randomization is not None:
        return _train_randomized(agent, episodes, tracks_for, episode_seconds, sigma_start, sigma_end, params,
                                 progress, env_rng, randomization)  # fmt: skip
    run = compiled_setup(agent, episodes, episode_seconds, sigma_start, sigma_end, params, env_rng)
    kind, sigmas, n_decisions, stats, simp, env_rng, dz = run
    for lo in range(0, episodes, max(1, chunk)):
        hi = min(episodes, lo + max(1, chunk))
        how = Run(simp, sigmas[lo:hi], n_decisions, True)
        kind.run(agent, tracks_for(lo, hi), how, env_rng, dz, stats[lo:hi], no_poses())
        if progress is not None:
            progress(hi)
    agent.begin_episode(sigmas[-1] if episodes else sigma_start)
    return stats


def _train_randomized(agent, episodes, tracks_for, episode_seconds, sigma_start, sigma_end, params, progress,
                      env_rng, randomization):  # fmt: skip
    """:func:`train_chunks` under domain randomization: a compiled call per episode, its own disturbances."""
    from pipefollow.sim import randomization as rz
    from pipefollow.sim.disturbance import noise_count

    randomization = rz.resolve(randomization)
    rz.check_not_both(params.disturbance, randomization)
    if env_rng is None:
        raise ValueError("a randomization draws the disturbances: pass a seeded env_rng")
    kind, sigmas, n_decisions, stats, _, env_rng, _ = compiled_setup(
        agent, episodes, episode_seconds, sigma_start, sigma_end, params, env_rng
    )
    for e in range(episodes):
        d = rz.draw(randomization, env_rng)
        how = Run(sim.pack_params(params._replace(disturbance=d)), sigmas[e : e + 1], n_decisions, True)
        kind.run(agent, tracks_for(e, e + 1), how, env_rng, np.zeros(noise_count(d)), stats[e : e + 1],
                 no_poses())  # fmt: skip
        if progress is not None and ((e + 1) % 50 == 0 or e + 1 == episodes):
            progress(e + 1)
    agent.begin_episode(sigmas[-1] if episodes else sigma_start)
    return stats


def train_compiled(agent, pipeline: Pipeline, episodes: int, **options) -> np.ndarray:
    """Train an agent of the learner registry in compiled code.

    It gives the same numbers as :func:`train` on ``PipelineFollowingEnv(pipeline, episode_seconds,
    params=params)`` with the same agent state and generator, and with ``env_rng`` in the state of
    the environment's ``np_random``. ``env_rng`` is required when ``params.disturbance`` has random
    parts (camera noise, misses, a varying current) and with a ``randomization`` (its
    disturbances drawn per episode, :func:`train_chunks`). Runs ``chunk`` episodes per compiled call
    and reports the episodes done to ``progress``. ``options`` are the keywords of
    :func:`train_chunks` (``episode_seconds``, ``sigma_start``, ``sigma_end``, ``params``,
    ``progress``, ``chunk``, ``env_rng``, ``randomization``) with its defaults. Returns (episodes, 4)
    statistics.
    """
    tracks = tracks_of([pipeline])
    return train_chunks(agent, episodes, lambda lo, hi: tracks, **options)
