r"""The pipe in one forward-looking sonar image: straight pieces on the seabed, and a confidence.

:func:`detect_image` finds a pipe in one ping of :mod:`pipefollow.perception.imaging_sonar`:

1. each range bin's intensities divided by the seabed's mean at that range, taken robustly from
   its *lit* cells: those whose means over :data:`LIT_BINS` range bins (up to the cell and from
   it) reach :data:`LIT` of the centred mean's :data:`REF_Q` quantile over the beams (acoustic
   shadow lies near the noise floor, a few hundredths of the seabed's echo), their median over
   ln 2 (an exponential's median is ln 2 of its mean; the pipe fills few beams at any one range;
   dropping the lowest lit cells reads about 5 % high on a uniform seabed). A bin with fewer than
   :data:`MIN_LIT` lit cells takes the nearest such bin's level (:func:`seabed_level`). Not the
   median of every beam: where the pipe's shadow covers half the beams at a range (a pipe near the
   transducer, a bend across the sector) that median falls towards the noise floor and the whole
   range bin's seabed turns into highlights (docs/decisions.md). Then each cell averaged over
   ``smooth`` range bins (and
   ``smooth_beams`` beams); a cell whose mean exceeds ``threshold`` is a *highlight* (over a
   uniform seabed the mean of three standard exponentials exceeds 5 with probability 4·10⁻⁵:
   about 0.5 false cells in a ping of 128 × 88 cells, fewer with the level 5 % high; none of 300
   pings of an empty seabed gave a piece, ``tests/test_imaging_sonar.py``);
2. each highlight's position on the seabed, its echo taken from the height of a pipe's axis on the
   seabed (``D/2``): ``ρ = √(r² − (altitude − D/2)²)`` along its beam's bearing;
3. the straight line through most highlights by a Hough transform (directions every
   :data:`HOUGH_STEP_DEG`, offsets every :data:`HOUGH_BIN` m), its inliers those within
   ``inlier`` m, refitted twice by total least squares (the principal axis of the inliers);
4. a piece when at least ``min_cells`` inliers spread at least ``min_length`` m along the line:
   the piece between the inliers' extreme projections, moved :data:`FACE` radii away from the
   transducer (the highlight is the pipe's face towards the sonar, not its axis), the far end the
   one further forward. With
   ``max_pieces`` > 1 the highlights within :data:`SUPPRESS` of a piece are its own and the next
   line is sought among the others.

The confidence is ``min(1, inliers / (4 · min_cells))``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.imaging_sonar import SonarImage, bearings, bin_ranges

THRESHOLD = 5.0  # a highlight's mean intensity over SMOOTH range bins, in seabed means
SMOOTH = 3  # range bins averaged ...
SMOOTH_BEAMS = 1  # ... over this many beams
MIN_CELLS = 8  # inliers a piece needs
MIN_LENGTH = 0.3  # m: their spread along the line
INLIER = 0.08  # m: an inlier's distance from the line
HOUGH_STEP_DEG = 2.0
HOUGH_BIN = 0.04  # m
# the highlight's line's distance short of the pipe's axis, in radii: on straight pipes at 0-90° to
# the track 2 m ahead (20 pings each) the line lay about R nearer the sonar for a pipe lying on the
# seabed, 0.4 R half buried
FACE = 0.8
LIT = 0.1  # a lit cell's range-averaged echo, at least, in REF_Q quantiles (step 1)
LIT_BINS = 3  # range bins averaged to tell a lit cell from a shadowed one
MIN_LIT = 8  # lit cells a range bin needs for its own level
LN2 = math.log(2.0)
REF_Q = 0.9  # the quantile over the beams of the range-averaged echo that LIT is a share of
MAX_CELLS = 2048  # highlights kept (the first in beam order beyond this)
SUPPRESS = 0.3  # m: highlights this near a piece found are its own (the highlight is wider than its line)
MAX_PIECES = 1  # straight pieces sought in one image


class ImageFix(NamedTuple):
    """What :func:`detect_image` found (camera metres; zeros when not found)."""

    found: bool
    x1: float = 0.0  # the piece's far end (lateral, forward) ...
    y1: float = 0.0
    x2: float = 0.0  # ... and its near end
    y2: float = 0.0
    cells: int = 0  # inliers
    highlights: int = 0  # highlights in the image (also when not found)
    confidence: float = 0.0  # the first piece's
    # every piece found, the strongest (the above) first: x1, y1, x2, y2, cells
    pieces: np.ndarray = np.zeros((0, 5))
    points: np.ndarray = np.zeros((0, 2))  # the highlights' seabed positions (lateral, forward)


def detect_image(
    image: SonarImage,
    diameter: float = 0.25,
    threshold: float = THRESHOLD,
    smooth: int = SMOOTH,
    min_cells: int = MIN_CELLS,
    min_length: float = MIN_LENGTH,
    inlier: float = INLIER,
    angles: np.ndarray | None = None,
    ranges: np.ndarray | None = None,
    smooth_beams: int = SMOOTH_BEAMS,
    max_pieces: int = MAX_PIECES,
    face: float = FACE,
) -> ImageFix:
    """The pipe's piece in one image (module docstring); ``angles``/``ranges`` save recomputing them."""
    for name, value in (("smooth", smooth), ("smooth_beams", smooth_beams), ("min_cells", min_cells),
                        ("max_pieces", max_pieces)):  # fmt: skip
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"detect setting {name} must be a whole number ≥ 1, got {value!r}")
    s = image.sonar
    if angles is None:
        angles = bearings(s)
    if ranges is None:
        ranges = bin_ranges(s)
    drop = s.altitude - 0.5 * diameter
    rho = np.sqrt(np.maximum(ranges * ranges - drop * drop, 0.0))
    st = np.array([threshold, smooth, min_cells, min_length, inlier, math.radians(HOUGH_STEP_DEG), HOUGH_BIN,
                   smooth_beams, face * 0.5 * diameter], dtype=np.float64)  # fmt: skip
    pieces = np.zeros((max_pieces, 5))
    px, py = np.empty(MAX_CELLS), np.empty(MAX_CELLS)
    count, n = _detect(image.intensity, angles, rho, s.along, st, pieces, px, py)
    points = np.column_stack((px[:n], py[:n]))
    if count == 0:
        return ImageFix(False, highlights=int(n), points=points)
    x1, y1, x2, y2, cells = pieces[0]
    conf = min(1.0, cells / (4.0 * min_cells))
    return ImageFix(True, x1, y1, x2, y2, int(cells), int(n), conf, pieces[:count], points)


@njit(cache=True)
def _highlights(intensity, angles, rho, along, threshold, smooth, smooth_beams, px, py):
    """Step 1–2 of the module docstring: the highlights' seabed positions into ``px, py``; how many."""
    nbeam, nb = intensity.shape
    level = np.empty(nb)
    seabed_level(intensity, level)
    n = 0
    half = smooth // 2
    for i in range(nbeam):
        sb, cb = math.sin(angles[i]), math.cos(angles[i])
        b0, b1 = max(i - smooth_beams // 2, 0), min(i - smooth_beams // 2 + smooth_beams, nbeam)
        for j in range(nb):
            x, y = rho[j] * sb, along + rho[j] * cb
            if rho[j] <= 0.0 or n >= px.shape[0]:
                continue
            lo, hi = max(j - half, 0), min(j - half + smooth, nb)
            total = 0.0
            for b in range(b0, b1):
                for k in range(lo, hi):
                    total += intensity[b, k] / level[k]
            if total / ((hi - lo) * (b1 - b0)) > threshold:
                px[n], py[n] = x, y
                n += 1
    return n


@njit(cache=True)
def seabed_level(intensity, level):
    """Each range bin's seabed mean into ``level``, from its lit cells (step 1 of the module docstring).

    A cell is lit when its echo averaged over the :data:`LIT_BINS` range bins up to it and over
    those from it both reach :data:`LIT` of the :data:`REF_Q` quantile of the centred averages
    (one-sided windows: a shadowed cell next to a lit range bin is not taken for lit; a shadow
    shorter than :data:`LIT_BINS` bins is not told from the seabed). A bin with
    fewer than :data:`MIN_LIT` lit cells (or half its beams, if fewer), nearly all in shadow,
    takes the level of the nearest bin that has them; the median of every beam / ln 2 if none has.
    """
    nbeam, nb = intensity.shape
    half = LIT_BINS // 2
    need = max(min(MIN_LIT, nbeam // 2), 1)
    by_bin = np.empty((nb, nbeam))  # (bin, beam): a bin's beams side by side, read beam by beam
    for i in range(nbeam):
        for k in range(nb):
            by_bin[k, i] = intensity[i, k]
    centred, low = np.zeros(nbeam), np.zeros(nbeam)  # centred, rebuilt each bin, is the quantile's workspace
    a, b = np.zeros(nbeam), np.zeros(nbeam)
    lit = np.empty(nbeam)
    for j in range(nb):
        lo, hi = max(j - half, 0), min(j - half + LIT_BINS, nb)
        before, after = max(j - LIT_BINS + 1, 0), min(j + LIT_BINS, nb)
        centred[:] = 0.0
        a[:] = 0.0
        b[:] = 0.0
        for k in range(lo, hi):  # each beam's sums over the bins in order, as a beam-by-beam loop would
            centred += by_bin[k]
        for k in range(before, j + 1):
            a += by_bin[k]
        for k in range(j, after):
            b += by_bin[k]
        for i in range(nbeam):
            centred[i] = centred[i] / (hi - lo)
            low[i] = min(a[i] / (j + 1 - before), b[i] / (after - j))
        ref = _quantile(centred, nbeam, REF_Q)
        m = 0
        for i in range(nbeam):
            if low[i] >= LIT * ref:
                lit[m] = by_bin[j, i]
                m += 1
        level[j] = max(_median(lit, m) / LN2, 1e-12) if m >= need else math.nan
    own = level == level  # the bins with enough lit cells
    found = own.any()
    for j in range(nb):  # the others: the nearest such bin's level
        if own[j]:
            continue
        if not found:
            level[j] = max(np.median(intensity[:, j]) / LN2, 1e-12)
            continue
        for d in range(1, nb):
            if j - d >= 0 and own[j - d]:
                level[j] = level[j - d]
                break
            if j + d < nb and own[j + d]:
                level[j] = level[j + d]
                break


@njit(cache=True)
def _select(w, n, k):
    """The ``k``-th smallest of ``w[:n]`` (0-based), ``w`` partitioned about it (Hoare's selection)."""
    lo, hi = 0, n - 1
    while lo < hi:
        pivot = w[(lo + hi) // 2]
        i, j = lo, hi
        while i <= j:
            while w[i] < pivot:
                i += 1
            while w[j] > pivot:
                j -= 1
            if i <= j:
                w[i], w[j] = w[j], w[i]
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            break
    return w[k]


@njit(cache=True)
def _two(w, n, k):
    """The ``k``-th and ``k+1``-th smallest of ``w[:n]``."""
    a = _select(w, n, k)
    b = w[k + 1]
    for i in range(k + 2, n):
        b = min(b, w[i])
    return a, b


@njit(cache=True)
def _median(w, n):
    """``np.median(w[:n])`` as numba computes it (the same arithmetic), without its copies; mutates ``w``."""
    half = n >> 1
    if n & 1 == 0:
        a, b = _two(w, n, half - 1)
        return (a + b) / 2
    return _select(w, n, half)


@njit(cache=True)
def _quantile(w, n, q):
    """``np.quantile(w[:n], q)``, 0 < q < 1, with numba's arithmetic but without its copies.

    Linear between the closest ranks, as numba computes it; mutates ``w``.
    """
    if n == 1:
        return w[0]
    rank = 1 + (n - 1) * ((q * 100.0) / 100.0)
    f = math.floor(rank)
    m = rank - f
    lower, upper = _two(w, n, int(f - 1))
    return lower * (1 - m) + upper * m


@njit(cache=True)
def line_piece(px, py, used, n, min_cells, min_length, inlier, d_theta, d_bin, along, shift):
    """Steps 3–4 on the highlights not ``used``: ``(found, x1, y1, x2, y2, inliers)``; marks its own used."""
    n_theta = int(math.pi / d_theta)
    reach = 0.0
    free = 0
    for k in range(n):
        if not used[k]:
            reach = max(reach, math.hypot(px[k], py[k]))
            free += 1
    if free < min_cells:
        return False, 0.0, 0.0, 0.0, 0.0, 0
    n_d = int(2.0 * reach / d_bin) + 2
    acc = np.zeros((n_theta, n_d), dtype=np.int32)
    best, bt, bd = 0, 0, 0
    for t in range(n_theta):  # lines x cos θ + y sin θ = d, θ in [0, π)
        ct, st = math.cos(t * d_theta), math.sin(t * d_theta)
        for k in range(n):
            if used[k]:
                continue
            b = int((px[k] * ct + py[k] * st + reach) / d_bin)
            acc[t, b] += 1
            if acc[t, b] > best:
                best, bt, bd = acc[t, b], t, b
    ct, st = math.cos(bt * d_theta), math.sin(bt * d_theta)
    d = (bd + 0.5) * d_bin - reach
    mx = my = phi = 0.0
    for _ in range(2):  # the inliers, refitted by their principal axis, twice
        m = 0
        sx = sy = 0.0
        for k in range(n):
            if not used[k] and abs(px[k] * ct + py[k] * st - d) <= inlier:
                sx += px[k]
                sy += py[k]
                m += 1
        if m < min_cells:
            return False, 0.0, 0.0, 0.0, 0.0, m
        mx, my = sx / m, sy / m
        sxx = sxy = syy = 0.0
        for k in range(n):
            if not used[k] and abs(px[k] * ct + py[k] * st - d) <= inlier:
                ex, ey = px[k] - mx, py[k] - my
                sxx += ex * ex
                sxy += ex * ey
                syy += ey * ey
        phi = 0.5 * math.atan2(2.0 * sxy, sxx - syy)  # the principal axis's direction
        ct, st = -math.sin(phi), math.cos(phi)  # its normal
        d = mx * ct + my * st
    ux, uy = math.cos(phi), math.sin(phi)
    lo, hi = math.inf, -math.inf
    m = 0
    for k in range(n):
        if not used[k] and abs(px[k] * ct + py[k] * st - d) <= inlier:
            u = (px[k] - mx) * ux + (py[k] - my) * uy
            lo, hi = min(lo, u), max(hi, u)
            m += 1
    for k in range(n):  # the piece's highlights used up: those within SUPPRESS of it
        u = min(max((px[k] - mx) * ux + (py[k] - my) * uy, lo), hi)
        if math.hypot(px[k] - mx - u * ux, py[k] - my - u * uy) <= SUPPRESS:
            used[k] = True
    if m < min_cells or hi - lo < min_length:
        return False, 0.0, 0.0, 0.0, 0.0, m
    if (mx * ct + my * st) - along * st < 0.0:  # turn the normal to point away from the transducer
        ct, st = -ct, -st
    mx, my = mx + shift * ct, my + shift * st  # from the face towards the sonar to the axis
    ax, ay = mx + lo * ux, my + lo * uy
    bx, by = mx + hi * ux, my + hi * uy
    if ay > by:  # the far end is the one further forward
        return True, ax, ay, bx, by, m
    return True, bx, by, ax, ay, m


@njit(cache=True)
def _detect(intensity, angles, rho, along, st, pieces, px, py):
    """Every piece (at most ``len(pieces)``), the strongest first, into ``pieces``: (count, highlights)."""
    threshold, smooth, min_cells, min_length = st[0], int(st[1]), int(st[2]), st[3]
    inlier, d_theta, d_bin, smooth_beams, shift = st[4], st[5], st[6], int(st[7]), st[8]
    n = _highlights(intensity, angles, rho, along, threshold, smooth, smooth_beams, px, py)
    used = np.zeros(n, dtype=np.bool_)
    count = 0
    for _ in range(pieces.shape[0]):
        if count >= pieces.shape[0]:
            break
        found, x1, y1, x2, y2, m = line_piece(
            px, py, used, n, min_cells, min_length, inlier, d_theta, d_bin, along, shift
        )
        if m < min_cells:
            break
        if found:
            pieces[count, 0], pieces[count, 1], pieces[count, 2], pieces[count, 3] = x1, y1, x2, y2
            pieces[count, 4] = m
            count += 1
    return count, n


__all__ = ["ImageFix", "detect_image", "line_piece", "seabed_level"]
