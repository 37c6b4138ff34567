r"""A downward-looking multibeam profiler: a fan of beams across track, ranges to seabed and pipe.

The camera of the paper fails in murky water; inspection AUVs track pipelines with sonar instead
(HUGIN's pipeline tracking with a multibeam echosounder, Midtgaard, Krogstad & Hagen 2011; SeeByte
AUTOTRACKER), whose ranges do not depend on turbidity. This module renders one *ping* of such a
profiler; :mod:`pipefollow.perception.sonar_detect` finds the pipe in it.

Geometry. The transducer flies ``altitude`` above the mean seabed at the forward position
``along`` (camera metres, default 0: under the AUV's centre) of the camera frame of
:mod:`pipefollow.sim.camera` (``x`` lateral, positive to starboard; ``y`` forward). The fan is
the plane across track through it, vertical or tilted forward by ``pitch``: it meets a flat
seabed on the line ``y = along + altitude · tan(pitch)``. Beam ``i`` points at the angle ``θ_i``
from the fan's axis, positive to starboard, the angles evenly spaced over ``±swath/2``; a ray at
angle ``φ`` has the direction ``(sin φ, cos φ sin τ, cos φ cos τ)`` (lateral, forward, down;
``τ`` the pitch). So a point at range ``r`` lies at lateral ``x = r sin φ`` and depth
``r cos φ cos τ``.

* **Seabed**: the height ``g(x) = x·tan(slope) + roughness(x)`` above the mean seabed; the
  roughness is a sum of :data:`ROUGHNESS_WAVES` cosines of random phase and wavelengths between
  :data:`ROUGHNESS_WAVELENGTHS`, scaled to an RMS of ``roughness`` (m), drawn per ping.
* **Pipe**: a cylinder of ``diameter`` whose axis lies ``R(1 − 2b)`` above the seabed under it
  (``R`` the radius, ``b`` the burial: the share of the diameter below the seabed; 0 = lying on
  it, ½ = top half above, 1 = the top flush with the seabed: invisible). Where a segment of the
  pipeline polyline crosses the fan's seabed line at angle ``α`` to the track, a vertical fan
  cuts the cylinder in the
  ellipse ``((x − x_c) cos α)² + (z − z_axis)² = R²`` when vertical; a ray's range to the pipe is
  the near root of ``|(r d − p) × a| = R`` (``d`` the ray's direction, ``p`` a point of the
  axis, ``a`` its direction), exact for any pitch. Each segment near the fan is a cylinder of its
  own length (lengthened by ``R`` at both ends, which closes the wedge between two segments at a
  bend). A stretch in ``buried_from``/``buried_to``
  (the disturbance's buried stretches, :mod:`pipefollow.sim.disturbance`) is fully buried.
* **A beam's range**: the mean of ``sub_rays`` rays spread evenly over the beam's −3 dB width
  (the beam width smooths the profile over its footprint), each ray's range the nearer of the
  seabed and the pipe; then Gaussian range noise of s.d. ``range_noise`` (from the caller's
  ``numpy.random.Generator``), then quantised to ``range_resolution``. A beam without a bottom
  detection (probability ``dropout``) reads NaN. On a flat seabed with ``beam_width = 0`` a beam
  reads exactly ``altitude / cos θ`` before noise and quantisation.

Parameters and their sources (docs/decisions.md, "Sonar"):

=================  ===========  ==============================================================
field              default      source
=================  ===========  ==============================================================
pitch              0° / 45°     :data:`DOWNWARD_SONAR` / :data:`LOOK_AHEAD_SONAR`: R2Sonic
                                heads steer the receive fan ±45° (receiver tilt, R2Sonic
                                manual); at 45° and 2 m the fan meets the seabed 2 m ahead,
                                inside the camera's 3 m (a fan under the AUV follows poorly:
                                docs/decisions.md)
altitude           2.0 m        the camera's: the renderer's light path assumes 2 m
                                (``Water.altitude``); a 2 m wide footprint at 2 m is a ±26.6°
                                lateral field of view, a plausible camera
n_beams            128          the R2Sonic 2024 forms 256 beams (R2Sonic operation manual);
                                every second one keeps the render cheap
swath              120°         R2Sonic 2024: opening angle 10°–160° selectable; ±60° at 2 m
                                covers 6.9 m across, 3.5× the camera's 2 m
beam_width         1.0°         Kongsberg EM 2040: beams of 0.5° × 1° or 1° × 1° (product
                                description); the wider, conservative one
range_resolution   0.01 m       c / 2B = 1500 / (2 · 80 kHz) = 9.4 mm for the WBMS's 80 kHz
                                bandwidth (Norbit WBMS manual)
range_noise        0.01 m       of the order of the range resolution (conservative at 2 m)
frequency          400 kHz      R2Sonic 2024: 200–400 kHz; Norbit WBMS: optimised for 400 kHz
                                (manuals); documentation only: nothing here depends on it,
                                attenuation over 2 m being negligible
pipe diameter      0.25 m       the renderer's pipe (``Water.pipe_diameter``); subsea lines
                                range from 6–12 in (0.15–0.3 m) flowlines to 42–44 in trunk
                                lines (Langeled, ≈1.1 m)
=================  ===========  ==============================================================

Randomness: :func:`render_ping` draws, in this order, ``n_beams`` standard normals (range noise,
if ``range_noise > 0``), ``n_beams`` uniforms (dropouts, if ``dropout > 0``) and
``2·ROUGHNESS_WAVES`` uniforms (roughness, if ``roughness > 0``) from the generator it is given.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.sim.disturbance import NO_BURIAL

ROUGHNESS_WAVES = 8  # cosines of the seabed's roughness per ping
ROUGHNESS_WAVELENGTHS = (0.3, 4.0)  # m: shortest and longest wavelength (log-uniform)
MAX_SEGMENTS = 16  # segments of the pipeline near the fan that one ping renders


class SonarError(ValueError):
    """A sonar setting that cannot be used; the message names the field."""


class Sonar(NamedTuple):
    """A multibeam profiler's settings (units in the comments; sources in the module docstring)."""

    n_beams: int = 128  # beams across track, [8, 1024]
    swath_deg: float = 120.0  # total opening angle (°), (0, 160]
    beam_width_deg: float = 1.0  # across-track −3 dB beam width (°), [0, 10]
    sub_rays: int = 3  # rays averaged over a beam's width, [1, 32]
    altitude: float = 2.0  # transducer height above the mean seabed (m), (0.2, 50]
    along: float = 0.0  # forward position of the transducer in camera metres, [-5, 5]
    pitch_deg: float = 0.0  # forward tilt of the fan from the vertical (°), [0, 60]
    range_resolution: float = 0.01  # range quantisation step (m), [0, 0.5]; 0 = none
    range_noise: float = 0.01  # Gaussian range noise s.d. (m), [0, 0.5]
    dropout: float = 0.0  # probability that a beam has no bottom detection (NaN), [0, 0.5]
    roughness: float = 0.0  # RMS seabed roughness (m), [0, 0.2]
    seabed_slope_deg: float = 0.0  # across-track seabed slope (°, rising to starboard), [-20, 20]
    frequency_khz: float = 400.0  # documentation only, (0, 2000]


_RANGES = {  # field: (low, high, low end closed)
    "n_beams": (8, 1024, True),
    "swath_deg": (0.0, 160.0, False),
    "beam_width_deg": (0.0, 10.0, True),
    "sub_rays": (1, 32, True),
    "altitude": (0.2, 50.0, False),
    "along": (-5.0, 5.0, True),
    "pitch_deg": (0.0, 60.0, True),
    "range_resolution": (0.0, 0.5, True),
    "range_noise": (0.0, 0.5, True),
    "dropout": (0.0, 0.5, True),
    "roughness": (0.0, 0.2, True),
    "seabed_slope_deg": (-20.0, 20.0, True),
    "frequency_khz": (0.0, 2000.0, False),
}
_WHOLE = ("n_beams", "sub_rays")

DOWNWARD_SONAR = Sonar()  # the fan straight down under the AUV's centre
LOOK_AHEAD_SONAR = Sonar(pitch_deg=45.0)  # the fan tilted forward, meeting the seabed 2 m ahead


def check_sonar(s: Sonar) -> Sonar:
    """``s`` (whole-number fields as ints) if every field is in range; else a one-line :class:`SonarError`."""
    if not isinstance(s, Sonar):
        raise SonarError(f"sonar must be a Sonar record, got {type(s).__name__}")
    check_ranges(s, _RANGES, _WHOLE, SonarError, "sonar")
    return s._replace(n_beams=int(s.n_beams), sub_rays=int(s.sub_rays))


def check_ranges(s, ranges: dict, whole: tuple, error: type[ValueError], what: str) -> None:
    """A one-line ``error`` naming the first field of record ``s`` outside ``ranges`` (a sonar's settings).

    ``ranges`` maps a field to ``(low, high, low end closed)``; the fields in ``whole`` must be whole
    numbers; every field a finite number.
    """
    for name, (lo, hi, closed) in ranges.items():
        value = getattr(s, name)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise error(f"{what} setting {name} must be a number, got {value!r}")
        if not math.isfinite(value):
            raise error(f"{what} setting {name} must be a finite number, got {value}")
        if name in whole and value != int(value):
            raise error(f"{what} setting {name} must be a whole number, got {value}")
        low_ok = value >= lo if closed else value > lo
        if not (math.isfinite(value) and low_ok and value <= hi):
            bracket = "[" if closed else "("
            raise error(f"{what} setting {name} must be in {bracket}{lo}, {hi}], got {value}")


def make_sonar(**fields) -> Sonar:
    """A checked :class:`Sonar` from keyword fields (the others at their defaults)."""
    unknown = sorted(set(fields) - set(Sonar._fields))
    if unknown:
        raise SonarError(f"unknown sonar setting(s) {unknown}; allowed: {', '.join(Sonar._fields)}")
    return check_sonar(Sonar(**fields))


def check_pipe(diameter: float, burial: float) -> None:
    """A one-line ``ValueError`` naming ``diameter`` or ``burial`` when out of range."""
    if not (isinstance(diameter, int | float) and math.isfinite(diameter) and 0.02 <= diameter <= 2.0):
        raise ValueError(f"diameter must be a pipe diameter in [0.02, 2] m, got {diameter!r}")
    if not (isinstance(burial, int | float) and math.isfinite(burial) and 0.0 <= burial <= 1.0):
        raise ValueError(f"burial must be the buried share of the diameter in [0, 1], got {burial!r}")


def fan_line(sonar: Sonar = DOWNWARD_SONAR) -> float:
    """Forward position (camera metres) of the fan's line on the mean seabed.

    ``along + altitude · tan(pitch)``.
    """
    return sonar.along + sonar.altitude * math.tan(math.radians(sonar.pitch_deg))


def beam_angles(sonar: Sonar = DOWNWARD_SONAR) -> np.ndarray:
    """The beams' angles from the vertical (rad, positive to starboard), port to starboard."""
    half = 0.5 * math.radians(sonar.swath_deg)
    return np.linspace(-half, half, sonar.n_beams)


class Ping(NamedTuple):
    """One rendered profile: the beams' angles and ranges (NaN: no bottom detection), and the truth."""

    angles: np.ndarray  # rad from the fan's axis, positive to starboard
    ranges: np.ndarray  # slant ranges (m)
    pipe_x: np.ndarray  # lateral positions (camera metres) where the pipe crosses the fan's seabed line ...
    pipe_visible: np.ndarray  # ... and whether it stands above the seabed there (not fully buried)
    along: float = 0.0  # the transducer's forward position (camera metres) ...
    pitch: float = 0.0  # ... and the fan's forward tilt (rad)


def render_ping(
    points: np.ndarray,
    cum: np.ndarray,
    pose: tuple[float, float, float],
    rng: np.random.Generator,
    sonar: Sonar = DOWNWARD_SONAR,
    diameter: float = 0.25,
    burial: float = 0.0,
    buried_from=NO_BURIAL,
    buried_to=NO_BURIAL,
    angles: np.ndarray | None = None,
    out: np.ndarray | None = None,
) -> Ping:
    """One ping of ``sonar`` from pose ``(x, y, ψ)`` over the pipeline ``points``/``cum``.

    ``sonar`` is taken as checked (:func:`make_sonar`); ``angles`` (from :func:`beam_angles`) and
    ``out`` (float64 of ``n_beams``) may be passed in to save their allocation in a loop. An
    empty ``points`` (shape ``(0, 2)``) is a seabed without a pipe.
    """
    n = sonar.n_beams
    if angles is None:
        angles = beam_angles(sonar)
    if out is None:
        out = np.empty(n)
    z = rng.standard_normal(n) if sonar.range_noise > 0.0 else _NONE
    u = rng.random(n) if sonar.dropout > 0.0 else _NONE
    waves = rng.random(2 * ROUGHNESS_WAVES) if sonar.roughness > 0.0 else _NONE
    seg = np.empty((MAX_SEGMENTS, 7))
    seen = np.zeros(MAX_SEGMENTS, dtype=np.bool_)
    crosses = np.zeros(MAX_SEGMENTS, dtype=np.bool_)
    x, y, psi = pose
    if buried_from is NO_BURIAL and buried_to is NO_BURIAL:
        buried = _NO_BURIAL, _NO_BURIAL
    else:
        buried = np.asarray(buried_from, dtype=np.float64), np.asarray(buried_to, dtype=np.float64)
    k = _render(
        points, cum, float(x), float(y), float(psi), angles, _settings(sonar), float(diameter), float(burial),
        buried[0], buried[1], z, u, waves, out, seg, seen, crosses,
    )  # fmt: skip
    c = crosses[:k]
    return Ping(angles, out, seg[:k, 5][c], seen[:k][c], sonar.along, math.radians(sonar.pitch_deg))


_NONE = np.zeros(0)
_NO_BURIAL = np.array(NO_BURIAL)


@functools.lru_cache(maxsize=64)
def _settings(s: Sonar) -> np.ndarray:
    """The settings the compiled render reads, as a float array (a record costs µs to pass).

    Cached per record (records are immutable); the array is read-only.
    """
    a = np.array(
        [
            math.radians(s.beam_width_deg), s.sub_rays, s.altitude, s.along, s.range_resolution,
            s.range_noise, s.dropout, s.roughness, math.tan(math.radians(s.seabed_slope_deg)),
            math.radians(s.pitch_deg),
        ]
    )  # fmt: skip
    a.flags.writeable = False
    return a


@njit(cache=True)
def seabed_height(x, slope, roughness, waves):
    """Seabed height (m) above the mean at lateral ``x``: slope plus the roughness's cosines."""
    h = x * slope
    if roughness > 0.0:
        nw = waves.shape[0] // 2
        lo, hi = math.log(ROUGHNESS_WAVELENGTHS[0]), math.log(ROUGHNESS_WAVELENGTHS[1])
        amp = roughness * math.sqrt(2.0 / nw)  # RMS of a cosine of amplitude A is A/√2
        for k in range(nw):
            wavelength = math.exp(lo + (hi - lo) * waves[2 * k])
            h += amp * math.cos(2.0 * math.pi * (x / wavelength + waves[2 * k + 1]))
    return h


@njit(cache=True)
def seabed_range(s, c, altitude, slope, roughness, waves):
    """Range (m) to the seabed along a ray with lateral component ``s`` and downward component ``c``.

    A plane (no roughness) exactly: ``altitude − r s·tan β = r c``; with roughness, a fixed-point
    iteration from there (the roughness's slopes are small).
    """
    r = altitude / (c + s * slope)
    if roughness > 0.0:
        for _ in range(6):
            r = (altitude - seabed_height(r * s, slope, roughness, waves)) / c
    return r


@njit(cache=True)
def cylinder_range(dx, dy, dz, px, py, pz, ax, ay, radius, length=math.inf):
    """Range (m) along the unit ray ``d`` from the transducer to the near side of a cylinder, or inf.

    The cylinder's axis starts at ``p`` (relative to the transducer) and runs ``length`` along the
    horizontal unit vector ``(ax, ay, 0)``; coordinates (lateral, forward, down). The near root of
    ``|(r d − p) × a|² = radius²`` (with ``q = d × a`` and ``w = p × a``:
    ``r² |q|² − 2 r q·w + |w|² − radius² = 0``), if its point lies along the axis within
    ``[−radius, length + radius]`` (the overlap closes the wedge between two segments at a bend).
    """
    qx, qy, qz = -dz * ay, dz * ax, dx * ay - dy * ax
    wx, wy, wz = -pz * ay, pz * ax, px * ay - py * ax
    qq = qx * qx + qy * qy + qz * qz
    qw = qx * wx + qy * wy + qz * wz
    ww = wx * wx + wy * wy + wz * wz
    disc = qw * qw - qq * (ww - radius * radius)
    if disc < 0.0 or qq <= 0.0:
        return math.inf
    r = (qw - math.sqrt(disc)) / qq
    if r <= 0.0:
        return math.inf
    t = (r * dx - px) * ax + (r * dy - py) * ay  # along the axis from its start
    if t < -radius or t > length + radius:
        return math.inf
    return r


@njit(cache=True)
def near_segments(points, cum, x, y, psi, line, margin, buried_from, buried_to, seg, open_, crosses):
    """The pipeline's segments that come within ``margin`` (m) of the fan's seabed line.

    ``line`` is the line's forward position in the camera frame of pose (x, y, ψ). Fills, for up
    to ``len(seg)`` segments, ``seg[k] = (lateral, forward of the start, unit direction lateral,
    forward, length, lateral where the segment is nearest the line, arc length there)``,
    ``open_[k]`` (False inside a buried stretch) and ``crosses[k]`` (the segment crosses the line;
    a half-open test, so a vertex on the line counts once); returns how many.
    """
    cs, sn = math.cos(psi), math.sin(psi)
    n = 0
    if points.shape[0] < 2:
        return 0
    dx, dy = points[0, 0] - x, points[0, 1] - y
    al, af = -sn * dx + cs * dy, cs * dx + sn * dy
    for i in range(points.shape[0] - 1):
        dx, dy = points[i + 1, 0] - x, points[i + 1, 1] - y
        bl, bf = -sn * dx + cs * dy, cs * dx + sn * dy
        ta, tb = af - line, bf - line
        length = math.hypot(bl - al, bf - af)
        if min(ta, tb) <= margin and max(ta, tb) >= -margin and length > 0.0 and n < seg.shape[0]:
            cross = (ta < 0.0 <= tb) or (tb < 0.0 <= ta)
            if cross:
                t = ta / (ta - tb)
            else:
                t = 0.0 if abs(ta) <= abs(tb) else 1.0
            s = cum[i] + t * (cum[i + 1] - cum[i])
            buried = False
            for j in range(buried_from.shape[0]):
                if buried_from[j] <= s <= buried_to[j]:
                    buried = True
            seg[n, 0], seg[n, 1] = al, af
            seg[n, 2], seg[n, 3], seg[n, 4] = (bl - al) / length, (bf - af) / length, length
            seg[n, 5], seg[n, 6] = al + t * (bl - al), s
            open_[n] = not buried
            crosses[n] = cross
            n += 1
        al, af = bl, bf
    return n


@njit(cache=True)
def _render(
    points,
    cum,
    x,
    y,
    psi,
    angles,
    st,
    diameter,
    burial,
    buried_from,
    buried_to,
    z,
    u,
    waves,
    out,
    seg,
    seen,
    crosses,
):
    width, sub, altitude, along = st[0], int(st[1]), st[2], st[3]
    resolution, noise, dropout, roughness, slope, pitch = st[4], st[5], st[6], st[7], st[8], st[9]
    cos_t, sin_t = math.cos(pitch), math.sin(pitch)
    ahead = altitude * sin_t / cos_t  # the fan's seabed line, forward of the transducer
    radius = 0.5 * diameter
    # a point of the pipe at height z above the seabed lies on the fan z·tan τ nearer than the line
    margin = diameter * (1.0 + sin_t / cos_t) + radius
    n = near_segments(
        points, cum, x, y, psi, along + ahead, margin, buried_from, buried_to, seg, seen, crosses
    )
    visible = burial < 1.0  # at 1 the top is flush with the seabed
    depth = np.empty(n)
    for k in range(n):
        # the pipe rests on the seabed under it: the axis's depth below the transducer
        depth[k] = (
            altitude - seabed_height(seg[k, 5], slope, roughness, waves) - radius * (1.0 - 2.0 * burial)
        )
        seen[k] = seen[k] and visible
    for i in range(angles.shape[0]):
        total = 0.0
        for j in range(sub):
            phi = angles[i] + (width * ((j + 0.5) / sub - 0.5) if sub > 1 else 0.0)
            sp, cp = math.sin(phi), math.cos(phi)
            r = seabed_range(sp, cp * cos_t, altitude, slope, roughness, waves)
            for k in range(n):
                if seen[k]:
                    hit = cylinder_range(
                        sp, cp * sin_t, cp * cos_t, seg[k, 0], seg[k, 1] - along, depth[k],
                        seg[k, 2], seg[k, 3], radius, seg[k, 4],
                    )  # fmt: skip
                    r = min(r, hit)
            total += r
        r = total / sub
        if noise > 0.0:
            r += noise * z[i]
        if resolution > 0.0:
            r = resolution * math.floor(r / resolution + 0.5)
        if dropout > 0.0 and u[i] < dropout:
            r = math.nan
        out[i] = r
    return n


def profile_points(
    ranges: np.ndarray, angles: np.ndarray, pitch: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """A ping's points as lateral position (m) and height above the transducer (m, negative).

    ``pitch`` (rad) is the fan's forward tilt (``Ping.pitch``).
    """
    return ranges * np.sin(angles), -ranges * np.cos(angles) * math.cos(pitch)
