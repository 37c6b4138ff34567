r"""The pipe in one multibeam profile: its lateral position, height and a confidence.

:func:`detect_profile` finds a pipe in one ping of :mod:`pipefollow.perception.sonar`:

1. the ping's points as lateral position ``x = r sin θ`` and height ``z = −r cos θ cos τ``
   (``τ`` the fan's forward tilt, ``Ping.pitch``);
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

The line through successive pings' detections, in the camera's frame, is
:mod:`pipefollow.perception.sonar_track`'s.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.sonar import Ping

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
    forward: float = 0.0  # forward position (camera metres) of the pipe's axis in the fan


def detect_profile(
    ping: Ping | tuple,
    diameter: float = 0.25,
    threshold: float = THRESHOLD,
    min_height: float | None = None,
) -> SonarFix:
    """The pipe in one ping (``Ping``, or ``(angles, ranges)`` of a vertical fan at forward 0).

    See the module docstring.
    """
    angles, ranges = ping[0], ping[1]
    along, pitch = (ping.along, ping.pitch) if isinstance(ping, Ping) else (0.0, 0.0)
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
    cos_t = math.cos(pitch)
    found, lateral, height, snr, depth, sigma = _detect(
        angles, ranges, cos_t, diameter, threshold, min_height
    )
    if not found:
        return SonarFix(False, snr=snr, seabed_depth=depth, sigma=sigma)
    # the fitted section's centre lies on the ray down the fan to the axis's depth
    forward = along + (depth - (height - 0.5 * diameter)) * math.tan(pitch)
    return SonarFix(True, lateral, height, snr, min(1.0, snr / (2.0 * threshold)), depth, sigma, forward)


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
def _detect(angles, ranges, cos_pitch, diameter, threshold, min_height):
    keep = np.isfinite(ranges)
    m = int(keep.sum())
    if m < MIN_BEAMS:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0
    r, th = ranges[keep], angles[keep]
    x, z = r * np.sin(th), -r * np.cos(th) * cos_pitch
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


__all__ = ["SonarFix", "THRESHOLD", "detect_profile"]
