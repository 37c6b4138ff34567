"""A batched vector environment: N AUVs stepped in one compiled call.

``gymnasium.make_vec("pipefollow/PipelineFollowing-v0", num_envs=N,
vectorization_mode="vector_entry_point", **kwargs)`` returns a :class:`PipelineFollowingVectorEnv`,
a native :class:`gymnasium.vector.VectorEnv`. Sub-environment ``i`` behaves number for number like
``PipelineFollowingEnv(**kwargs)`` reset with seed ``seed + i`` (tested): it has its own generator
for its random pipes, start perturbation and random disturbances, drawn in the same order as the
single environment draws them.

* **Pipelines**: ``pipeline`` is one spec for all sub-environments or a list of N specs (names,
  files, points ``[[x, y], ...]``, :class:`~pipefollow.sim.pipeline.Pipeline` objects,
  ``random[:FAMILY]``); a random family draws a new pipe from the sub-environment's generator at
  each of its resets.
* **Autoreset** (``autoreset_mode``, also in ``metadata``), Gymnasium 1.x's three modes:

  - ``NEXT_STEP`` (default): the step after an episode's last one resets that sub-environment
    and returns its first observation, reward 0 and no termination or truncation; the action
    given to it is ignored. :meth:`~PipelineFollowingVectorEnv.reset_done` resets the finished
    sub-environments at once instead (the same draws), for Stable-Baselines3.
  - ``SAME_STEP``: the step that ends an episode resets the sub-environment and returns its
    first observation; the last observation and info are in ``info["final_obs"]`` (an object
    array, ``None`` where no episode ended) and ``info["final_info"]`` (a dict of arrays, with
    the episode summary), with the masks ``_final_obs`` and ``_final_info``.
  - ``DISABLED``: nothing resets by itself; ``reset(options={"reset_mask": m})`` resets the
    sub-environments that ``m`` marks, and stepping one whose episode has ended raises
    :class:`gymnasium.error.ResetNeeded`.

  ``gymnasium.make_vec`` passes its keyword arguments to this class, so the mode is chosen with
  ``make_vec(ID, num_envs=N, autoreset_mode=AutoresetMode.SAME_STEP)``; Gymnasium refuses
  ``vector_kwargs`` for a vector entry point (they are for ``vectorization_mode="sync"`` or
  ``"async"``, whose wrappers take ``autoreset_mode`` the same way).
* **Infos**: the single environment's keys, each an array with the batch dimension first
  (``pose`` (N, 3), ``current`` (N, 2), ...), with Gymnasium's ``_key`` masks, the episode
  summary (``episode_pipe_in_view``, ``episode_progress_m``, ``episode_rms_e_dist``) and
  ``reached_pipe_end`` included: each sub-environment's episode so far (False while it goes on), its
  whole episode's where ``terminated | truncated`` (in ``final_info`` under same-step autoreset):
  truncated at its time limit, or terminated at the pipe's far end.
* **Observations**: float64 by default, ``obs_dtype="float32"`` as in the single environment.
* **Disturbances**: supported, as in the single environment (each sub-environment draws its
  camera reading's normals from its own generator).
* **Copies**: ``pickle`` and ``copy.deepcopy`` work at any time and the copy continues with the
  same numbers.
* **Vision camera** (``camera="vision"``, ``observation="image"``): supported; after the batched
  decision each sub-environment renders and detects with its own generator, as the single one does.
* **Sonar** (``sensor="sonar"``, ``"fused"``, ``"fls"`` or ``"fused-fls"``): supported the same
  way; each sub-environment's sonar draws from a generator spawned from its own, as in the single
  environment.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium.error import ResetNeeded
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from pipefollow.envs.shell import (
    CAMERA_ARGUMENTS,
    SHARED_ARGUMENTS,
    end_info,
    episode_summary,
    image_space,
    make_setup,
    observation,
    parse_reset_options,
    randomized_setup,
    start_episode,
    state_infos,
)
from pipefollow.envs.vector_batch import PipeBatch, pipeline_specs, step_batch
from pipefollow.perception.camera import camera_settings
from pipefollow.perception.sensor import make_sensor, start_sensor
from pipefollow.sim import decision as sim
from pipefollow.sim import episode as ep
from pipefollow.sim.pipe_names import pipeline_source
from pipefollow.sim.pipeline import Pipeline
from pipefollow.sim.randomization import MAX_NOISE, check_not_both
from pipefollow.sim.randomization import resolve as resolve_randomization


def _checked_count_and_mode(num_envs, render_mode, autoreset_mode) -> tuple[int, AutoresetMode]:
    """The number of sub-environments and the autoreset mode, checked; the vector env does not render."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
        raise ValueError(f"num_envs must be an integer ≥ 1, got {num_envs!r}")
    if render_mode is not None:
        raise ValueError("the vector environment does not render; use PipelineFollowingEnv")
    try:
        mode = AutoresetMode(autoreset_mode)
    except ValueError:
        allowed = ", ".join(repr(m.value) for m in AutoresetMode)
        raise ValueError(f"autoreset_mode must be one of {allowed}, got {autoreset_mode!r}") from None
    return int(num_envs), mode


def _camera_of(kwargs: dict[str, Any]):
    """The camera settings, popped from ``kwargs`` (left: the shared arguments); unknown keys refused."""
    unknown = sorted(set(kwargs) - set(SHARED_ARGUMENTS) - set(CAMERA_ARGUMENTS))
    if unknown:
        raise TypeError(
            f"unknown argument(s) {unknown} of the vector environment; allowed: num_envs, pipeline, "
            f"autoreset_mode, {', '.join(SHARED_ARGUMENTS + CAMERA_ARGUMENTS)}, randomization"
        )
    return camera_settings(**{k: kwargs.pop(k) for k in CAMERA_ARGUMENTS if k in kwargs})


class PipelineFollowingVectorEnv(VectorEnv):
    """N pipeline-following AUVs in one batch (module docstring).

    Args:
        num_envs: number of sub-environments.
        pipeline: one pipeline spec for all (a name, a file, a :class:`Pipeline`, points
            ``[[x, y], ...]``, ``random[:FAMILY]``), or a list of ``num_envs`` specs.
        autoreset_mode: a :class:`gymnasium.vector.AutoresetMode` or its value (``"NextStep"``,
            ``"SameStep"``, ``"Disabled"``); next-step by default.
        **kwargs: the single environment's arguments (``episode_seconds``, ``start_lateral_noise``,
            ``start_heading_noise_deg``, ``params``, ``disturbance``, ``obs_dtype``, ``randomization``),
            shared by all; rendering is not offered (``render_mode`` must be ``None``). Under a
            ``randomization`` each sub-environment draws its episode's disturbances at its reset from
            its own generator, as the single environment.
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(
        self,
        num_envs: int = 1,
        pipeline: str | os.PathLike | Pipeline | Sequence[Any] = "paper-left",
        render_mode: str | None = None,
        max_episode_steps: int | None = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        **kwargs: Any,
    ) -> None:
        n, mode = _checked_count_and_mode(num_envs, render_mode, autoreset_mode)
        randomization = kwargs.pop("randomization", None)
        camera = _camera_of(kwargs)
        specs = pipeline_specs(pipeline, n)
        setup = make_setup(**kwargs)
        # gymnasium.make_vec passes the registered id's max_episode_steps (its episode's decisions);
        # the episodes end after episode_seconds, as in the single environment, and a longer
        # episode than the id's would be cut by the single environment's TimeLimit: refused
        if max_episode_steps is not None and max_episode_steps < setup.max_decisions:
            raise ValueError(
                f"max_episode_steps {max_episode_steps} is shorter than the episodes "
                f"({setup.max_decisions} decisions): pass max_episode_steps={setup.max_decisions} "
                "with episode_seconds, or use an id with that episode (pipefollow.ENV_IDS)"
            )
        self.setup = setup
        self.randomization = None
        if randomization is not None:
            self.randomization = resolve_randomization(randomization)
            check_not_both(setup.params.disturbance, self.randomization)
        self._describe(n, mode, camera)
        # each sub-environment's pipe, padded for step_batch
        self._pipes = PipeBatch(specs, setup.episode_seconds)
        self.suites, self.pipelines = self._pipes.suites, self._pipes.pipelines  # the batch's lists
        self._make_buffers()

    def _describe(self, n: int, mode: AutoresetMode, camera) -> None:
        """The public attributes: the batch, its autoreset mode, the shared arguments and the spaces."""
        setup = self.setup
        self.num_envs = n
        self.render_mode = None
        self.autoreset_mode = mode
        self.metadata = {**type(self).metadata, "autoreset_mode": mode}
        self.episode_seconds = setup.episode_seconds
        self.max_decisions = setup.max_decisions
        self.start_lateral_noise = setup.start_lateral_noise
        self.start_heading_noise_deg = setup.start_heading_noise_deg
        self.params = setup.params
        self.camera_settings = camera
        self.single_observation_space = (
            image_space(camera.water) if camera.observation == "image" else setup.observation_space
        )
        self.single_action_space = setup.action_space
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)

    def _make_buffers(self) -> None:
        """The batch's states, per sub-environment parameters, normals, books and step buffers."""
        n, setup = self.num_envs, self.setup
        self.states = np.zeros((n, sim.STATE_SIZE))
        # per sub-environment: packed parameters and normals per camera reading (its episode's)
        self._packed = np.tile(setup.packed, (n, 1))
        self._counts = np.full(n, setup.noise_count, dtype=np.int64)
        self._z = np.zeros((n, MAX_NOISE if self.randomization is not None else setup.noise_count))
        self._rngs: list[np.random.Generator] | None = None
        self._books = ep.new_book(n)  # each sub-environment's episode (pipefollow.sim.episode)
        # sub-environments whose episode ended (next-step: reset at the next step; disabled: must be reset)
        self._ended_before = np.zeros(n, dtype=bool)
        self._started = False
        self._rewards = np.zeros(n)
        self._no_skip = np.zeros(n, dtype=bool)
        self._ends = np.zeros(n, dtype=np.int64)
        # the vision camera renders and detects per sub-environment after the batched decision
        # (and the sonar with sensor="sonar", "fused", "fls" or "fused-fls": pipefollow.perception.sensor)
        cam, lost = self.params.camera, self.params.lost_reward
        cams = [make_sensor(self.camera_settings, cam, lost) for _ in range(n)]
        self._cams = cams if cams[0] is not None else None

    @property
    def np_random_generators(self) -> list[np.random.Generator]:
        """The sub-environments' generators (seeded at the first :meth:`reset`)."""
        if self._rngs is None:
            self._rngs = [seeding.np_random(None)[0] for _ in range(self.num_envs)]
        return self._rngs

    def reset(self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None):
        """Reset the sub-environments; ``seed`` (int: ``seed + i`` for sub-environment i, or a list).

        ``options`` takes the single environment's reset options (``pipeline``,
        ``lateral_offset``, ``heading_offset_deg``), applied to every sub-environment reset, and
        Gymnasium's ``reset_mask`` (a bool array of shape ``(num_envs,)``): only the sub-environments
        it marks are reset (and seeded); the others keep their episode. The infos' ``_key`` masks
        mark the sub-environments reset.
        """
        n = self.num_envs
        options = dict(options or {})
        mask = self._reset_mask(options.pop("reset_mask", None))
        opts = parse_reset_options(options, extra=("reset_mask",))
        seeds = (
            [None if seed is None else seed + i for i in range(n)]
            if not isinstance(seed, list | tuple)
            else list(seed)
        )
        if len(seeds) != n:
            raise ValueError(f"reset got {len(seeds)} seeds for {n} sub-environments")
        rngs = self.np_random_generators
        chosen = np.flatnonzero(mask)
        for i in chosen:
            if seeds[i] is not None:
                rngs[i] = seeding.np_random(seeds[i])[0]
        if opts.switches_pipeline:
            source = pipeline_source(opts.pipeline, self.setup.episode_seconds)
            for i in chosen:
                self.suites[i] = source[0]
                self._pipes.load(i, source[1])
        for i in chosen:
            self._reset_one(int(i), opts.lateral_offset, opts.heading_offset_deg)
        self._ended_before[mask] = False
        self._started = True
        return self._observations(), self._infos(mask)

    def _reset_mask(self, mask) -> np.ndarray:
        """Gymnasium's ``reset_mask`` checked (as its ``SyncVectorEnv`` checks it); None: all."""
        n = self.num_envs
        if mask is None:
            return np.ones(n, dtype=bool)
        if not isinstance(mask, np.ndarray) or mask.dtype != np.bool_:
            raise TypeError(f"reset option reset_mask must be a numpy bool array, got {mask!r}")
        if mask.shape != (n,):
            raise ValueError(f"reset option reset_mask must have shape ({n},), got {mask.shape}")
        if not mask.any():
            raise ValueError("reset option reset_mask marks no sub-environment")
        if not self._started and not mask.all():
            raise ValueError("the first reset must reset every sub-environment (reset_mask all True)")
        return mask

    def _reset_one(self, i: int, lateral=None, heading_deg=None) -> None:
        """Sub-environment ``i``'s reset, with the single environment's draws in its order."""
        setup, rng = self.setup, self.np_random_generators[i]
        if self.randomization is not None:  # drawn first, before the pipe
            setup = randomized_setup(setup, self.randomization, rng)
            self._packed[i], self._counts[i] = setup.packed, setup.noise_count
        pipe = start_episode(
            self.states[i], self.suites[i], self.pipelines[i], rng, setup, self._z[i, : self._counts[i]],
            lateral, heading_deg,
        )  # fmt: skip
        if pipe is not self.pipelines[i]:
            self._pipes.load(i, pipe)
        self._books[i] = 0.0
        if self._cams is not None:
            pts, cum = self._pipes.of(i)
            rng, disturbance = self.np_random_generators[i], setup.params.disturbance
            start_sensor(self._cams[i], self.states[i], pts, cum, rng, disturbance)

    def step(self, actions):
        """One 1-s decision of every sub-environment, autoresetting by :attr:`autoreset_mode`."""
        if not self._started:
            raise ResetNeeded("call reset() before the first step()")
        a = np.asarray(actions, dtype=np.float64).reshape(-1)
        if a.size != self.num_envs:
            raise ValueError(f"expected {self.num_envs} actions (one per sub-environment), got {a.size}")
        mode = self.autoreset_mode
        resetting = self._ended_before
        any_reset = bool(resetting.any())
        if any_reset and mode == AutoresetMode.DISABLED:
            raise ResetNeeded(
                f"the episodes of sub-environment(s) {np.flatnonzero(resetting).tolist()} have ended: "
                "reset them with reset(options={'reset_mask': mask}) before step()"
            )
        if self._z.shape[1]:
            rngs = self.np_random_generators
            for i in range(self.num_envs):
                if not resetting[i]:
                    rngs[i].standard_normal(out=self._z[i, : self._counts[i]])
        skip = resetting if any_reset else self._no_skip
        rewards, ends = self._rewards, self._ends
        a_prev = self.states[:, sim.A_PREV].copy() if self._cams is not None else None
        pipes = self._pipes
        ok = step_batch(
            self.states, a, pipes.points, pipes.cum, pipes.n_points, self._packed, self._z, skip,
            rewards, self._books, self.max_decisions, ends,
        )  # fmt: skip
        if not ok:
            raise ValueError("action is NaN")
        if self._cams is not None:  # each sub-environment renders and detects with its own generator
            rngs = self.np_random_generators
            for i in np.flatnonzero(~skip):
                pts, cum = pipes.of(i)
                rewards[i] = self._cams[i].step(self.states[i], pts, cum, rngs[i], rewards[i], a_prev[i])
        if any_reset:  # next-step autoreset
            for i in np.flatnonzero(resetting):
                self._reset_one(int(i))
        truncated = ends == ep.TIME_LIMIT
        terminated = ends == ep.PIPE_END  # the pipe's far end reached
        done = truncated | terminated
        every = np.ones(self.num_envs, dtype=bool)
        if mode == AutoresetMode.SAME_STEP and done.any():
            final_obs = np.full(self.num_envs, None, dtype=object)
            last = self._observations()
            for i in np.flatnonzero(done):
                final_obs[i] = last[i]
            final_info = self._infos(done, ends)
            for i in np.flatnonzero(done):
                self._reset_one(int(i))
            infos = self._infos(every)
            infos["final_obs"], infos["_final_obs"] = final_obs, done.copy()
            infos["final_info"], infos["_final_info"] = final_info, done.copy()
            self._ended_before = np.zeros(self.num_envs, dtype=bool)
        else:
            infos = self._infos(every, ends)
            self._ended_before = done.copy()
        return self._observations(), rewards.copy(), terminated, truncated, infos

    def reset_done(self) -> np.ndarray:
        """Reset the sub-environments whose episode ended at the last step, now; their first observations.

        The draws are those the next step's autoreset would make; that step then steps them.
        Returns the observations (k, 4) of the k reset sub-environments, in index order.
        """
        done = np.flatnonzero(self._ended_before)
        for i in done:
            self._reset_one(int(i))
        self._ended_before[:] = False
        return self._observations()[done]

    def _observations(self) -> np.ndarray:
        if self._cams is None:
            return observation(self.states, self.setup)
        dtype = self.setup.observation_space.dtype
        slots = self.setup.obs_slots
        cams = zip(self._cams, self.states, strict=True)
        return np.stack([c.observation(s, dtype, slots) for c, s in cams])

    def _infos(self, present: np.ndarray, ends: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """The infos of all sub-environments, ``_key`` masks ``present``, with the episodes' summaries.

        ``ends``: the end codes of the step (``pipefollow.sim.episode.end_of``) for ``reached_pipe_end``;
        none: every episode goes on.
        """
        infos: dict[str, np.ndarray] = {}
        for key, value in state_infos(self.states).items():
            infos[key], infos["_" + key] = value, present.copy()
        if self._cams is not None:
            per_env = [c.info() for c in self._cams]
            for key in per_env[0]:
                infos[key] = np.array([d[key] for d in per_env])
                infos["_" + key] = present.copy()
        # the summary of each episode so far, as the single environment's info has it at every step
        for key, value in episode_summary(self._books, self.states).items():
            infos[key] = np.where(present, value, 0.0)  # 0 where masked out, as Gymnasium's SyncVectorEnv
            infos["_" + key] = present.copy()
        infos.update(end_info(np.full(self.num_envs, ep.GOES_ON) if ends is None else ends))
        infos["_reached_pipe_end"] = present.copy()
        return infos
