r"""Disturbances and faults: ocean current, camera noise, missed detections, buried stretches.

All are off by default (:data:`NO_DISTURBANCE`), and then the simulation is the paper's, number
for number. The record :class:`Disturbance` is the ``disturbance`` field of
:class:`~pipefollow.sim.decision.SimParams`, so the environment and the compiled loops take it.

* **Ocean current** (Fossen 2021, §10.3): constant speed ``V_c`` and direction ``β_c`` (the
  direction it flows *towards*, clockwise from north) in the north-east frame. The vehicle model
  of eq. 16 acts on the velocity relative to the water ``ν_r = ν − ν_c`` with
  ``ν_c = R(ψ)ᵀ [V_c cos β_c, V_c sin β_c, 0]``. Optionally ``V_c`` and ``β_c`` vary slowly as a
  first-order Gauss–Markov process updated once per decision.
* **Camera**: Gaussian noise of standard deviation ``camera_noise`` (m) on the detected end
  points; a missed detection with probability ``miss_prob`` per camera reading (the pipe counts as
  not seen); buried stretches, arc-length intervals of the pipe the camera cannot see.

Random numbers: every camera reading (the reset's and each decision's) consumes
:func:`noise_layout`\\ ``(d)[2]`` standard normals, drawn by the caller from a seeded
``numpy.random.Generator`` and handed to the compiled code as an array ``z`` (the environment
draws from its ``np_random``, the compiled loops from the generator they are given):
``z[0:2]`` drive the current's variation (if on), the next four the camera noise on
``(x1, y1, x2, y_near)`` (if on), the next the missed detection (if on): the reading is
missed when ``Φ(z) < miss_prob``, which has probability ``miss_prob``; then one for the DVL's
noise and one for the gyro's (each if on; :func:`sensor_offsets`).

* **Motion sensors** (beyond the paper): a DVL reading the sway velocity over ground with white
  noise of s.d. ``dvl_noise`` (m/s) and a gyro reading the yaw rate with s.d. ``gyro_noise``
  (rad/s), read with every camera reading; only a learner that observes them
  (:mod:`pipefollow.sim.observation`) sees them.

TOML tables are read and checked here too (:func:`disturbance_from_dict`); single values with
:func:`non_negative` and :func:`probability`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, NamedTuple

from numba import njit
from numba.np.unsafe.ndarray import to_fixed_tuple

from pipefollow.sim import records

MAX_BURIED = 4  # buried stretches a scenario can hold
NO_BURIAL = (math.inf, math.inf, math.inf, math.inf)  # the buried-stretch slots when none is buried


class DisturbanceError(ValueError):
    """A disturbance setting that cannot be used; the message names the input."""


class Disturbance(NamedTuple):
    """Disturbances and faults of a simulation (all off by default).

    Buried stretches are up to :data:`MAX_BURIED` arc-length intervals ``[buried_from[k],
    buried_to[k]]``, sorted and disjoint; unused slots hold ``inf``.
    """

    current_speed: float = 0.0  # V_c (m/s), mean speed of the current
    current_direction: float = 0.0  # β_c (rad), direction it flows towards, clockwise from north
    current_time_constant: float = 0.0  # T_c (s) of the Gauss–Markov variation; 0 = constant
    current_speed_sd: float = 0.0  # stationary standard deviation of V_c (m/s)
    current_direction_sd: float = 0.0  # stationary standard deviation of β_c (rad)
    camera_noise: float = 0.0  # standard deviation of the end-point noise (m)
    miss_prob: float = 0.0  # probability of a missed detection per camera reading
    dvl_noise: float = 0.0  # standard deviation of the DVL's sway velocity over ground (m/s)
    gyro_noise: float = 0.0  # standard deviation of the gyro's yaw rate (rad/s)
    buried_from: tuple[float, float, float, float] = NO_BURIAL  # starts of buried stretches (m)
    buried_to: tuple[float, float, float, float] = NO_BURIAL  # their ends (m)


NO_DISTURBANCE = Disturbance()
PACKED_SIZE = records.size(NO_DISTURBANCE)  # floats of a packed Disturbance
_AT = records.offsets(NO_DISTURBANCE)
_SCALARS = _AT["buried_from"]  # the scalar fields come first, up to the buried stretches
_FROM, _TO = _AT["buried_from"], _AT["buried_to"]


def pack(d: Disturbance) -> list[float]:
    """``d`` as a flat list of floats (see :func:`unpack`)."""
    return records.flatten(d)


@njit(cache=True)
def unpack(a, i):
    """The record packed at ``a[i : i + PACKED_SIZE]``, inside compiled code."""
    scalars = to_fixed_tuple(a[i : i + _SCALARS], _SCALARS)
    buried_from = to_fixed_tuple(a[i + _FROM : i + _FROM + MAX_BURIED], MAX_BURIED)
    buried_to = to_fixed_tuple(a[i + _TO : i + _TO + MAX_BURIED], MAX_BURIED)
    return Disturbance(*scalars, buried_from, buried_to)


@njit(cache=True)
def noise_layout(d):
    """``(camera offset, miss offset, count)`` of the standard normals ``z`` of one reading."""
    varying = d.current_time_constant > 0.0 and (d.current_speed_sd > 0.0 or d.current_direction_sd > 0.0)
    cam = 2 if varying else 0
    miss = cam + (4 if d.camera_noise > 0.0 else 0)
    dvl, gyro = sensor_offsets(d)
    return cam, miss, gyro + (1 if d.gyro_noise > 0.0 else 0)


@njit(cache=True)
def sensor_offsets(d):
    """``(DVL offset, gyro offset)`` of the motion sensors' normals in ``z``, after the camera's."""
    varying = d.current_time_constant > 0.0 and (d.current_speed_sd > 0.0 or d.current_direction_sd > 0.0)
    dvl = (2 if varying else 0) + (4 if d.camera_noise > 0.0 else 0) + (1 if d.miss_prob > 0.0 else 0)
    return dvl, dvl + (1 if d.dvl_noise > 0.0 else 0)


def noise_count(d: Disturbance) -> int:
    """Standard normals consumed per camera reading (0 without random disturbances)."""
    return int(noise_layout(d)[2])


@njit(cache=True)
def vary_current(speed, direction, d, seconds, z0, z1):
    """One step of the first-order Gauss–Markov current over ``seconds``: new ``(V_c, β_c)``.

    ``x ← x̄ + φ (x − x̄) + σ √(1 − φ²) z`` with ``φ = exp(−seconds / T_c)``: the exact
    discretization of an Ornstein–Uhlenbeck process with mean x̄, stationary s.d. σ and time
    constant T_c. The speed is kept ≥ 0.
    """
    phi = math.exp(-seconds / d.current_time_constant)
    k = math.sqrt(1.0 - phi * phi)
    speed = d.current_speed + phi * (speed - d.current_speed) + d.current_speed_sd * k * z0
    mean_dir, sd_dir = d.current_direction, d.current_direction_sd
    direction = mean_dir + phi * (direction - mean_dir) + sd_dir * k * z1
    return max(speed, 0.0), direction


@njit(cache=True)
def missed(d, z):
    """A missed detection for the standard normal ``z``: ``Φ(z) < miss_prob`` (always at 1)."""
    if d.miss_prob >= 1.0:
        return True
    return 0.5 * math.erfc(-z / math.sqrt(2.0)) < d.miss_prob


# ---------------------------------------------------------------------------------------------
# Construction and checks


def _number(value: Any, name: str, source: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise DisturbanceError(f"{source}{name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise DisturbanceError(f"{source}{name} must be a finite number, got {value}")
    return value


def non_negative(value: Any, name: str, source: str = "") -> float:
    """``value`` as a finite float ≥ 0; a :class:`DisturbanceError` naming ``source`` and ``name``."""
    value = _number(value, name, source)
    if value < 0.0:
        raise DisturbanceError(f"{source}{name} must be ≥ 0, got {value:g}")
    return value


def probability(value: Any, name: str, source: str = "") -> float:
    """``value`` as a float in [0, 1]; a :class:`DisturbanceError` naming ``source`` and ``name``."""
    value = _number(value, name, source)
    if not 0.0 <= value <= 1.0:
        raise DisturbanceError(f"{source}{name} must be a probability in [0, 1], got {value:g}")
    return value


def _buried(value: Any, name: str, source: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
    if not isinstance(value, list | tuple) or len(value) > MAX_BURIED:
        raise DisturbanceError(f"{source}{name} must be a list of at most {MAX_BURIED} [from, to] pairs (m)")
    starts, ends = list(NO_BURIAL), list(NO_BURIAL)
    last = -math.inf
    for k, pair in enumerate(value):
        if not isinstance(pair, list | tuple) or len(pair) != 2:
            raise DisturbanceError(f"{source}{name}[{k}] must be a pair [from, to] (m), got {pair!r}")
        s0 = non_negative(pair[0], f"{name}[{k}] from", source)
        s1 = _number(pair[1], f"{name}[{k}] to", source)
        if not s0 < s1:
            raise DisturbanceError(f"{source}{name}[{k}] must have from < to, got [{s0:g}, {s1:g}]")
        if s0 < last:
            raise DisturbanceError(f"{source}{name} must be sorted and must not overlap")
        starts[k], ends[k] = s0, s1
        last = s1
    return tuple(starts), tuple(ends)


def make_disturbance(
    current_speed: float = 0.0,
    current_direction_deg: float = 0.0,
    *,
    current_time_constant: float = 0.0,
    current_speed_sd: float = 0.0,
    current_direction_sd_deg: float = 0.0,
    camera_noise: float = 0.0,
    miss_prob: float = 0.0,
    buried: list | tuple = (),
    dvl_noise: float = 0.0,
    gyro_noise_deg: float = 0.0,
    source: str = "",
) -> Disturbance:
    """A checked :class:`Disturbance` in user units (m/s, degrees, m; buried as ``[[from, to], ...]``).

    ``dvl_noise`` is in m/s, ``gyro_noise_deg`` in degrees per second.

    Raises:
        DisturbanceError: a value out of range; the message starts with ``source``.
    """
    src = f"{source}: " if source else ""
    speed = non_negative(current_speed, "current_speed", src)
    direction = _number(current_direction_deg, "current_direction_deg", src)
    tc = non_negative(current_time_constant, "current_time_constant", src)
    speed_sd = non_negative(current_speed_sd, "current_speed_sd", src)
    dir_sd = non_negative(current_direction_sd_deg, "current_direction_sd_deg", src)
    if (speed_sd > 0.0 or dir_sd > 0.0) and tc <= 0.0:
        raise DisturbanceError(f"{src}a varying current needs current_time_constant > 0 (s)")
    starts, ends = _buried(list(buried), "buried", src)
    return Disturbance(
        speed,
        math.radians(direction),
        tc,
        speed_sd,
        math.radians(dir_sd),
        non_negative(camera_noise, "camera_noise", src),
        probability(miss_prob, "miss_prob", src),
        non_negative(dvl_noise, "dvl_noise", src),
        math.radians(non_negative(gyro_noise_deg, "gyro_noise_deg", src)),
        starts,
        ends,
    )


def check(d: Disturbance) -> Disturbance:
    """Check a record built by hand (radians inside); returns it unchanged or raises."""
    if not isinstance(d, Disturbance):
        raise DisturbanceError(f"disturbance must be a Disturbance, got {type(d).__name__}")
    buried = [(a, b) for a, b in zip(d.buried_from, d.buried_to, strict=True) if math.isfinite(a)]
    same = make_disturbance(
        d.current_speed,
        math.degrees(d.current_direction),
        current_time_constant=d.current_time_constant,
        current_speed_sd=d.current_speed_sd,
        current_direction_sd_deg=math.degrees(d.current_direction_sd),
        camera_noise=d.camera_noise,
        miss_prob=d.miss_prob,
        buried=buried,
        dvl_noise=d.dvl_noise,
        gyro_noise_deg=math.degrees(d.gyro_noise),
    )
    if (same.buried_from, same.buried_to) != (tuple(d.buried_from), tuple(d.buried_to)):
        raise DisturbanceError("unused buried slots must hold inf at both ends, after the used ones")
    return d


TOML_KEYS = (
    "current_speed",
    "current_direction_deg",
    "current_time_constant",
    "current_speed_sd",
    "current_direction_sd_deg",
    "camera_noise",
    "miss_prob",
    "buried",
    "dvl_noise",
    "gyro_noise_deg",
)


def disturbance_from_dict(d: Mapping[str, Any], source: str = "disturbance") -> Disturbance:
    """A scenario from a TOML table or JSON object with the keys :data:`TOML_KEYS` (user units).

    Example::

        [disturbance]
        current_speed = 0.1          # m/s
        current_direction_deg = 90   # towards east
        camera_noise = 0.05          # m
        miss_prob = 0.02
        buried = [[6.0, 7.5]]        # arc length (m)

    Raises:
        DisturbanceError: an unknown key or a value out of range, named with ``source``.
    """
    if not isinstance(d, Mapping):
        raise DisturbanceError(f"{source}: must be a table, got {type(d).__name__}")
    unknown = sorted(set(d) - set(TOML_KEYS))
    if unknown:
        raise DisturbanceError(f"{source}: unknown key '{unknown[0]}'; allowed: {', '.join(TOML_KEYS)}")
    return make_disturbance(**dict(d), source=source)


def to_dict(d: Disturbance) -> dict[str, Any]:
    """The user-unit table of ``d`` (inverse of :func:`disturbance_from_dict`)."""
    return {
        "current_speed": d.current_speed,
        "current_direction_deg": math.degrees(d.current_direction),
        "current_time_constant": d.current_time_constant,
        "current_speed_sd": d.current_speed_sd,
        "current_direction_sd_deg": math.degrees(d.current_direction_sd),
        "camera_noise": d.camera_noise,
        "miss_prob": d.miss_prob,
        "buried": [[a, b] for a, b in zip(d.buried_from, d.buried_to, strict=True) if math.isfinite(a)],
        "dvl_noise": d.dvl_noise,
        "gyro_noise_deg": math.degrees(d.gyro_noise),
    }
