"""What the single and the vector environment share, defined once.

Both environments are shells around the same compiled decision (:mod:`pipefollow.sim.decision`);
this module holds everything else they have in common: the checks of their arguments and the
spaces (:func:`make_setup`), the reset options (:func:`parse_reset_options`), the start of an
episode with its draws in a fixed order (:func:`start_episode`), the info keys
(:func:`state_infos`) and the episode's summary so far (:func:`episode_summary`), which every
step's info carries. (Their pipeline argument
is read by :func:`pipefollow.sim.pipe_names.pipeline_source`.) The functions take one state of
shape ``(STATE_SIZE,)`` or a batch of shape ``(N, STATE_SIZE)`` and return arrays of the matching
shape, so the two environments cannot drift apart.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gymnasium import spaces

from pipefollow.files.limits import MAX_EPISODE_SECONDS
from pipefollow.files.paper_training import EPISODE_SECONDS
from pipefollow.perception.slots import observed
from pipefollow.sim import decision as sim
from pipefollow.sim import episode as ep
from pipefollow.sim.disturbance import Disturbance, check, disturbance_from_dict, noise_count
from pipefollow.sim.observation import bounds as observation_bounds
from pipefollow.sim.observation import names as observation_names
from pipefollow.sim.observation import slots as observation_slots
from pipefollow.sim.observation import units as observation_units
from pipefollow.sim.pipeline import Pipeline
from pipefollow.sim.suites import Suite, min_length_for

# The constructor arguments of the single environment that the vector environment shares.
SHARED_ARGUMENTS = (
    "episode_seconds",
    "start_lateral_noise",
    "start_heading_noise_deg",
    "params",
    "disturbance",
    "obs_dtype",
    "state",
)
# the camera's arguments (pipefollow.perception.camera.camera_settings), shared too
CAMERA_ARGUMENTS = ("camera", "observation", "reward_from", "water", "sensor")

RESET_OPTIONS = ("pipeline", "lateral_offset", "heading_offset_deg")

OBS_DTYPES = {"float64": np.float64, "float32": np.float32}

# Info keys: (key, first state slot, last slot + 1 or None for a scalar, boolean or not).
INFO_FIELDS = (
    ("pipe_in_view", sim.IN_VIEW, None, True),
    ("overridden", sim.OVERRIDDEN, None, True),
    ("e_dist", sim.E_DIST, None, False),
    ("e_angl", sim.E_ANGL, None, False),
    ("progress_m", sim.PROGRESS_MAX, None, False),
    ("pose", sim.X, sim.PSI + 1, False),
    ("nu", sim.U, sim.R + 1, False),
    ("waypoint", sim.WP_X, sim.WP_Y + 1, False),
    ("executed_action", sim.A_PREV, None, False),
    ("time_s", sim.TIME, None, False),
    ("y_near", sim.Y_NEAR, None, False),
    ("camera_missed", sim.MISSED, None, True),
    ("current", sim.CURRENT_SPEED, sim.CURRENT_DIR + 1, False),
)
# (key, first slot, boolean, index into the last axis): indexing with Ellipsis gives a 0-d array
_INFO_INDEX = tuple(
    (key, first, boolean, (Ellipsis, first if stop is None else slice(first, stop)))
    for key, first, stop, boolean in INFO_FIELDS
)


# The episode's summary, in every step's info: the episode so far, at its last step the whole episode.
SUMMARY_KEYS = ("episode_pipe_in_view", "episode_progress_m", "episode_rms_e_dist")


@dataclass(frozen=True)
class Setup:
    """The checked arguments both environments are built from, and their spaces."""

    episode_seconds: float
    max_decisions: int
    start_lateral_noise: float
    start_heading_noise_deg: float
    params: sim.SimParams
    packed: np.ndarray  # sim.pack_params(params)
    noise_count: int  # standard normals of one camera reading (0 without random disturbances)
    obs_dtype: type
    observation_space: spaces.Box
    action_space: spaces.Box
    state: str = "paper"  # the named state observed (pipefollow.sim.observation)
    obs_slots: np.ndarray = field(default_factory=lambda: observation_slots("paper"))  # its state slots

    @property
    def observation_names(self) -> tuple[str, ...]:
        """The names of the observation's entries (``x1, y1, x2, v_x`` and any measured ones)."""
        return observation_names(self.state)

    @property
    def observation_units(self) -> tuple[str, ...]:
        """Their units (``m, m, m, m/s`` and ``m/s`` for v_y, ``rad/s`` for r)."""
        return observation_units(self.state)

    @property
    def min_pipe_length(self) -> float:
        """The shortest random pipe an episode may draw (m)."""
        return min_length_for(self.episode_seconds)


def make_setup(
    episode_seconds: float = EPISODE_SECONDS,
    start_lateral_noise: float = 0.0,
    start_heading_noise_deg: float = 0.0,
    params: sim.SimParams = sim.PAPER_SIM,
    disturbance: Disturbance | dict[str, Any] | None = None,
    obs_dtype: str | type | np.dtype = "float64",
    state: str = "paper",
) -> Setup:
    """Check the environments' shared arguments (one-line ``ValueError`` naming the argument).

    ``state`` names the observation (:mod:`pipefollow.sim.observation`): the paper's
    ``(x1, y1, x2, v_x)`` (m, m, m, m/s) or it with the DVL's sway velocity over ground (m/s) and
    the gyro's yaw rate (rad/s).
    """
    slots = observation_slots(state)  # an unknown name: ValueError naming state
    decision_seconds = sim.decision_seconds(params)
    if not (
        isinstance(episode_seconds, int | float | np.number)
        and math.isfinite(episode_seconds)
        and decision_seconds <= episode_seconds <= MAX_EPISODE_SECONDS
    ):
        raise ValueError(
            f"episode_seconds must be from {decision_seconds:g} to {MAX_EPISODE_SECONDS:g}, "
            f"got {episode_seconds}"
        )
    for name, value in (
        ("start_lateral_noise", start_lateral_noise),
        ("start_heading_noise_deg", start_heading_noise_deg),
    ):
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"{name} must be a finite number ≥ 0, got {value}")
    try:
        dtype = np.dtype(obs_dtype).type
    except TypeError:
        dtype = None
    if dtype not in OBS_DTYPES.values():
        raise ValueError(f"obs_dtype must be one of {', '.join(OBS_DTYPES)}, got {obs_dtype!r}")
    if isinstance(disturbance, dict):
        disturbance = disturbance_from_dict(disturbance)
    if disturbance is not None:
        params = params._replace(disturbance=disturbance)
    check(params.disturbance)
    low, high = observation_bounds(state, params.camera)
    observation_space = spaces.Box(low=low.astype(dtype), high=high.astype(dtype), dtype=dtype)
    return Setup(
        episode_seconds=float(episode_seconds),
        max_decisions=int(round(float(episode_seconds) / decision_seconds)),
        start_lateral_noise=float(start_lateral_noise),
        start_heading_noise_deg=float(start_heading_noise_deg),
        params=params,
        packed=sim.pack_params(params),
        noise_count=noise_count(params.disturbance),
        obs_dtype=dtype,
        observation_space=observation_space,
        action_space=spaces.Box(-1.0, 1.0, (1,), dtype=np.float32),
        state=state,
        obs_slots=slots,
    )


def randomized_setup(setup: Setup, randomization, rng: np.random.Generator) -> Setup:
    """The setup of one episode under a :class:`~pipefollow.sim.randomization.Randomization`.

    Its disturbances are drawn from ``rng`` (:func:`pipefollow.sim.randomization.draw`, a fixed
    count of uniforms) and replace ``setup.params.disturbance``.
    """
    from dataclasses import replace

    from pipefollow.sim.randomization import draw

    d = draw(randomization, rng)
    params = setup.params._replace(disturbance=d)
    return replace(setup, params=params, packed=sim.pack_params(params), noise_count=noise_count(d))


_KEEP = object()  # the reset options do not switch the pipeline


@dataclass(frozen=True)
class ResetOptions:
    """The reset options both environments take (None: drawn from the start noise)."""

    pipeline: Any = _KEEP
    lateral_offset: float | None = None
    heading_offset_deg: float | None = None

    @property
    def switches_pipeline(self) -> bool:
        """Whether the options name a new pipeline."""
        return self.pipeline is not _KEEP


def parse_reset_options(options: dict[str, Any] | None, extra: tuple[str, ...] = ()) -> ResetOptions:
    """The reset options; an unknown key raises ``ValueError`` (``extra`` names keys the caller took)."""
    options = dict(options or {})
    unknown = sorted(set(options) - set(RESET_OPTIONS))
    if unknown:
        raise ValueError(f"unknown reset option(s) {unknown}; allowed: {', '.join(RESET_OPTIONS + extra)}")
    out = {}
    for key in ("lateral_offset", "heading_offset_deg"):
        value = options.get(key)
        if value is not None:
            if not math.isfinite(value):
                raise ValueError(f"reset option {key} must be a finite number, got {value}")
            value = float(value)
        out[key] = value
    return ResetOptions(options.get("pipeline", _KEEP), **out)


def start_episode(
    state: np.ndarray,
    suite: Suite | None,
    pipeline: Pipeline,
    rng: np.random.Generator,
    setup: Setup,
    z: np.ndarray,
    lateral_offset: float | None = None,
    heading_offset_deg: float | None = None,
) -> Pipeline:
    """Start an episode in ``state``; returns its pipeline (a new draw of ``suite`` if not None).

    The draws from ``rng``, in this order: the pipe (a family's), the lateral and the heading
    offset (each only with its start noise and no fixed value), the camera reading's normals
    (``z``, only with random disturbances). The AUV starts at rest on the first point, heading
    along the first segment, offset to starboard by ``lateral_offset`` (m) and turned by
    ``heading_offset_deg``.
    """
    if suite is not None:
        pipeline = suite.draw(rng, setup.min_pipe_length)
    lateral, heading_deg = lateral_offset, heading_offset_deg
    # without start noise no number is drawn: the generator then serves the random pipes alone
    if lateral is None:
        noise = setup.start_lateral_noise
        lateral = rng.uniform(-1.0, 1.0) * noise if noise > 0.0 else 0.0
    if heading_deg is None:
        noise = setup.start_heading_noise_deg
        heading_deg = rng.uniform(-1.0, 1.0) * noise if noise > 0.0 else 0.0
    p0, h = pipeline.points[0], pipeline.start_heading
    # positive lateral offset = to starboard of the pipe's direction
    x = p0[0] - math.sin(h) * float(lateral)
    y = p0[1] + math.cos(h) * float(lateral)
    psi = h + math.radians(float(heading_deg))
    if z.size:
        rng.standard_normal(out=z)
    sim.init_state_packed(state, pipeline.points, pipeline.cumulative, x, y, psi, setup.packed, z)
    return pipeline


def observation(states: np.ndarray, setup: Setup) -> np.ndarray:
    """Observations of one state or a batch: a new array of the setup's dtype.

    ``(x1, y1, x2, v_x)`` under the paper's state, and the measured entries of another.
    """
    # the paper's state is the leading slots: a slice, as cheap as before the named states
    return observed(states, setup.obs_dtype, None if setup.state == "paper" else setup.obs_slots)


def image_space(water) -> spaces.Box:
    """The observation space of ``observation="image"``: the grey camera image, ``(H, W, 1)`` uint8.

    Height × width × channel, Gymnasium's layout of images (its image wrappers and Stable-Baselines3's
    ``VecTransposeImage`` read it so); row 0 is the footprint's far edge.
    """
    return spaces.Box(0, 255, (water.height, water.width, 1), dtype=np.uint8)


def state_infos(states: np.ndarray) -> dict[str, np.ndarray]:
    """The info of one state (0-d and 1-d arrays) or of a batch (arrays with the batch dimension first).

    The numbers are views of one copy of ``states``: a step's info stays as it was when later
    steps change the state, and shares no object with another step's (as Gymnasium's checker
    demands), at a fraction of the cost of an array per key.
    """
    snap = np.array(states)
    if snap.ndim == 1:  # one state: a comparison of the whole state would cost more than three
        return {
            key: np.array(snap[first] != 0.0) if boolean else snap[index]
            for key, first, boolean, index in _INFO_INDEX
        }
    flags = snap != 0.0
    return {key: (flags if boolean else snap)[index] for key, _, boolean, index in _INFO_INDEX}


def end_info(ends) -> dict[str, np.ndarray]:
    """``reached_pipe_end`` of episodes from their end codes (:func:`pipefollow.sim.episode.end_of`).

    True where the episode ended at the pipe's far end (``terminated``); False while it goes on and
    after a time limit (``truncated``). A flag, not a string, so that every client that turns infos
    into tensors or HDF5 datasets (TorchRL, Minari) takes it. One code gives a 0-d array, a batch an
    array of the batch's length.
    """
    if isinstance(ends, int | np.integer):  # one environment, at every step: no array arithmetic
        return {"reached_pipe_end": np.array(ends == ep.PIPE_END)}
    return {"reached_pipe_end": np.asarray(ends) == ep.PIPE_END}


def episode_summary(book: np.ndarray, states: np.ndarray) -> dict[str, np.ndarray]:
    """The summary of episodes so far from their books (:mod:`pipefollow.sim.episode`) and states.

    One book and state, or a batch of each (rows). ``episode_pipe_in_view`` is the share of
    decisions that ended with the pipe in view (NaN before the first decision),
    ``episode_progress_m`` the arc length reached, ``episode_rms_e_dist`` the RMS of ``e_dist``
    over the decisions in view (NaN if none). Every value is float64.
    """
    if book.ndim == 1:  # one episode, at every step: plain floats cost a fraction of array arithmetic
        counts = book.tolist()
        d, n, e2 = counts[ep.DECISIONS], counts[ep.SEEN], counts[ep.E2]
        return {
            "episode_pipe_in_view": np.array(n / d if d > 0 else math.nan),
            "episode_progress_m": np.array(states.item(sim.PROGRESS_MAX)),
            "episode_rms_e_dist": np.array(math.sqrt(e2 / n) if n > 0 else math.nan),
        }
    decisions, seen, sum_e2 = book[..., ep.DECISIONS], book[..., ep.SEEN], book[..., ep.E2]
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(decisions > 0, seen / np.maximum(decisions, 1), np.nan)
        rms = np.where(seen > 0, np.sqrt(sum_e2 / np.maximum(seen, 1)), np.nan)
    return {
        "episode_pipe_in_view": share,
        "episode_progress_m": np.array(states[..., sim.PROGRESS_MAX], dtype=np.float64),
        "episode_rms_e_dist": rms,
    }
