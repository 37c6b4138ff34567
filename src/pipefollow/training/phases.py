"""Training in phases, the one way ``pipefollow train`` and experiment trials train a learner.

A run with seed ``s`` draws from three streams in the compiled loops: the agent's generator
``numpy.random.default_rng(s)`` (exploration; made by the caller, see :func:`agent_rng`), its first
child (the pipes of ``random[:FAMILY]`` phases, spawned at the first such phase) and
``default_rng(SeedSequence(s).spawn(1)[0])`` (the random disturbances, :func:`disturbance_rng`) —
the same numbers as that first child (docs/decisions.md, "The paper's learners trained through
the sensor"). Trained through a camera or sensor, a phase's environment draws its pipes and
disturbances from a stream of its own instead (:func:`.through_env.env_seed`). σ is the paper's
schedule in the ``sigma_unit`` reading's units, scaled to normalized action units; the simulation
takes the readings and the disturbances.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from pipefollow import readings as rd
from pipefollow.files.paper_training import EPISODE_SECONDS
from pipefollow.learners.exploration import SIGMA_END, SIGMA_START, sigma_schedule
from pipefollow.sim import decision as sim
from pipefollow.sim.disturbance import NO_DISTURBANCE, Disturbance
from pipefollow.training.compiled import train_compiled
from pipefollow.training.random_pipes import train_random_compiled


def agent_rng(seed: int) -> np.random.Generator:
    """The agent's generator of a run with ``seed`` (exploration; its first child draws random pipes)."""
    return np.random.default_rng(seed)


def disturbance_rng(seed: int) -> np.random.Generator:
    """The random disturbances' generator of a run with ``seed``: a stream of their own."""
    return np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0])


def sim_under(readings: rd.Readings, disturbance: Disturbance = NO_DISTURBANCE) -> sim.SimParams:
    """The simulated system of a run: the readings' parameters with ``disturbance``."""
    return rd.sim_params(readings)._replace(disturbance=disturbance)


def sigma_range(readings: rd.Readings = rd.DEFAULT, start: float = SIGMA_START, end: float = SIGMA_END):
    """σ's first and last value in normalized action units: ``start``, ``end`` in ``sigma_unit``'s units."""
    scale = rd.sigma_scale(readings)
    return start * scale, end * scale


def phase_sigmas(
    episodes: int, readings: rd.Readings = rd.DEFAULT, start: float = SIGMA_START, end: float = SIGMA_END
) -> np.ndarray:
    """σ of every episode of a phase as :func:`train_phases` trains it (normalized action units).

    The one schedule that training, the learning curve, TensorBoard and the results report.
    """
    return sigma_schedule(episodes, *sigma_range(readings, start, end))


def train_phases(
    agent,
    phases: Sequence[tuple[str, int]],
    *,
    seed: int,
    readings: rd.Readings = rd.DEFAULT,
    disturbance: Disturbance = NO_DISTURBANCE,
    randomization=None,
    episode_seconds: float = EPISODE_SECONDS,
    sigma_start: float = SIGMA_START,
    sigma_end: float = SIGMA_END,
    progress: Callable[[int], None] | None = None,
    phase_params: Sequence | None = None,
    camera: dict | None = None,
) -> list[np.ndarray]:
    """Train ``agent`` (its ``rng`` from :func:`agent_rng`) through ``phases`` of (pipeline, episodes).

    A pipeline is a built-in name, a JSON file or ``random[:FAMILY]`` (a new pipe every episode).
    σ runs from ``sigma_start`` to ``sigma_end`` (the paper's units, scaled by the ``sigma_unit``
    reading) over each phase. ``progress`` gets the episodes done over all phases. A
    ``randomization`` (:mod:`pipefollow.sim.randomization`; a preset name, table or record) draws
    every episode's disturbances from the disturbances' stream (through a camera or sensor: the
    environment's) instead of ``disturbance``.
    ``phase_params`` gives each phase the learner's parameter record for its episodes (None: the
    agent's record at the start; :meth:`~pipefollow.learners.protocol.Agent.retune`); the agent
    ends with the last phase's. ``camera`` (the environment's camera arguments: ``camera``,
    ``water``, ``sensor``) trains every phase through that camera or sensor in the environment
    (:mod:`pipefollow.training.through_env`; its own generator, :func:`.through_env.env_seed`)
    instead of the learner's compiled loop of the ideal camera. Returns one (episodes, 4)
    statistics array per phase.
    """
    from pipefollow.sim.pipe_names import resolve_training
    from pipefollow.sim.suites import Suite

    pipes = [resolve_training(name) for name, _ in phases]  # a bad pipeline fails before any training
    if randomization is not None:
        from pipefollow.sim.randomization import resolve

        randomization = resolve(randomization)
    start, end = sigma_range(readings, sigma_start, sigma_end)  # each phase runs phase_sigmas' schedule
    schedule = dict(
        episode_seconds=episode_seconds,
        sigma_start=start,
        sigma_end=end,
        params=sim_under(readings, disturbance),
        env_rng=disturbance_rng(seed),
        randomization=randomization,
    )
    own = agent.params
    records = list(phase_params) if phase_params is not None else [None] * len(phases)
    if len(records) != len(phases):
        raise ValueError(f"phase_params must have one entry per phase ({len(phases)}), got {len(records)}")
    out, done, pipe_rng = [], 0, None
    for k, (pipe, (name, episodes), record) in enumerate(zip(pipes, phases, records, strict=True)):
        wanted = own if record is None else record
        if wanted is not agent.params:
            agent.retune(wanted)
        report = None if progress is None else (lambda n, before=done: progress(before + n))
        if camera is not None:  # a sensor of the environment's, frame by frame
            from pipefollow.training.through_env import train_through_env

            stats = train_through_env(
                agent, name, episodes, camera=camera, seed=seed, phase=k, progress=report,
                episode_seconds=episode_seconds, sigma_start=start, sigma_end=end,
                params=schedule["params"], randomization=randomization,
            )  # fmt: skip
        elif isinstance(pipe, Suite):  # a new pipe every episode, from a child of the agent's generator
            pipe_rng = pipe_rng if pipe_rng is not None else agent.rng.spawn(1)[0]
            stats = train_random_compiled(
                agent, pipe, episodes, pipe_rng=pipe_rng, progress=report, **schedule
            )
        else:
            stats = train_compiled(agent, pipe, episodes, progress=report, **schedule)
        out.append(stats)
        done += episodes
    return out
