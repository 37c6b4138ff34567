"""A batched vector environment: N AUVs stepped in one compiled call.

``gymnasium.make_vec("pipefollow/PipelineFollowing-v0", num_envs=N,
vectorization_mode="vector_entry_point", **kwargs)`` returns a :class:`PipelineFollowingVectorEnv`,
a native :class:`gymnasium.vector.VectorEnv`. Sub-environment ``i`` behaves number for number like
``PipelineFollowingEnv(**kwargs)`` reset with seed ``seed + i`` (tested): it has its own generator
for its random pipes, start perturbation and random disturbances, drawn in the same order as the
single environment draws them.

* **Pipelines**: ``pipeline`` is one spec for all sub-environments or a list of N specs (names,
  files, :class:`~pipefollow.sim.pipeline.Pipeline` objects, ``random[:FAMILY]``); a random family
  draws a new pipe from the sub-environment's generator at each of its resets.
* **Autoreset**: Gymnasium's next-step mode (``metadata["autoreset_mode"]``): the step after an
  episode's last one resets that sub-environment and returns its first observation, reward 0 and
  no termination or truncation; the action given to it is ignored.
  :meth:`~PipelineFollowingVectorEnv.reset_done` resets the finished sub-environments at once
  instead (the same draws), for clients that reset within the step (Stable-Baselines3).
* **Infos**: a dict of arrays with Gymnasium's ``_key`` masks: the single environment's scalar
  entries, ``pose``, ``nu`` and ``waypoint`` as (N, 3) / (N, 2) arrays, and the episode summary
  (``episode_pipe_in_view``, ``episode_progress_m``, ``episode_rms_e_dist``) where an episode ends.
* **Disturbances**: supported, as in the single environment (each sub-environment draws its
  camera reading's normals from its own generator).
* **Vision camera** (``camera="vision"``, ``observation="image"``): supported; after the batched
  decision each sub-environment renders and detects with its own generator, as the single one does.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numba import njit

from pipefollow.envs.env import PipelineFollowingEnv
from pipefollow.perception.camera import VisionCamera
from pipefollow.sim import decision as sim
from pipefollow.sim.pipeline import Pipeline, resolve
from pipefollow.sim.suites import min_length_for, parse_random_spec


@njit(cache=True)
def step_batch(
    states, actions, points, cum, n_points, packed, z, skip, rewards, decisions, seen, sum_e2, max_n, ended
):
    """One decision of every sub-environment not in ``skip``, with its episode counters.

    Actions are clipped to [-1, 1]; returns False (stepping nothing) if one is NaN. Writes the
    rewards, counts decisions, decisions ending in view and their Σ e_dist², and marks in
    ``ended`` the sub-environments whose episode this decision ends.
    """
    for i in range(states.shape[0]):
        if math.isnan(actions[i]):
            return False
    for i in range(states.shape[0]):
        ended[i] = False
        if skip[i]:
            rewards[i] = 0.0
            continue
        n = n_points[i]
        a = min(1.0, max(-1.0, actions[i]))
        s = states[i]
        rewards[i] = sim.decide_packed(s, a, points[i, :n], cum[i, :n], packed, z[i])
        decisions[i] += 1
        if s[sim.IN_VIEW] != 0.0:
            seen[i] += 1
            sum_e2[i] += s[sim.E_DIST] ** 2
        ended[i] = decisions[i] >= max_n
    return True


_SCALARS = (
    ("pipe_in_view", sim.IN_VIEW, bool),
    ("overridden", sim.OVERRIDDEN, bool),
    ("e_dist", sim.E_DIST, float),
    ("e_angl", sim.E_ANGL, float),
    ("progress_m", sim.PROGRESS_MAX, float),
    ("executed_action", sim.A_PREV, float),
    ("time_s", sim.TIME, float),
    ("y_near", sim.Y_NEAR, float),
    ("camera_missed", sim.MISSED, bool),
)
_SUMMARY = ("episode_pipe_in_view", "episode_progress_m", "episode_rms_e_dist")


class PipelineFollowingVectorEnv(VectorEnv):
    """N pipeline-following AUVs in one batch (module docstring).

    Args:
        num_envs: number of sub-environments.
        pipeline: one pipeline spec for all, or a sequence of ``num_envs`` specs.
        **kwargs: the single environment's arguments (``episode_seconds``, ``start_lateral_noise``,
            ``start_heading_noise_deg``, ``params``, ``disturbance``), shared by all; rendering is
            not offered (``render_mode`` must be ``None``).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(
        self,
        num_envs: int = 1,
        pipeline: str | os.PathLike | Pipeline | Sequence[str | os.PathLike | Pipeline] = "paper-left",
        render_mode: str | None = None,
        max_episode_steps: int | None = None,
        **kwargs: Any,
    ) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
            raise ValueError(f"num_envs must be an integer ≥ 1, got {num_envs!r}")
        if render_mode is not None:
            raise ValueError("the vector environment does not render; use PipelineFollowingEnv")
        n = int(num_envs)
        specs = list(pipeline) if isinstance(pipeline, list | tuple) else [pipeline] * n
        if len(specs) != n:
            raise ValueError(f"pipeline lists {len(specs)} specs for {n} sub-environments")
        # the single environment checks the arguments and fixes spaces and parameters
        proto = PipelineFollowingEnv(specs[0], **kwargs)
        # gymnasium.make_vec passes the registered spec's max_episode_steps, an upper bound; the
        # episodes end after episode_seconds, as in the single environment
        if max_episode_steps is not None and max_episode_steps < proto.max_decisions:
            raise ValueError(
                f"max_episode_steps {max_episode_steps} is shorter than the episodes "
                f"({proto.max_decisions} decisions): set episode_seconds instead"
            )
        self.num_envs = n
        self.render_mode = None
        self.episode_seconds = proto.episode_seconds
        self.max_decisions = proto.max_decisions
        self.start_lateral_noise = proto.start_lateral_noise
        self.start_heading_noise_deg = proto.start_heading_noise_deg
        self.params = proto.params
        self._packed = proto._packed
        self.single_observation_space = proto.observation_space
        self.single_action_space = proto.action_space
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self._min_length = min_length_for(self.episode_seconds)
        self.suites = [parse_random_spec(s) for s in specs]
        self.pipelines = [
            resolve(s) if f is None else f.pipe(0) for s, f in zip(specs, self.suites, strict=True)
        ]
        cap = max(len(p.points) for p in self.pipelines)
        self._points = np.zeros((n, cap, 2))
        self._cum = np.zeros((n, cap))
        self._n_points = np.zeros(n, dtype=np.int64)
        for i, pipe in enumerate(self.pipelines):
            self._load_pipe(i, pipe)
        self.states = np.zeros((n, sim.STATE_SIZE))
        self._z = np.zeros((n, proto._z.size))
        self._rngs: list[np.random.Generator] | None = None
        self._decisions = np.zeros(n, dtype=np.int64)
        self._seen = np.zeros(n, dtype=np.int64)
        self._sum_e2 = np.zeros(n)
        self._autoreset = np.zeros(n, dtype=bool)
        self._rewards = np.zeros(n)
        self._no_skip = np.zeros(n, dtype=bool)
        self._ended = np.zeros(n, dtype=bool)
        # the vision camera renders and detects per sub-environment after the batched decision
        self._cams = None
        if proto._vision is not None:
            settings, cam, lost = proto.camera_settings, self.params.camera, self.params.lost_reward
            self._cams = [VisionCamera(settings, cam, lost) for _ in range(n)]

    def _load_pipe(self, i: int, pipe: Pipeline) -> None:
        m = len(pipe.points)
        if m > self._points.shape[1]:  # grow the buffers of all sub-environments
            cap = max(m, 2 * self._points.shape[1])
            points, cum = np.zeros((self.num_envs, cap, 2)), np.zeros((self.num_envs, cap))
            points[:, : self._points.shape[1]] = self._points
            cum[:, : self._cum.shape[1]] = self._cum
            self._points, self._cum = points, cum
        self._points[i, :m] = pipe.points
        self._cum[i, :m] = pipe.cumulative
        self._n_points[i] = m
        self.pipelines[i] = pipe

    @property
    def np_random_generators(self) -> list[np.random.Generator]:
        """The sub-environments' generators (seeded at the first :meth:`reset`)."""
        if self._rngs is None:
            self._rngs = [seeding.np_random(None)[0] for _ in range(self.num_envs)]
        return self._rngs

    def reset(self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None):
        """Reset every sub-environment; ``seed`` (int: ``seed + i`` for sub-environment i, or a list).

        ``options`` takes the single environment's reset options (``pipeline``,
        ``lateral_offset``, ``heading_offset_deg``), applied to every sub-environment.
        """
        n = self.num_envs
        seeds = (
            [None if seed is None else seed + i for i in range(n)]
            if not isinstance(seed, list | tuple)
            else seed
        )
        if len(seeds) != n:
            raise ValueError(f"reset got {len(seeds)} seeds for {n} sub-environments")
        rngs = self.np_random_generators
        for i, s in enumerate(seeds):
            if s is not None:
                rngs[i] = seeding.np_random(s)[0]
        options = dict(options or {})
        if "pipeline" in options:
            spec = options.pop("pipeline")
            self.suites = [parse_random_spec(spec)] * n
            for i in range(n):
                self._load_pipe(i, resolve(spec) if self.suites[i] is None else self.suites[i].pipe(0))
        lateral = options.pop("lateral_offset", None)
        heading = options.pop("heading_offset_deg", None)
        if options:
            raise ValueError(
                f"unknown reset option(s) {sorted(options)}; "
                "allowed: pipeline, lateral_offset, heading_offset_deg"
            )
        for i in range(n):
            self._reset_one(i, lateral, heading)
        self._autoreset[:] = False
        return self._observations(), self._infos(np.zeros(n, dtype=bool))

    def _reset_one(self, i: int, lateral=None, heading_deg=None) -> None:
        """Sub-environment ``i``'s reset, with the single environment's draws in its order."""
        rng = self.np_random_generators[i]
        if self.suites[i] is not None:
            self._load_pipe(i, self.suites[i].draw(rng, self._min_length))
        if lateral is None:
            noise = self.start_lateral_noise
            lateral = rng.uniform(-1.0, 1.0) * noise if noise > 0.0 else 0.0
        if heading_deg is None:
            noise = self.start_heading_noise_deg
            heading_deg = rng.uniform(-1.0, 1.0) * noise if noise > 0.0 else 0.0
        pipe = self.pipelines[i]
        p0, h = pipe.points[0], pipe.start_heading
        x = p0[0] - math.sin(h) * float(lateral)
        y = p0[1] + math.cos(h) * float(lateral)
        psi = h + math.radians(float(heading_deg))
        z = self._z[i]
        if z.size:
            rng.standard_normal(out=z)
        m = self._n_points[i]
        sim.init_state_packed(
            self.states[i], self._points[i, :m], self._cum[i, :m], x, y, psi, self._packed, z
        )
        self._decisions[i] = 0
        self._seen[i] = 0
        self._sum_e2[i] = 0.0
        if self._cams is not None:
            self._cams[i].reset(self.states[i], self._points[i, :m], self._cum[i, :m], rng)

    def step(self, actions):
        """One 1-s decision of every sub-environment (next-step autoreset; module docstring)."""
        a = np.asarray(actions, dtype=np.float64).reshape(-1)
        if a.size != self.num_envs:
            raise ValueError(f"expected {self.num_envs} actions (one per sub-environment), got {a.size}")
        resetting = self._autoreset
        any_reset = bool(resetting.any())
        if self._z.shape[1]:
            rngs = self.np_random_generators
            for i in range(self.num_envs):
                if not resetting[i]:
                    rngs[i].standard_normal(out=self._z[i])
        skip = resetting if any_reset else self._no_skip
        rewards, truncated = self._rewards, self._ended
        a_prev = self.states[:, sim.A_PREV].copy() if self._cams is not None else None
        ok = step_batch(
            self.states, a, self._points, self._cum, self._n_points, self._packed, self._z, skip, rewards,
            self._decisions, self._seen, self._sum_e2, self.max_decisions, truncated,
        )  # fmt: skip
        if not ok:
            raise ValueError("action is NaN")
        if self._cams is not None:
            rngs = self.np_random_generators
            for i in np.flatnonzero(~skip):
                m = self._n_points[i]
                pts, cum = self._points[i, :m], self._cum[i, :m]
                rewards[i] = self._cams[i].step(self.states[i], pts, cum, rngs[i], rewards[i], a_prev[i])
        if any_reset:
            for i in np.flatnonzero(resetting):
                self._reset_one(int(i))
        truncated = truncated.copy()
        terminated = np.zeros(self.num_envs, dtype=bool)
        infos = self._infos(truncated)
        self._autoreset = truncated.copy()  # no terminal states: only truncations end episodes
        return self._observations(), rewards.copy(), terminated, truncated, infos

    def reset_done(self) -> np.ndarray:
        """Reset the sub-environments whose episode ended at the last step, now; their first observations.

        The draws are those the next step's autoreset would make; that step then steps them.
        Returns the observations (k, 4) of the k reset sub-environments, in index order.
        """
        done = np.flatnonzero(self._autoreset)
        for i in done:
            self._reset_one(int(i))
        self._autoreset[:] = False
        return self._observations()[done]

    def _observations(self) -> np.ndarray:
        if self._cams is None:
            return self.states[:, :4].copy()
        return np.stack([c.observation(s) for c, s in zip(self._cams, self.states, strict=True)])

    def _infos(self, ended: np.ndarray) -> dict[str, np.ndarray]:
        s = self.states
        n = self.num_envs
        every = np.ones(n, dtype=bool)
        infos: dict[str, np.ndarray] = {}
        for key, slot, kind in _SCALARS:
            col = s[:, slot]
            infos[key] = col != 0.0 if kind is bool else col.copy()
            infos["_" + key] = every
        infos["pose"], infos["_pose"] = s[:, sim.X : sim.PSI + 1].copy(), every
        infos["nu"], infos["_nu"] = s[:, sim.U : sim.R + 1].copy(), every
        infos["waypoint"], infos["_waypoint"] = s[:, sim.WP_X : sim.WP_Y + 1].copy(), every
        if self._cams is not None:
            for key in self._cams[0].info():
                infos[key] = np.array([c.info()[key] for c in self._cams])
                infos["_" + key] = every
        if ended.any():
            dec = np.maximum(self._decisions, 1)
            with np.errstate(invalid="ignore", divide="ignore"):
                rms = np.where(self._seen > 0, np.sqrt(self._sum_e2 / np.maximum(self._seen, 1)), np.nan)
            values = (self._seen / dec, s[:, sim.PROGRESS_MAX].copy(), rms)
            for key, v in zip(_SUMMARY, values, strict=True):
                infos[key] = np.where(ended, v, 0.0 if key != "episode_rms_e_dist" else np.nan)
                infos["_" + key] = ended.copy()
        return infos
