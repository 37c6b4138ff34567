r"""A forward-looking imaging sonar: one ping's sector image of echo intensity over bearing and range.

The look-ahead profiler (:mod:`pipefollow.perception.sonar`) measures one line across the track;
in murky water its line does not show where the pipe goes (docs/decisions.md, "What a sensor could
give in murky water"). A forward-looking imaging sonar (FLS) insonifies a wide sector ahead with a
fan of narrow horizontal beams, each wide in the vertical, and records each beam's echo intensity
over range: the image of a strip of seabed ahead, in which a pipe shows as a bright highlight
followed by its acoustic shadow (Teledyne BlueView M900-130 and Blueprint Oculus M750d: a 130°
horizontal and a 20° vertical aperture). This module renders such an image;
:mod:`pipefollow.perception.imaging_detect` finds the pipe in it.

Geometry. The transducer flies ``altitude`` above a flat seabed at the forward position ``along``
(camera metres, :mod:`pipefollow.sim.camera`: ``x`` lateral to starboard, ``y`` forward), its
vertical beam's axis tilted ``tilt`` below the horizontal. Beam ``i`` looks along the bearing
``β_i`` (evenly spaced over ``±fov/2``, positive to starboard) in the horizontal plane; a point at
horizontal distance ``ρ`` along it lies at ``(ρ sin β, along + ρ cos β)``. Along each beam the
seabed is a height field sampled every ``step`` of ``ρ``: the seabed at 0, and where the beam's
line passes within the radius ``R`` of a pipe segment's axis at the distance ``d``, the pipe's top
``R(1 − 2b) + √(R² − d²)`` (``b`` the buried share of the diameter, as the profiler's; stretches
in ``buried_from``/``buried_to`` are fully buried).

Echo. Marching outwards, a sample is lit if no nearer sample rises higher in the transducer's
view (its depression angle is not above the lowest so far): the others lie in the acoustic shadow.
A lit sample at slant range ``r`` and depression ``δ`` spreads the energy
``μ · cos²θ · a · G(δ)²`` evenly over the slant ranges its ``step`` of ``ρ`` spans at the sample's
height, each range bin taking the share inside it (so a flat seabed's bins show no ripple from the
sampling; on the pipe's sloping face the span ignores the slope): ``μ``
the backscatter strength (1 for the seabed, ``pipe_strength`` for the pipe), ``θ`` the angle
between the surface normal and the direction to the transducer
(Lambert's law), ``a`` the sample's surface length, ``G`` the vertical beam pattern (Gaussian,
−3 dB at ``±vertical/2`` off the tilt, two-way). A bin's intensity is its energy divided by the
bin's width plus the noise floor ``floor`` (times ``sin² tilt``, the Lambert echo at the tilt; the
seabed's mean a bin there is ``sin² tilt / cos tilt``, so 0.05 is 3.5 % of it), times an
independent standard exponential (fully developed speckle: a Rayleigh amplitude). The image is
what the sonar's time-varied gain shows: spreading and absorption are taken as compensated.

Parameters and their sources (docs/decisions.md, "A forward-looking imaging sonar"):

=================  ===========  ==============================================================
field              default      source
=================  ===========  ==============================================================
n_beams            128          Oculus M750d: 512 beams over 130° at 750 kHz (datasheet);
                                every fourth one (1.0° apart) keeps the render cheap
fov                130°         BlueView M900-130 and Oculus M750d: 130° horizontal
vertical           20°          both: 20° vertical aperture
beam_width         1.0°         Oculus M750d 1° horizontal at 750 kHz; BlueView M900 1°
tilt               45°          mounted to look at the seabed 1.4–2.9 m ahead from 2 m: the
                                camera's depth of view (3 m) and beyond
altitude           2.0 m        the camera's (``Water.altitude``), as the profiler's
range_resolution   0.025 m      BlueView M900-130: 2.5 cm (datasheet); Oculus M750d 4 mm
range_min/max      2.2–4.4 m    slant ranges of the seabed 0.9–3.9 m ahead from 2 m
pipe_strength      5            a steel or concrete-coated pipe's echo over sand (an order
                                of magnitude in target strength per unit area; assumed)
floor              0.05         the noise floor in the shadows (× sin² tilt: 3.5 % of the
                                seabed's mean at the tilt)
=================  ===========  ==============================================================

Randomness: :func:`render_image` draws ``n_beams × n_bins`` standard exponentials (the speckle)
from the generator it is given, and nothing else.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.sonar import check_ranges
from pipefollow.sim.disturbance import NO_BURIAL


class ImagingSonarError(ValueError):
    """An imaging sonar setting that cannot be used; the message names the field."""


class ImagingSonar(NamedTuple):
    """A forward-looking imaging sonar's settings (units in the comments; sources in the module docstring)."""

    n_beams: int = 128  # beams over the horizontal aperture, [8, 1024]
    fov_deg: float = 130.0  # horizontal aperture (°), (0, 170]
    vertical_deg: float = 20.0  # vertical aperture, −3 dB full width (°), (0, 60]
    tilt_deg: float = 45.0  # the vertical beam's axis below the horizontal (°), (0, 89]
    altitude: float = 2.0  # transducer height above the seabed (m), (0.2, 50]
    along: float = 0.0  # forward position of the transducer in camera metres, [-5, 5]
    range_min: float = 2.2  # the image's nearest slant range (m), (0, 100)
    range_max: float = 4.4  # its farthest (m), (range_min, 100]
    range_resolution: float = 0.025  # the range bins' width (m), (0, 1]
    pipe_strength: float = 5.0  # the pipe's backscatter over the seabed's, (0, 1000]
    floor: float = 0.05  # the noise floor, times sin² tilt (module docstring), [0, 10]
    step: float = 0.01  # the height field's sampling along a beam (m), (0, 0.1]


_RANGES = {  # field: (low, high, low end closed)
    "n_beams": (8, 1024, True),
    "fov_deg": (0.0, 170.0, False),
    "vertical_deg": (0.0, 60.0, False),
    "tilt_deg": (0.0, 89.0, False),
    "altitude": (0.2, 50.0, False),
    "along": (-5.0, 5.0, True),
    "range_min": (0.0, 100.0, False),
    "range_max": (0.0, 100.0, False),
    "range_resolution": (0.0, 1.0, False),
    "pipe_strength": (0.0, 1000.0, False),
    "floor": (0.0, 10.0, True),
    "step": (0.0, 0.1, False),
}

FLS = ImagingSonar()


def check_imaging_sonar(s: ImagingSonar) -> ImagingSonar:
    """``s`` (``n_beams`` an int) if every field is in range; else a one-line :class:`ImagingSonarError`."""
    if not isinstance(s, ImagingSonar):
        raise ImagingSonarError(f"imaging sonar must be an ImagingSonar record, got {type(s).__name__}")
    check_ranges(s, _RANGES, ("n_beams",), ImagingSonarError, "imaging sonar")
    if s.range_max <= s.range_min:
        raise ImagingSonarError(
            f"imaging sonar setting range_max must exceed range_min ({s.range_min}), got {s.range_max!r}"
        )
    if s.range_min <= s.altitude and s.range_max <= s.altitude:
        raise ImagingSonarError(
            f"imaging sonar ranges {s.range_min}-{s.range_max} m never reach the seabed {s.altitude} m below"
        )
    return s._replace(n_beams=int(s.n_beams))


def n_bins(s: ImagingSonar) -> int:
    """The image's range bins."""
    return int(math.ceil((s.range_max - s.range_min) / s.range_resolution - 1e-9))


def bearings(s: ImagingSonar) -> np.ndarray:
    """The beams' bearings (rad, positive to starboard), evenly spaced over the aperture."""
    half = math.radians(s.fov_deg) / 2.0
    return np.linspace(-half, half, s.n_beams) if s.n_beams > 1 else np.zeros(1)


def bin_ranges(s: ImagingSonar) -> np.ndarray:
    """The range bins' centres (m)."""
    return s.range_min + (np.arange(n_bins(s)) + 0.5) * s.range_resolution


def ground_distance(s: ImagingSonar, slant: np.ndarray | float, height: float = 0.0):
    """Horizontal distance of a point ``height`` above the seabed at slant range ``slant`` (NaN if none)."""
    drop = s.altitude - height
    sq = np.asarray(slant, dtype=float) ** 2 - drop * drop
    return np.sqrt(np.where(sq >= 0.0, sq, np.nan))


class SonarImage(NamedTuple):
    """One ping's image and where it was taken."""

    intensity: np.ndarray  # (n_beams, n_bins), speckled
    mean: np.ndarray  # (n_beams, n_bins): the intensity before the speckle (the truth of the image)
    sonar: ImagingSonar


def render_image(
    points: np.ndarray,
    cum: np.ndarray,
    pose: tuple[float, float, float],
    rng: np.random.Generator,
    sonar: ImagingSonar = FLS,
    diameter: float = 0.25,
    burial: float = 0.0,
    buried_from: np.ndarray = NO_BURIAL,
    buried_to: np.ndarray = NO_BURIAL,
    angles: np.ndarray | None = None,
    out: np.ndarray | None = None,
) -> SonarImage:
    """One ping from ``pose`` = (x, y, ψ) over the pipeline ``points`` (module docstring).

    ``angles`` (:func:`bearings`) and ``out`` (an ``(n_beams, n_bins)`` array for the mean) may be
    passed to save their allocation; the returned image's ``mean`` is then ``out`` itself, which the
    next call with it overwrites.
    """
    s = sonar
    if angles is None:
        angles = bearings(s)
    nb = n_bins(s)
    mean = np.empty((s.n_beams, nb)) if out is None else out
    if angles.shape != (s.n_beams,) or mean.shape != (s.n_beams, nb):
        raise ImagingSonarError(
            f"angles must have shape ({s.n_beams},) and out ({s.n_beams}, {nb}) for this sonar, "
            f"got {angles.shape} and {mean.shape}"
        )
    x, y, psi = pose
    _render(
        np.ascontiguousarray(points, dtype=np.float64), np.ascontiguousarray(cum, dtype=np.float64),
        float(x), float(y), float(psi), angles, _settings(s), float(diameter), float(burial),
        np.asarray(buried_from, dtype=np.float64), np.asarray(buried_to, dtype=np.float64), mean,
    )  # fmt: skip
    speckle = rng.standard_exponential(mean.shape)
    return SonarImage(mean * speckle, mean, s)


def _settings(s: ImagingSonar) -> np.ndarray:
    return np.array(
        [
            math.radians(s.vertical_deg), math.radians(s.tilt_deg), s.altitude, s.along,
            s.range_min, s.range_resolution, s.pipe_strength, s.floor, s.step,
        ]
    )  # fmt: skip


@njit(cache=True)
def _near(points, cum, x, y, psi, reach, along, buried_from, buried_to, seg):
    """The pipe's open (unburied) segments within ``reach`` of the transducer, camera frame.

    Fills ``seg[k] = (ax, ay, ex, ey, length)`` (start, unit direction, length); a segment partly
    buried is split at its buried stretches. Returns how many.
    """
    cs, sn = math.cos(psi), math.sin(psi)
    n = 0
    for i in range(points.shape[0] - 1):
        dx, dy = points[i, 0] - x, points[i, 1] - y
        ax, ay = -sn * dx + cs * dy, cs * dx + sn * dy - along
        dx, dy = points[i + 1, 0] - x, points[i + 1, 1] - y
        bx, by = -sn * dx + cs * dy, cs * dx + sn * dy - along
        length = math.hypot(bx - ax, by - ay)
        if length <= 0.0:
            continue
        ex, ey = (bx - ax) / length, (by - ay) / length
        # the segment's distance from the transducer (above the seabed)
        t = min(max(-(ax * ex + ay * ey), 0.0), length)
        if math.hypot(ax + t * ex, ay + t * ey) > reach:
            continue
        lo = 0.0  # the open parts between the buried stretches
        while lo < length and n < seg.shape[0]:
            hi = length
            skip = -1.0
            for j in range(buried_from.shape[0]):
                bf, bt = buried_from[j] - cum[i], buried_to[j] - cum[i]
                if bt > lo and bf < hi:
                    if bf <= lo:
                        lo = max(lo, bt)
                    else:
                        hi = bf
                        skip = bt
            if lo < hi:
                seg[n, 0], seg[n, 1] = ax + lo * ex, ay + lo * ey
                seg[n, 2], seg[n, 3], seg[n, 4] = ex, ey, hi - lo
                n += 1
            if skip < 0.0:
                break
            lo = skip
    return n


@njit(cache=True)
def _render(points, cum, x, y, psi, angles, st, diameter, burial, buried_from, buried_to, mean):
    vertical, tilt, altitude, along = st[0], st[1], st[2], st[3]
    r_min, dr, strength, floor, step = st[4], st[5], st[6], st[7], st[8]
    nb = mean.shape[1]
    r_max = r_min + nb * dr
    radius = 0.5 * diameter
    axis = radius * (1.0 - 2.0 * burial)  # the axis's height above the seabed
    rho_max = math.sqrt(max(r_max * r_max - altitude * altitude, 0.0))
    seg = np.empty((64, 5))
    n = _near(points, cum, x, y, psi, rho_max + 2.0 * diameter, along, buried_from, buried_to, seg)
    k_beam = 4.0 * math.log(2.0) / (vertical * vertical)  # G(δ)² = exp(-k (δ - tilt)²), two-way
    ref = math.sin(tilt) ** 2  # the Lambert echo at the tilt, the floor's reference
    # the height field's samples: from where a pipe could shadow the image's nearest range
    rho_min = math.sqrt(max(r_min * r_min - altitude * altitude, 0.0))
    q0 = int(max(rho_min - 4.0 * diameter, step) / step)
    n_samples = int(math.ceil(rho_max / step)) + 1
    # the flat seabed's slant ranges (the sample's span) and energy at each sample, the same for every beam
    # (each sample's shares of its bins, as _deposit gives them, kept for the beams that cross the pipe)
    half = 0.5 * step
    flat_lo, flat_hi = np.zeros(n_samples), np.zeros(n_samples)
    flat_energy = np.zeros(n_samples)
    flat_bin = np.full(n_samples, -1, dtype=np.int64)  # the first bin; -1 for none
    flat_count = np.zeros(n_samples, dtype=np.int64)  # the bins it spans in the image (> 2: _deposit)
    flat_share = np.zeros((n_samples, 2))
    flat_row = np.zeros(nb)
    for q in range(q0, n_samples):
        rho = q * step
        r = math.hypot(rho, altitude)
        flat_lo[q], flat_hi[q] = math.hypot(rho - half, altitude), math.hypot(rho + half, altitude)
        off = math.atan2(altitude, rho) - tilt
        cos_i = altitude / r
        flat_energy[q] = cos_i * cos_i * step * math.exp(-k_beam * off * off)
        flat_bin[q], flat_count[q] = _shares(
            flat_lo[q], flat_hi[q], flat_energy[q], r_min, dr, nb, flat_share[q]
        )
        _add_sample(flat_row, flat_bin[q], flat_count[q], flat_share[q], flat_lo[q], flat_hi[q],
                    flat_energy[q], r_min, dr)  # fmt: skip
    for j in range(nb):
        flat_row[j] = flat_row[j] / dr + floor * ref
    heights = np.zeros(n_samples)
    slopes = np.zeros(n_samples)
    for i in range(angles.shape[0]):
        ux, uy = math.sin(angles[i]), math.cos(angles[i])
        first, last = n_samples, -1  # the samples on the pipe
        for k in range(n):
            ax, ay, ex, ey, length = seg[k, 0], seg[k, 1], seg[k, 2], seg[k, 3], seg[k, 4]
            # the ray's signed distance from the axis's line: c0 + c1 ρ; its position along it: t0 + t1 ρ
            c0, c1 = -ax * ey + ay * ex, ux * ey - uy * ex
            t0, t1 = -(ax * ex + ay * ey), ux * ex + uy * ey
            a, b = -math.inf, math.inf
            for c, g, lo, hi in ((c0, c1, -radius, radius), (t0, t1, -radius, length + radius)):
                if g == 0.0:
                    if c < lo or c > hi:
                        a, b = 1.0, 0.0
                else:
                    p, qq = (lo - c) / g, (hi - c) / g
                    a, b = max(a, min(p, qq)), min(b, max(p, qq))
            a, b = max(a, 0.0), min(b, rho_max)
            if a >= b:
                continue
            for q in range(max(int(a / step), q0), min(int(b / step) + 2, n_samples)):
                d = c0 + c1 * q * step
                if abs(d) >= radius:
                    continue
                root = math.sqrt(radius * radius - d * d)
                top = axis + root
                if top > heights[q]:
                    if last < first:
                        first, last = q, q
                    first, last = min(first, q), max(last, q)
                    heights[q] = top
                    slopes[q] = -d * c1 / root  # dz/dρ of the top along the ray
        if last < first:  # the flat seabed only
            for j in range(nb):
                mean[i, j] = flat_row[j]
            continue
        for j in range(nb):
            mean[i, j] = 0.0
        lowest = math.inf  # the smallest tangent of depression so far (the horizon)
        for q in range(q0, n_samples):
            rho = q * step
            z = heights[q]
            drop = altitude - z
            tan_d = drop / rho
            if tan_d > lowest:
                continue  # in the shadow of a nearer sample
            lowest = tan_d
            if z <= 0.0:
                c = flat_count[q]  # _add_sample written out: a call here more than doubled the render
                if c > 2:
                    _deposit(mean[i], flat_lo[q], flat_hi[q], flat_energy[q], r_min, dr)
                elif c > 0:
                    jb = flat_bin[q]
                    mean[i, jb] += flat_share[q, 0]
                    if c == 2:
                        mean[i, jb + 1] += flat_share[q, 1]
                continue
            heights[q] = 0.0
            r = math.hypot(rho, drop)
            r_lo, r_hi = math.hypot(rho - half, drop), math.hypot(rho + half, drop)
            if r_hi <= r_min or r_lo >= r_max:
                continue
            slope = slopes[q]
            # the surface's normal (-slope, 1)/√(1+slope²) against the way to the transducer (-ρ, drop)/r
            norm = math.sqrt(1.0 + slope * slope)
            cos_i = (slope * rho + drop) / (norm * r)
            if cos_i <= 0.0:
                continue
            off = math.atan2(drop, rho) - tilt
            energy = strength * cos_i * cos_i * step * norm * math.exp(-k_beam * off * off)
            _deposit(mean[i], r_lo, r_hi, energy, r_min, dr)
        for q in range(first, min(last + 1, n_samples)):
            heights[q] = 0.0
        for j in range(nb):
            mean[i, j] = mean[i, j] / dr + floor * ref
    return n


@njit(cache=True)
def _shares(r_lo, r_hi, energy, r_min, dr, nb, out):
    """What :func:`_deposit` adds to a row for spans of at most two bins: ``(first bin, bins)``.

    The amounts go into ``out``; more than two bins (a coarse ``step``) give ``(-1, 3)``, left to
    :func:`_deposit`.
    """
    u0, u1 = (r_lo - r_min) / dr, (r_hi - r_min) / dr
    width = u1 - u0
    if width <= 0.0:
        j = int(math.floor(u0))
        if 0 <= j < nb:
            out[0] = energy
            return j, 1
        return -1, 0
    first, end = max(int(math.floor(u0)), 0), min(int(math.floor(u1)) + 1, nb)
    if end - first > 2:
        return -1, 3
    for j in range(first, end):
        share = min(u1, j + 1.0) - max(u0, float(j))
        out[j - first] = energy * share / width if share > 0.0 else 0.0
    return (first, end - first) if end > first else (-1, 0)


@njit(cache=True)
def _add_sample(row, first, count, share, r_lo, r_hi, energy, r_min, dr):
    """A flat-seabed sample added to ``row`` from its :func:`_shares` (``_deposit`` past two bins)."""
    if count > 2:
        _deposit(row, r_lo, r_hi, energy, r_min, dr)
    elif count > 0:
        row[first] += share[0]
        if count == 2:
            row[first + 1] += share[1]


@njit(cache=True)
def _deposit(row, r_lo, r_hi, energy, r_min, dr):
    """Add a sample's ``energy``, spread evenly over its slant ranges ``r_lo``–``r_hi``, to ``row``'s bins.

    Each bin takes the share of the span inside it; what falls outside the image is dropped.
    """
    nb = row.shape[0]
    u0, u1 = (r_lo - r_min) / dr, (r_hi - r_min) / dr
    width = u1 - u0
    if width <= 0.0:
        j = int(math.floor(u0))
        if 0 <= j < nb:
            row[j] += energy
        return
    for j in range(max(int(math.floor(u0)), 0), min(int(math.floor(u1)) + 1, nb)):
        share = min(u1, j + 1.0) - max(u0, float(j))
        if share > 0.0:
            row[j] += energy * share / width


__all__ = [
    "FLS",
    "ImagingSonar",
    "ImagingSonarError",
    "SonarImage",
    "bearings",
    "bin_ranges",
    "check_imaging_sonar",
    "ground_distance",
    "n_bins",
    "render_image",
]
