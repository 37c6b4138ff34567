r"""The pipe in a multibeam profile, and its line in the camera frame from successive profiles.

:func:`detect_profile` finds a pipe in one ping of :mod:`pipefollow.perception.sonar`:

1. the ping's points as lateral position ``x = r sin θ`` and height ``z = −r cos θ``;
2. the seabed as a line ``z = a + b x``, fitted robustly (Tukey's biweight, iteratively
   reweighted from the median height; the pipe is a minority of the beams) and the noise scale
   ``σ`` as 1.4826 × the median absolute residual;
3. a matched filter for the pipe's top: at each beam whose residual exceeds ``σ``, the template
   ``t(u) = √(1 − (2u/D)²)`` over ``|u| < D/2`` (a pipe of diameter ``D`` lying across the fan)
   is fitted to the residuals by least squares; its signal-to-noise ratio
   ``SNR = Σ e t / (σ √Σ t²)`` is standard normal at each candidate on a pipe-free seabed with
   Gaussian noise; the best candidate is a pipe when ``SNR ≥ threshold`` and its fitted height
   is at least ``min_height``;
4. the seabed refitted by least squares without the pipe's window and the beams more than 3σ
   off it, and the lateral position as the vertex of a parabola fitted to the pipe's top (the
   beams within the window above half the peak's residual); the centroid of the residuals if the
   parabola is not concave or its vertex leaves the window.

The confidence is ``min(1, SNR / (2 · threshold))``: ½ at the threshold, 1 at twice it.

:class:`SonarTrack` remembers the detections of the last pings in the earth frame and fits a
straight line through them in the current camera frame, which gives the camera's observation
``(x1, y1, x2, y_near)`` (:mod:`pipefollow.sim.camera`): the line clipped to the camera's
footprint. The direction comes from the pings behind the AUV, so at a bend it lags the camera
(which sees 3 m ahead); with one ping only the pipe is taken parallel to the track.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.sonar import Ping
from pipefollow.sim.camera import PAPER_CAMERA, CameraParams, clip_segment

THRESHOLD = 6.0  # SNR of the matched filter for a detection (false alarms: docs/decisions.md, "Sonar")
MIN_HEIGHT_SHARE = 0.25  # the fitted top at least this share of the diameter above the seabed
TUKEY_C = 4.685  # the biweight's tuning constant (95 % efficiency under Gaussian noise)
MIN_SIGMA = 0.002  # m: the noise scale's floor (a noise-free, unquantised profile)
MIN_BEAMS = 8  # valid beams a profile needs


class SonarFix(NamedTuple):
    """What :func:`detect_profile` found in one ping (camera metres; zeros when not found)."""

    found: bool
    lateral: float = 0.0  # the pipe's lateral position on the fan (m, positive to starboard)
    height: float = 0.0  # its fitted top above the seabed (m)
    snr: float = 0.0  # the matched filter's peak signal-to-noise ratio (also when not found)
    confidence: float = 0.0  # in [0, 1]
    seabed_depth: float = 0.0  # the fitted seabed's depth under the transducer (m): the altitude
    sigma: float = 0.0  # the estimated height noise (m)


def detect_profile(
    ping: Ping | tuple,
    diameter: float = 0.25,
    threshold: float = THRESHOLD,
    min_height: float | None = None,
) -> SonarFix:
    """The pipe in one ping (``Ping`` or ``(angles, ranges)``): see the module docstring."""
    angles, ranges = ping[0], ping[1]
    if not (math.isfinite(diameter) and diameter > 0.0):
        raise ValueError(f"diameter must be a positive number of metres, got {diameter!r}")
    if not (math.isfinite(threshold) and threshold > 0.0):
        raise ValueError(f"threshold must be a positive signal-to-noise ratio, got {threshold!r}")
    if min_height is None:
        min_height = MIN_HEIGHT_SHARE * diameter
    angles, ranges = np.asarray(angles, np.float64), np.asarray(ranges, np.float64)
    if angles.shape != ranges.shape or angles.ndim != 1:
        shapes = f"{angles.shape} and {ranges.shape}"
        raise ValueError(f"angles and ranges must be 1-D arrays of one length, got {shapes}")
    found, lateral, height, snr, depth, sigma = _detect(angles, ranges, diameter, threshold, min_height)
    if not found:
        return SonarFix(False, snr=snr, seabed_depth=depth, sigma=sigma)
    return SonarFix(True, lateral, height, snr, min(1.0, snr / (2.0 * threshold)), depth, sigma)


@njit(cache=True)
def _line_fit(x, z, w):
    """Weighted least squares ``z = a + b x``; ``(a, b)`` (b = 0 when x does not spread)."""
    sw = sx = sz = sxx = sxz = 0.0
    for i in range(x.shape[0]):
        sw += w[i]
        sx += w[i] * x[i]
        sz += w[i] * z[i]
        sxx += w[i] * x[i] * x[i]
        sxz += w[i] * x[i] * z[i]
    if sw <= 0.0:
        return 0.0, 0.0
    mx, mz = sx / sw, sz / sw
    vxx = sxx / sw - mx * mx
    if vxx <= 1e-12:
        return mz, 0.0
    b = (sxz / sw - mx * mz) / vxx
    return mz - b * mx, b


@njit(cache=True)
def _scale(e):
    """1.4826 × the median absolute value of ``e`` (a normal's σ), floored at MIN_SIGMA."""
    return max(1.4826 * np.median(np.abs(e)), MIN_SIGMA)


@njit(cache=True)
def _seabed(x, z):
    """The seabed line by Tukey's biweight from the median height: ``(a, b, σ)``."""
    a, b = np.median(z), 0.0
    w = np.empty(x.shape[0])
    e = z - a
    sigma = _scale(e)
    for it in range(10):
        for i in range(x.shape[0]):
            q = e[i] / (TUKEY_C * sigma)
            w[i] = (1.0 - q * q) ** 2 if abs(q) < 1.0 else 0.0
        a_new, b_new = _line_fit(x, z, w)
        done = abs(a_new - a) < 1e-7 and abs(b_new - b) < 1e-7
        a, b = a_new, b_new
        e = z - (a + b * x)
        if done:
            break
        if it < 3:  # the scale settles with the first fits; later ones only refine the line
            sigma = _scale(e)
    return a, b, _scale(e)


@njit(cache=True)
def _matched(x, e, sigma, half, lo_e):
    """The best template fit: ``(snr, centre, height)`` over candidate centres with ``e > lo_e``.

    ``x`` is sorted but where the pipe bends a profile back on itself; the window's scan then
    runs over every beam.
    """
    best, centre, height = -math.inf, 0.0, 0.0
    n = x.shape[0]
    ordered = True
    for j in range(1, n):
        if x[j] < x[j - 1]:
            ordered = False
    for c in range(n):
        if e[c] <= lo_e:
            continue
        xc = x[c]
        set_ = stt = 0.0
        lo, hi = 0, n
        if ordered:  # the beams within the window only
            lo, hi = c, c + 1
            while lo > 0 and xc - x[lo - 1] < half:
                lo -= 1
            while hi < n and x[hi] - xc < half:
                hi += 1
        for j in range(lo, hi):
            u = (x[j] - xc) / half
            if -1.0 < u < 1.0:
                t = math.sqrt(1.0 - u * u)
                set_ += e[j] * t
                stt += t * t
        if stt <= 0.0:
            continue
        snr = set_ / (sigma * math.sqrt(stt))
        if snr > best:
            best, centre, height = snr, xc, set_ / stt
    return best, centre, height


@njit(cache=True)
def _det3(a, b, c, d, e, f, g, h, i):
    """The determinant of the 3 × 3 matrix of rows (a, b, c), (d, e, f), (g, h, i)."""
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


@njit(cache=True)
def _vertex(x, e, centre, half, peak):
    """The pipe's lateral position: the top's parabola vertex, else the residuals' centroid."""
    n = 0
    s0 = s1 = s2 = s3 = s4 = t0 = t1 = t2 = 0.0
    cw = cx = 0.0
    for j in range(x.shape[0]):
        u = x[j] - centre
        if abs(u) < half and e[j] > 0.0:
            cw += e[j]
            cx += e[j] * x[j]
            if e[j] >= 0.5 * peak:
                n += 1
                s0 += 1.0
                s1 += u
                s2 += u * u
                s3 += u * u * u
                s4 += u * u * u * u
                t0 += e[j]
                t1 += e[j] * u
                t2 += e[j] * u * u
    fallback = cx / cw if cw > 0.0 else centre
    if n < 3:
        return fallback
    # normal equations of e = c0 + c1 u + c2 u², solved by Cramer's rule
    det = _det3(s0, s1, s2, s1, s2, s3, s2, s3, s4)
    if abs(det) < 1e-18:
        return fallback
    c1 = _det3(s0, t0, s2, s1, t1, s3, s2, t2, s4) / det
    c2 = _det3(s0, s1, t0, s1, s2, t1, s2, s3, t2) / det
    if c2 >= 0.0:
        return fallback
    u = -c1 / (2.0 * c2)
    if abs(u) >= half:
        return fallback
    return centre + u


@njit(cache=True)
def _circle(x, e, centre, half, peak, radius, xc):
    """The pipe's section as a circle of the known radius through its top's beams: its centre's ``x``.

    Gauss–Newton on ``Σ (|p_j − c| − radius)²`` over the beams within the window above half the
    peak, from ``xc`` (the parabola's vertex). Unlike the parabola, the circle is not pulled
    towards the nadir when the far flank lies in the pipe's acoustic shadow. Returns ``xc``
    unchanged when fewer than 3 beams take part or the fit leaves the window.
    """
    cx, cz = xc, peak - radius
    for _ in range(10):
        a11 = a12 = a22 = g1 = g2 = 0.0
        n = 0
        for j in range(x.shape[0]):
            if abs(x[j] - centre) < half and e[j] >= 0.5 * peak:
                dx, dz = x[j] - cx, e[j] - cz
                rho = math.sqrt(dx * dx + dz * dz)
                if rho <= 0.0:
                    continue
                jx, jz, res = -dx / rho, -dz / rho, rho - radius
                a11 += jx * jx
                a12 += jx * jz
                a22 += jz * jz
                g1 += jx * res
                g2 += jz * res
                n += 1
        det = a11 * a22 - a12 * a12
        if n < 3 or abs(det) < 1e-12:
            return xc
        step_x = -(a22 * g1 - a12 * g2) / det
        step_z = -(a11 * g2 - a12 * g1) / det
        cx += step_x
        cz += step_z
        if abs(step_x) < 1e-6 and abs(step_z) < 1e-6:
            break
    if not abs(cx - centre) < half:
        return xc
    return cx


@njit(cache=True)
def _detect(angles, ranges, diameter, threshold, min_height):
    keep = np.isfinite(ranges)
    m = int(keep.sum())
    if m < MIN_BEAMS:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0
    r, th = ranges[keep], angles[keep]
    x, z = r * np.sin(th), -r * np.cos(th)
    a, b, sigma = _seabed(x, z)
    e = z - (a + b * x)
    half = 0.5 * diameter
    snr, centre, height = _matched(x, e, sigma, half, sigma)
    depth = -a
    if snr < threshold or height < min_height:
        return False, 0.0, 0.0, max(snr, 0.0), depth, sigma
    # refit the seabed without the pipe's window and the beams far off the line
    w = np.empty(m)
    for i in range(m):
        w[i] = 0.0 if abs(x[i] - centre) < 1.5 * half or abs(e[i]) > 3.0 * sigma else 1.0
    if w.sum() >= MIN_BEAMS:
        a, b = _line_fit(x, z, w)
        e = z - (a + b * x)
    peak = 0.0
    for i in range(m):
        if abs(x[i] - centre) < half and e[i] > peak:
            peak = e[i]
    lateral = _circle(x, e, centre, half, peak, half, _vertex(x, e, centre, half, peak))
    return True, lateral, peak, snr, -a, sigma


class SonarView(NamedTuple):
    """The camera's observation from the sonar track (camera metres; see :class:`SonarTrack`)."""

    in_view: bool  # the current ping found the pipe and its line crosses the camera's footprint
    x1: float  # the line's far end in the footprint ...
    y1: float
    x2: float  # ... and its near end
    y_near: float
    lateral: float  # the line's lateral offset at the AUV's centre (forward 0), even outside the footprint
    angle: float  # its angle to the track (rad, positive turning to starboard ahead)
    detected: bool  # the current ping found the pipe (anywhere in the swath)
    pings: int  # detections the line was fitted to


NO_VIEW = SonarView(False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, 0)


class SonarTrack:
    """The pipe's line from the detections of successive pings (earth-frame memory).

    Each :meth:`update` stores the detection's earth position (from the pose of its ping and the
    fan's ``along``); :meth:`view` fits ``lateral = c0 + c1·forward`` by least squares to the
    stored detections that lie within ``memory_m`` of the fan along the track in the current
    camera frame (at most ``memory`` of them, the newest) and clips the line from forward 0 to the
    footprint's depth to the footprint, as :func:`pipefollow.sim.camera.observe` clips the pipe.
    With detections spread less than ``min_spread`` m along the track the line is the newest
    detection's, parallel to the track. A ping without a detection keeps the memory but gives no
    view (the pipe counts as not seen).
    """

    def __init__(
        self,
        along: float = 0.0,
        memory: int = 6,
        memory_m: float = 4.0,
        min_spread: float = 0.3,
        camera: CameraParams = PAPER_CAMERA,
    ) -> None:
        if isinstance(memory, bool) or not isinstance(memory, int) or memory < 1:
            raise ValueError(f"memory must be a whole number of pings ≥ 1, got {memory!r}")
        for name, value in (("memory_m", memory_m), ("min_spread", min_spread), ("along", along)):
            if not (isinstance(value, int | float) and math.isfinite(value)):
                raise ValueError(f"{name} must be a finite number of metres, got {value!r}")
        if memory_m <= 0.0:
            raise ValueError(f"memory_m must be a positive distance (m), got {memory_m!r}")
        if min_spread < 0.0:
            raise ValueError(f"min_spread must be ≥ 0 (m), got {min_spread!r}")
        self.along, self.memory_m, self.min_spread, self.camera = along, memory_m, min_spread, camera
        self._ring = np.zeros((memory, 2))  # earth positions, the newest at index (count − 1) % memory
        self._count = 0
        self.last = NO_VIEW

    def reset(self) -> None:
        """Forget every detection (a new episode)."""
        self._count = 0
        self.last = NO_VIEW

    def update(self, pose: tuple[float, float, float], fix: SonarFix) -> SonarView:
        """Add the ping's detection (if found) taken at ``pose``; returns :meth:`view` from ``pose``."""
        if fix.found:
            x, y, psi = pose
            cs, sn = math.cos(psi), math.sin(psi)
            k = self._count % self._ring.shape[0]
            self._ring[k, 0] = x + cs * self.along - sn * fix.lateral
            self._ring[k, 1] = y + sn * self.along + cs * fix.lateral
            self._count += 1
        self.last = self.view(pose, fix.found)
        return self.last

    def view(self, pose: tuple[float, float, float], detected: bool = True) -> SonarView:
        """The line through the remembered detections, in the camera frame of ``pose``."""
        x, y, psi = pose
        cam = self.camera
        r = _track_line(
            self._ring, self._count, float(x), float(y), float(psi),
            self.along, self.memory_m, self.min_spread, cam.half_width, cam.depth,
        )  # fmt: skip
        pings, c0, angle, clipped, x1, y1, x2, yn = r
        if pings == 0:
            return NO_VIEW
        if not detected or not clipped:
            return SonarView(False, 0.0, 0.0, 0.0, 0.0, c0, angle, detected, pings)
        return SonarView(True, x1, y1, x2, yn, c0, angle, detected, pings)


@njit(cache=True)
def _track_line(ring, count, x, y, psi, along, memory_m, min_spread, half_width, depth):
    """:meth:`SonarTrack.view`'s arithmetic: ``(pings, c0, angle, in footprint, x1, y1, x2, y_near)``."""
    m = ring.shape[0]
    cs, sn = math.cos(psi), math.sin(psi)
    lat = np.empty(m)
    fwd = np.empty(m)
    n = 0
    for i in range(min(count, m)):
        k = (count - 1 - i) % m  # newest first
        dx, dy = ring[k, 0] - x, ring[k, 1] - y
        lc, fc = -sn * dx + cs * dy, cs * dx + sn * dy  # sim.camera.to_camera
        if abs(fc - along) <= memory_m:
            lat[n], fwd[n] = lc, fc
            n += 1
    if n == 0:
        return 0, 0.0, 0.0, False, 0.0, 0.0, 0.0, 0.0
    mf, ml = fwd[:n].mean(), lat[:n].mean()
    if fwd[:n].max() - fwd[:n].min() < min_spread:
        c0, c1 = lat[0], 0.0  # the newest detection, along the track
    else:
        sff = sfl = 0.0
        for i in range(n):
            sff += (fwd[i] - mf) ** 2
            sfl += (fwd[i] - mf) * (lat[i] - ml)
        c1 = sfl / sff
        c0 = ml - c1 * mf
    t0, t1 = clip_segment(c0, 0.0, c0 + c1 * depth, depth, -half_width, half_width, 0.0, depth)
    if t0 > t1:
        return n, c0, math.atan(c1), False, 0.0, 0.0, 0.0, 0.0
    return n, c0, math.atan(c1), True, c0 + t1 * c1 * depth, t1 * depth, c0 + t0 * c1 * depth, t0 * depth


__all__ = ["NO_VIEW", "SonarFix", "SonarTrack", "SonarView", "THRESHOLD", "detect_profile"]
