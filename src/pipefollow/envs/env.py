"""The Gymnasium environment ``pipefollow/PipelineFollowing-v0``."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.error import ResetNeeded

from pipefollow.envs.shell import (
    MAX_EPISODE_SECONDS,
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
from pipefollow.files.paper_training import EPISODE_SECONDS
from pipefollow.perception.camera import camera_settings
from pipefollow.perception.sensor import make_sensor, start_sensor
from pipefollow.sim import decision as sim
from pipefollow.sim import episode as ep
from pipefollow.sim.disturbance import Disturbance
from pipefollow.sim.pipe_names import pipeline_source
from pipefollow.sim.pipeline import Pipeline
from pipefollow.sim.randomization import Randomization, check_not_both
from pipefollow.sim.randomization import resolve as resolve_randomization

__all__ = ["MAX_EPISODE_SECONDS", "PipelineFollowingEnv"]


class PipelineFollowingEnv(gym.Env):
    """An AUV following a subsea pipeline with a downward camera (Fjerdingen et al., 2010).

    ## Description

    The AUV of the paper's §3 (3-DOF model of eq. 16, PD waypoint controller) swims above a
    pipeline laid out as a polyline. Once per second the agent chooses where to put the next
    waypoint: on a circle of radius 3 m around the AUV, at a bearing between 90° to port and
    90° to starboard of its heading. A camera sees the part of the pipe inside a 2 m × 3 m
    footprint ahead of the AUV. If the pipe leaves the footprint, a search behaviour takes over
    (the AUV turns on the spot towards the side where it last saw the pipe) until the pipe is
    back in view.

    ## Action Space

    ``Box(-1, 1, (1,), float32)``: the waypoint bearing relative to the heading in units of 90°;
    positive turns to starboard, negative to port. Actions outside [-1, 1] are clipped; a NaN
    action or one of another shape than ``(1,)`` (a plain number is accepted too) raises
    ``ValueError``. While the pipe is lost the action is ignored.

    ## Observation Space

    ``Box(4,)`` of float64 (``obs_dtype="float32"`` for float32), in camera coordinates (x lateral,
    positive to starboard; y forward):

    | index | observation                                   | min   | max  | unit |
    |-------|-----------------------------------------------|-------|------|------|
    | 0     | x1: lateral position of the far end of the pipe in view  | -1 | 1 | m |
    | 1     | y1: forward position of the far end of the pipe in view  | 0  | 3 | m |
    | 2     | x2: lateral position of the near end of the pipe in view | -1 | 1 | m |
    | 3     | v_x: surge speed over ground                      | -1 | 1 | m/s |

    While the pipe is out of view, (x1, y1, x2) hold the last sighting; ``info["pipe_in_view"]``
    tells the two apart. ``state="paper+drift"`` appends the DVL's sway velocity over ground v_y
    (m/s, −1…1, starboard +), ``"paper+yaw"`` the gyro's yaw rate r (rad/s, −1…1), ``"paper+drift+yaw"``
    both (:mod:`pipefollow.sim.observation`; noise: the disturbance's ``dvl_noise``, ``gyro_noise_deg``);
    ``env.setup.observation_names`` and ``.observation_units`` name them.

    With ``observation="image"``: ``Box(0, 255, (H, W, 1), uint8)``, the grey camera image of the
    footprint (96 × 64 pixels of 3.125 cm by default: H along y, row 0 at the far edge 3 m ahead;
    W along x, column 0 at 1 m to port), height × width × channel as Gymnasium's image wrappers
    (``GrayscaleObservation``, ``ResizeObservation``, ``FrameStackObservation``) and
    Stable-Baselines3's ``CnnPolicy`` (through its ``VecTransposeImage``) take it.

    ## Rewards

    Eq. 19: ``v_x − e_dist² − e_angl² − (a − a_prev)²`` with ``e_dist = (x1 + x2)/2`` (m),
    ``e_angl = atan2(x1 − x2, y1 − y_near)`` (rad) and ``a_prev`` the previously executed action.
    Every decision in which the pipe is lost (at its start or its end) gives −10.

    ## Starting State

    At rest on the first point of the pipeline, heading along the first segment. With
    ``start_lateral_noise`` / ``start_heading_noise_deg`` the lateral offset (m) and heading
    offset (deg) are drawn uniformly from ±those values with the environment's seeded generator.
    ``reset(options={"lateral_offset": m, "heading_offset_deg": deg})`` sets them exactly.

    ## Episode End

    The episode is truncated after ``episode_seconds`` (one decision per second; 20 in the
    paper's training), at most :data:`MAX_EPISODE_SECONDS`; agents should bootstrap from the last
    state. Each registered id's ``max_episode_steps`` is its own episode's decisions
    (:data:`pipefollow.ENV_IDS`), so ``gym.make``'s ``TimeLimit`` wrapper ends an episode at the same
    step as the environment; an ``episode_seconds`` longer than the id's needs
    ``gym.make(ID, episode_seconds=S, max_episode_steps=S)`` (``gym.make_vec`` refuses it without).
    The episode is terminated when the AUV reaches the pipe's far end (its progress within 0.5 m of
    the pipe's length, :func:`pipefollow.sim.episode.reached_end`), a terminal state; under the
    paper's reading ``pipe_end=continue`` (``params.end_at_pipe_end=False``) it goes on there, the
    pipe lost (−10 a decision). ``info["reached_pipe_end"]`` says which: True at the far end,
    False at a time limit (and while the episode goes on). ``step`` before the first ``reset`` raises
    :class:`gymnasium.error.ResetNeeded`. After the episode's last decision it carries on as
    Gymnasium's own environments do: a warning (once until the next reset), the simulation goes on
    and every further step ends as the last one did (``truncated`` or ``terminated``), without a
    second summary; ``strict_reset=True`` raises ``ResetNeeded`` there instead.

    ## Arguments

    * ``pipeline``: built-in name (``paper-left``, ``paper-right``, ``paper-validation``), path of a
      JSON file ``{"points": [[x, y], ...]}``, the points themselves (``[[0, 0], [5, 0], [5, 5]]``,
      m, x north, y east), a :class:`~pipefollow.sim.pipeline.Pipeline`, or a suite's pipe by the name
      ``pipefollow suites export`` gives it (``heldout-003``: pipe 3 of ``heldout``, as long as
      ``episode_seconds`` needs, as ``pipefollow evaluate --pipeline`` takes it; held-out pipes are
      there to judge a policy, not to train it). ``reset(options={"pipeline": ...})`` switches it.
      ``random`` or ``random:NAME`` (a training family of :mod:`pipefollow.sim.suites`; ``random``
      is ``mixed``) draws a new pipe from the environment's generator at every reset, so
      auto-resetting vector environments train on a fresh pipe every episode.
    * ``episode_seconds``: episode length in seconds (default 20).
    * ``start_lateral_noise``, ``start_heading_noise_deg``: start perturbation (default 0).
    * ``render_mode``: ``None``, ``"rgb_array"`` (the paper's Fig. 2 view as an image) or
      ``"human"`` (the same view in a Matplotlib window, updated at every step).
    * ``params``: a :class:`~pipefollow.sim.decision.SimParams` (default: the paper's system).
    * ``disturbance``: a :class:`~pipefollow.sim.disturbance.Disturbance` (ocean current, camera
      noise, missed detections, buried stretches) or a dict of its user-unit keys
      (:func:`~pipefollow.sim.disturbance.disturbance_from_dict`), replacing ``params.disturbance``;
      none by default. Its random parts draw from the environment's seeded ``np_random``.
    * ``obs_dtype``: ``"float64"`` (default; the simulator's own numbers) or ``"float32"`` (what
      most neural-network policies take; the observation rounded to float32).
    * ``camera``: ``"ideal"`` (default: the exact visible piece, the paper's) or ``"vision"``: the
      observation and the in-view decision come from a pipe detector on the rendered camera image
      and a tracker that carries the pipe from frame to frame by the vehicle's navigation
      (:mod:`pipefollow.perception`; needs the extra ``vision``); a pipe out of the tracked view is
      a lost pipe. ``"vision-raw"``: the detector alone, each frame's detection as it is.
    * ``observation``: ``"state"`` (default, ``Box(4)``) or ``"image"``: the camera image,
      ``Box(0, 255, (H, W, 1), uint8)``.
    * ``reward_from``: ``"truth"`` (default: eq. 19 from the true geometry; a lost detection still
      gives −10) or ``"detected"`` (eq. 19 from the detection).
    * ``water``: the image's water and camera settings: a
      :class:`~pipefollow.perception.water.Water`, a preset name (``clear``, ``moderate``,
      ``turbid``) or a dict of its fields (``preset`` allowed); ``clear`` by default. Its ``burial``
      (share of the pipe's width under sand) is the sonar's buried share of the diameter too.
    * ``sensor``: what writes the observation (:mod:`pipefollow.perception.sensor`): ``"camera"``
      (default: the camera of ``camera``, exactly as without this argument), ``"sonar"`` (a
      multibeam sonar whose fan meets the seabed 2 m ahead, alone; turbidity does not reach it; a
      lost pipe is −10 and the search, as with the vision camera; only with ``camera="ideal"``) or
      ``"fused"`` (each decision the camera's detection when it finds the pipe, else the sonar's
      view, fed to the vision camera's pipe tracker — or, with the ideal camera, the sonar's view
      while the exact camera sees no pipe); ``"fls"`` and ``"fused-fls"`` the same with a
      forward-looking imaging sonar and the map of its highlights instead of the multibeam sonar
      (:mod:`pipefollow.perception.imaging_track`). The sonar draws from a generator spawned from
      ``np_random`` at each reset, so the camera's draws stay what they are. With
      ``observation="image"`` the agent observes the camera's image (the frames of
      ``observation="image"`` alone) while the sensor decides the pipe in view, the search and the
      −10: the rewards and the episode are those of the same sensor with the state observation.
    * ``randomization``: domain randomization, a
      :class:`~pipefollow.sim.randomization.Randomization`, a preset name (``mild``, ``moderate``,
      ``vision``, ``harsh``) or a table of its keys: every reset draws the episode's disturbances from
      ``np_random`` (before the pipe of a ``random`` family); not with ``disturbance``.
    * ``strict_reset``: raise :class:`gymnasium.error.ResetNeeded` on a step after the episode's
      end instead of warning and carrying on (default ``False``, Gymnasium's behaviour).
    * ``state``: the observation, ``"paper"`` (default) or the paper's with measured motion (above).

    ## Info

    Every value is a NumPy array (0-d for a number), so vector wrappers batch them with their
    dtype; the vector environment gives the same keys with the batch dimension first.
    ``pipe_in_view``, ``overridden`` (the search behaviour acted), ``e_dist``, ``e_angl``,
    ``progress_m`` (arc length reached along the pipe), ``pose`` (x north, y east, ψ),
    ``nu`` (u, v, r) relative to the water (ν_r; equal to ν without a current), ``waypoint``,
    ``executed_action``, ``time_s``, ``y_near`` (forward position of the near end of the pipe in
    view, m), ``camera_missed`` (a missed detection hid the pipe), ``current`` ((V_c m/s, β_c rad)).
    Like the observation, ``e_dist``, ``e_angl`` and ``y_near`` hold the last sighting's values
    while the pipe is lost. The episode's summary, in every info (reset's included) so that the
    keys never change within an episode (Minari's ``DataCollector`` and other recorders demand it):
    ``episode_pipe_in_view`` (share of the decisions so far ending with the pipe in view; NaN
    before the first), ``episode_progress_m`` (m) and ``episode_rms_e_dist`` (RMS of ``e_dist``
    over those decisions, m; NaN if none), all float64. They are the episode's so far: at its
    last step (``terminated or truncated``) the whole episode's, which clients that log per episode
    read there; steps past the end repeat them. With the vision camera also ``detected``,
    ``detection_confidence``, ``true_pipe_in_view``, ``true_e_dist`` and ``true_e_angl`` (the
    exact camera's; with the tracker also ``track_confidence``); the episode's summary is then the
    exact camera's too. With a sonar (``sensor="sonar"``, ``"fused"``, ``"fls"``, ``"fused-fls"``) also
    ``sonar_detected`` (the ping found the pipe anywhere in its swath or image), ``sonar_in_view``
    (its line, or its map's piece, crosses the footprint) and
    the exact camera's ``true_pipe_in_view``, ``true_e_dist`` and ``true_e_angl``.
    ``reached_pipe_end`` (a 0-d bool) is in every info too: True once the
    episode has ended at the pipe's far end.

    ## Registered ids

    Importing :mod:`pipefollow.envs` (or ``gym.make("pipefollow.envs:ID")`` in a fresh
    interpreter) registers :data:`pipefollow.ENV_IDS`: ``pipefollow/PipelineFollowing-v0`` (the
    paper's training: ``paper-left``, 20 steps), ``pipefollow/PipelineFollowingImage-v0`` (the
    same with the camera image as observation), ``pipefollow/PipelineFollowingVision-v0`` (the
    same through the pipe detector; extra ``vision``), ``pipefollow/PipelineFollowingRandom-v0``
    (a new ``random:mixed`` pipe every 90-s episode, 90 steps) and
    ``pipefollow/PipelineFollowingValidation-v0`` (the paper's held-out ``paper-validation`` pipe,
    60 steps). Keyword arguments of ``gym.make`` override the id's.

    ## Version History

    * v0: the first release. Before it (unreleased): the episode's summary joined every step's
      info (it was at the last step only); ``observation="image"`` became ``(H, W, 1)`` (was
      ``(1, H, W)``); the ids got their episodes' ``max_episode_steps`` (was 86,400 for one id); reaching
      a finite pipe's far end terminates the episode (``reached_pipe_end``); ``sensor="sonar"``
      and ``"fused"`` (the default ``"camera"`` unchanged).
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 2}

    def __init__(
        self,
        pipeline: str | os.PathLike | Pipeline | Sequence[Sequence[float]] = "paper-left",
        episode_seconds: float = EPISODE_SECONDS,
        start_lateral_noise: float = 0.0,
        start_heading_noise_deg: float = 0.0,
        render_mode: str | None = None,
        params: sim.SimParams = sim.PAPER_SIM,
        disturbance: Disturbance | dict[str, Any] | None = None,
        obs_dtype: str | type = "float64",
        camera: str = "ideal",
        observation: str = "state",
        reward_from: str = "truth",
        water: Any = None,
        sensor: str = "camera",
        randomization: Randomization | str | dict[str, Any] | None = None,
        strict_reset: bool = False,
        state: str = "paper",
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None, 'human' or 'rgb_array', got {render_mode!r}")
        setup = make_setup(
            episode_seconds,
            start_lateral_noise,
            start_heading_noise_deg,
            params,
            disturbance,
            obs_dtype,
            state,
        )
        self.setup = setup
        self.randomization = None
        if randomization is not None:
            self.randomization = resolve_randomization(randomization)
            check_not_both(setup.params.disturbance, self.randomization)
        self.episode_setup = setup  # this episode's: under a randomization, its own disturbances
        self.suite, self.pipeline = pipeline_source(pipeline, setup.episode_seconds)
        self.episode_seconds = setup.episode_seconds
        self.max_decisions = setup.max_decisions
        self.start_lateral_noise = setup.start_lateral_noise
        self.start_heading_noise_deg = setup.start_heading_noise_deg
        self.render_mode = render_mode
        self.params = setup.params
        self.observation_space = setup.observation_space
        self.action_space = setup.action_space
        # the vision camera (pipefollow.perception.camera): None with the ideal camera's state
        # and the sonar (pipefollow.perception.sensor) with sensor="sonar" or "fused"
        self.camera_settings = camera_settings(camera, observation, reward_from, water, sensor)
        self._vision = make_sensor(self.camera_settings, self.params.camera, self.params.lost_reward)
        if observation == "image":
            self.observation_space = image_space(self.camera_settings.water)
        self.state = np.zeros(sim.STATE_SIZE)
        self._z = np.zeros(setup.noise_count)  # standard normals of one camera reading
        self._book = ep.new_book()  # the episode's counts (pipefollow.sim.episode)
        self._summary = episode_summary(self._book, self.state)  # the info's summary keys
        self._needs_reset = True  # before the first reset
        self.strict_reset = bool(strict_reset)
        self._warned_after_end = False  # stepping past the end warns once per episode
        self._end = ep.GOES_ON  # how the episode ended (pipefollow.sim.episode.end_of), once it has
        self.trail: list[tuple[float, float, float]] = []
        self.last_reward: float | None = None  # shown by render()
        self.episode_return = 0.0  # the rewards returned, summed (the book counts the decisions)
        self._scene = None  # the rendering's figure, made on the first render() and reused

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Start an episode; see the class docstring for the options."""
        super().reset(seed=seed)
        opts = parse_reset_options(options)
        if opts.switches_pipeline:
            self.suite, self.pipeline = pipeline_source(opts.pipeline, self.episode_seconds)
        if self.randomization is not None:  # drawn first, before the pipe
            self.episode_setup = randomized_setup(self.setup, self.randomization, self.np_random)
            self._z = np.zeros(self.episode_setup.noise_count)
        self.pipeline = start_episode(
            self.state, self.suite, self.pipeline, self.np_random, self.episode_setup, self._z,
            opts.lateral_offset, opts.heading_offset_deg,
        )  # fmt: skip
        self._book[:] = 0.0
        self._end = ep.GOES_ON
        self._summary = episode_summary(self._book, self.state) | end_info(self._end)
        self._needs_reset = False
        self._warned_after_end = False
        s = self.state
        self.trail = [(s[sim.X], s[sim.Y], s[sim.PSI])]
        self.last_reward, self.episode_return = None, 0.0
        if self._vision is not None:
            pipe, disturbance = self.pipeline, self.episode_setup.params.disturbance
            start_sensor(self._vision, self.state, pipe.points, pipe.cumulative, self.np_random, disturbance)
        if self.render_mode == "human":
            self.render()
        return self._observation(), self._info()

    def step(self, action):
        """One 1-s decision; see the class docstring."""
        if self._needs_reset:
            raise ResetNeeded("call reset() before the first step()")
        past_end = self._end != ep.GOES_ON
        if past_end:
            if self.strict_reset:
                raise ResetNeeded("the episode has ended: call reset() before step()")
            if not self._warned_after_end:
                self._warned_after_end = True
                gym.logger.warn(
                    "step() after the episode's end (truncated or terminated was returned): the episode goes "
                    "on, but call reset() to start a new one"
                )
        arr = np.asarray(action, dtype=np.float64)
        if arr.shape not in ((1,), ()):  # a wrong shape is a caller's bug, not an action
            raise ValueError(f"action must have shape (1,) (or be a number), got shape {arr.shape}")
        a = float(arr.reshape(-1)[0])
        if math.isnan(a):
            raise ValueError("action is NaN")
        a = min(1.0, max(-1.0, a))
        s, z, book, pipe = self.state, self._z, self._book, self.pipeline
        if z.size:
            self.np_random.standard_normal(out=z)
        a_prev = s[sim.A_PREV]
        r, end = ep.decide_packed(
            s, a, pipe.points, pipe.cumulative, self.episode_setup.packed, z, book, self.max_decisions
        )
        self.trail.append((s[sim.X], s[sim.Y], s[sim.PSI]))
        if self._vision is not None:  # the book's count in view stays the true geometry's
            r = self._vision.step(s, pipe.points, pipe.cumulative, self.np_random, r, a_prev)
        self.last_reward = r
        self.episode_return += r
        if self.render_mode == "human":
            self.render()
        if past_end:  # the episode's summary again, in arrays of its own (no object shared between infos)
            self._summary = {key: value.copy() for key, value in self._summary.items()}
            end = self._end
        else:  # the summary of the episode so far, and how it ended if it did
            self._end = end
            self._summary = episode_summary(book, s) | end_info(end)
        info = self._info()
        return self._observation(), r, end == ep.PIPE_END, end == ep.TIME_LIMIT, info

    @property
    def book(self) -> np.ndarray:
        """A copy of the episode's book (:mod:`pipefollow.sim.episode`): its counts so far."""
        return self._book.copy()

    def _observation(self) -> np.ndarray:
        if self._vision is None:
            return observation(self.state, self.setup)
        return self._vision.observation(self.state, self.setup.observation_space.dtype, self.setup.obs_slots)

    def _info(self) -> dict[str, Any]:
        info = state_infos(self.state)
        if self._vision is not None:
            info.update(self._vision.info())
        info.update(self._summary)  # made anew by each reset and step
        return info

    def __getstate__(self) -> dict[str, Any]:
        """The environment without its rendering's figure (a copy draws a new one when it renders)."""
        state = self.__dict__.copy()
        state["_scene"] = None
        return state

    def render(self):
        """The paper's Fig. 2 view: an RGB array (``"rgb_array"``) or a Matplotlib window (``"human"``).

        One figure is made on the first call and updated after that; in ``"human"`` mode
        ``reset`` and ``step`` render by themselves, and :meth:`close` closes the window.
        """
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array'")
            return None
        from pipefollow.envs.render import Scene

        if self._scene is None or self._scene.pipeline is not self.pipeline:
            self.close()
            self._scene = Scene(self.pipeline, self.params, pyplot=self.render_mode == "human")
            if self.render_mode == "human":
                self._scene.open_window()
        self._scene.update(self.state, np.array(self.trail), self.last_reward, self.episode_return)
        if self.render_mode == "human":
            self._scene.show(pause=1.0 / self.metadata["render_fps"])
            return None
        view = self._scene.rgb()
        if self._vision is not None:  # the camera image and the detection beside the Fig. 2 view
            view = np.hstack([view, self._vision.panel(view.shape[0])])
        return view

    def close(self):
        """Close the rendering's figure (and its window)."""
        if self._scene is not None:
            self._scene.close()
            self._scene = None
