"""The pipe detector's edges: Hough segments in metres, their dominant direction, edges and the pair.

The stages of :func:`~pipefollow.perception.detector_legs.leg` from the Hough segments to a pipe's
two edges: the segments in camera metres (:func:`segment_geometry`), their length-weighted
dominant direction (:func:`dominant_direction`) and the segments along it
(:func:`aligned_segments`), those grouped into edges by their offset across (:func:`edge_groups`),
the pair of edges a pipe diameter apart (:func:`edge_pair`) with its confidence
(:func:`pair_confidence`), and both edges refitted to the edge pixels by least squares
(:func:`refine_edges`). docs/decisions.md ("pairing", "refinement") has the measurements behind
the thresholds.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.follow import add_edge_pixel, fit_edge
from pipefollow.perception.pixels import column_x, pixel_pitch, row_y

# the thresholds of the edge stages, each with its unit and what it guards against
ANGLE_BINS = 36  # bins of the direction histogram over 180° (5° each): finer bins split one edge's segments
NEIGHBOUR_WEIGHT = 0.5  # the histogram's circular smoothing: a direction on a bin's border counts in both
MAX_MISALIGNMENT = math.radians(12.0)  # rad from the peak: the pipe's segments; wider takes in a bend's leg
EDGE_LINK = 0.3  # diameters: segments closer than this across are one edge (a staircase edge's pieces)
MIN_PAIR_SEPARATION = 0.35  # diameters: the two edges at least this far apart and ... (texture lines are
MAX_PAIR_SEPARATION = 1.4  # ... at most this far: a pipe's edges are parallel, a diameter apart; ... not)
MIN_EDGE_SHARE = 0.1  # weaker edge's length / stronger's, ≥ this: one line is no pipe; one cut at a turn is
FIT_BANDS_PX = (2.5, 1.5)  # pixels: the refit's bands, around the Hough line (good to 1°), then the first fit
MIN_FIT_PIXELS = 6  # edge pixels an edge's refit needs; with fewer the Hough line stays (noise pixels)
MIN_FIT_SPREAD = 0.05  # share of the extent the pixels must spread along (s.d.) to tilt the line (a blob)
EXTEND = 0.4  # m: how far edge pixels may lengthen the Hough segments' extent (and the walk starts back)


class Segments(NamedTuple):
    """Hough segments in camera metres (arrays, one entry a segment)."""

    ax: np.ndarray  # lateral position of one end (m) ...
    ay: np.ndarray  # ... and its forward position
    bx: np.ndarray  # the other end
    by: np.ndarray
    length: np.ndarray  # m
    theta: np.ndarray  # direction (rad) in [0, π): a line's direction modulo π


class LegFrame(NamedTuple):
    """Coordinates along and across a leg: ``u = p·(dx, dy) − t_lo`` along, ``s = p·(nx, ny)`` across."""

    dx: float  # unit vector along the leg
    dy: float
    nx: float  # unit vector across it (the along vector turned 90° anticlockwise)
    ny: float
    t_lo: float  # the leg's start along (dx, dy) from the origin (m)


@njit(cache=True)
def segment_geometry(segs, grid):
    """The Hough segments (rows of pixel coordinates ``x0, y0, x1, y1``) as :class:`Segments` in metres.

    A segment's end pixel ``(column, row)`` stands for its pixel's centre.
    """
    m = segs.shape[0]
    ax = column_x(segs[:, 0], grid)
    ay = row_y(segs[:, 1], grid)
    bx = column_x(segs[:, 2], grid)
    by = row_y(segs[:, 3], grid)
    length = np.sqrt((bx - ax) ** 2 + (by - ay) ** 2)
    theta = np.empty(m)
    for i in range(m):
        theta[i] = math.atan2(by[i] - ay[i], bx[i] - ax[i]) % math.pi
    return Segments(ax, ay, bx, by, length, theta)


@njit(cache=True)
def dominant_direction(theta, length):
    """The direction (rad, in [0, π)) that most segment length shares: a histogram's peak.

    The histogram of ``theta`` has :data:`ANGLE_BINS` bins weighted by length and is smoothed
    circularly (a bin plus :data:`NEIGHBOUR_WEIGHT` of each neighbour); the peak bin's centre is
    returned.
    """
    hist = np.zeros(ANGLE_BINS)
    for i in range(theta.size):
        hist[int(theta[i] / math.pi * ANGLE_BINS) % ANGLE_BINS] += length[i]
    best_bin, best_val = 0, -1.0
    for b in range(ANGLE_BINS):
        v = hist[b] + NEIGHBOUR_WEIGHT * (hist[(b - 1) % ANGLE_BINS] + hist[(b + 1) % ANGLE_BINS])
        if v > best_val:
            best_bin, best_val = b, v
    return (best_bin + 0.5) * math.pi / ANGLE_BINS


@njit(cache=True)
def aligned_segments(theta, length, peak):
    """The segments within :data:`MAX_MISALIGNMENT` of direction ``peak``, and their mean direction.

    Returns ``(idx, direction)``: the segments' indices and their length-weighted mean direction
    (rad; doubled angles average a direction modulo π).
    """
    keep = np.zeros(theta.size, dtype=np.bool_)
    s2, c2 = 0.0, 0.0
    for i in range(theta.size):
        diff = abs((theta[i] - peak + 0.5 * math.pi) % math.pi - 0.5 * math.pi)
        if diff < MAX_MISALIGNMENT:
            keep[i] = True
            s2 += length[i] * math.sin(2.0 * theta[i])
            c2 += length[i] * math.cos(2.0 * theta[i])
    return np.nonzero(keep)[0], 0.5 * math.atan2(s2, c2)


@njit(cache=True)
def edge_groups(rho, weight, diameter):
    """Segments grouped into edges by their offsets across ``rho`` (m): single linkage.

    Consecutive offsets (sorted) closer than :data:`EDGE_LINK` diameters are one edge.

    Returns:
        ``(group, g_rho, g_len)``: each segment's group, and per group its weighted mean offset
        and its total ``weight`` (segment length).
    """
    k = rho.size
    order = np.argsort(rho)
    group = np.empty(k, dtype=np.int64)
    g = 0
    group[order[0]] = 0
    for j in range(1, k):
        if rho[order[j]] - rho[order[j - 1]] >= EDGE_LINK * diameter:
            g += 1
        group[order[j]] = g
    n_groups = g + 1
    g_rho = np.zeros(n_groups)
    g_len = np.zeros(n_groups)
    for j in range(k):
        g_rho[group[j]] += weight[j] * rho[j]
        g_len[group[j]] += weight[j]
    g_rho /= g_len
    return group, g_rho, g_len


@njit(cache=True)
def edge_pair(g_rho, g_len, diameter):
    """The two edges that make the pipe: ``(pa, pb, score)``, ``pa = −1`` if no pair qualifies.

    A pair qualifies if its edges lie :data:`MIN_PAIR_SEPARATION` to :data:`MAX_PAIR_SEPARATION`
    diameters apart and its weaker edge has at least :data:`MIN_EDGE_SHARE` of the stronger's
    segment length (:func:`best_pair`). An edge cut short by the border still counts.
    """
    return best_pair(g_rho, g_len, diameter, MIN_PAIR_SEPARATION, MAX_PAIR_SEPARATION, MIN_EDGE_SHARE)


@njit(cache=True)
def best_pair(g_rho, g_len, diameter, min_sep, max_sep, min_share):
    """The pair of edge groups with the most segment length: ``(pa, pb, score)``, ``pa = −1`` if none.

    A pair qualifies if its edges lie ``min_sep`` to ``max_sep`` diameters apart and its weaker
    edge has at least ``min_share`` of the stronger's segment length; ``score`` is the pair's
    segment length (m).
    """
    pa, pb, score = -1, -1, 0.0
    for i in range(g_rho.size):
        for j in range(i + 1, g_rho.size):
            sep = g_rho[j] - g_rho[i]
            total = g_len[i] + g_len[j]
            if (
                min_sep * diameter <= sep <= max_sep * diameter
                and min(g_len[i], g_len[j]) >= min_share * max(g_len[i], g_len[j])
                and total > score
            ):
                pa, pb, score = i, j, total
    return pa, pb, score


@njit(cache=True)
def segment_offsets(sg, idx, nx, ny):
    """Each segment ``idx[j]``'s offset across the leg (normal ``nx, ny``) at its midpoint, and its length."""
    k = idx.size
    rho = np.empty(k)
    wk = np.empty(k)
    for j in range(k):
        i = idx[j]
        rho[j] = 0.5 * (sg.ax[i] + sg.bx[i]) * nx + 0.5 * (sg.ay[i] + sg.by[i]) * ny
        wk[j] = sg.length[i]
    return rho, wk


@njit(cache=True)
def pair_span(sg, idx, group, pa, pb, dx, dy):
    """``(t_lo, t_hi)``: along the leg (``dx, dy``), the extent of edge groups ``pa`` and ``pb``."""
    t_lo, t_hi = math.inf, -math.inf
    for j in range(idx.size):
        if group[j] == pa or group[j] == pb:
            i = idx[j]
            ta = sg.ax[i] * dx + sg.ay[i] * dy
            tb = sg.bx[i] * dx + sg.by[i] * dy
            t_lo, t_hi = min(t_lo, ta, tb), max(t_hi, ta, tb)
    return t_lo, t_hi


@njit(cache=True)
def pair_confidence(score, extent, sep, diameter):
    """A pair's confidence in [0, 1]: its edges' coverage of its extent, times the separation's fit.

    ``score`` is the two edges' segment length and ``extent`` the pair's length along the leg
    (m): their ratio halved is the mean edge's coverage (at most 1). The separation's relative
    error enters as ``exp(−err²)``.
    """
    return min(1.0, 0.5 * score / extent) * math.exp(-(((sep - diameter) / diameter) ** 2))


@njit(cache=True)
def refine_edges(edges, grid, frame, extent, rho_a, rho_b):
    """Both edges of a leg fitted by least squares to their edge pixels.

    Each edge is a line ``s = offset + slope·u`` across against along (``frame``: a
    :class:`LegFrame`), starting at the Hough groups' offsets ``rho_a``, ``rho_b`` and no slope.
    Two passes, each on the edge pixels in a band of :data:`FIT_BANDS_PX` around the previous
    fit: the Hough direction is only good to a degree or two, so the second pass looks in a
    narrower band, and it may lengthen the leg by :data:`EXTEND` beyond the first's extent.

    Returns:
        ``(fit, u_lo, u_hi)``: per edge (rows) its offset at ``u = 0`` and its slope, and the
        last pass's range along of the pixels on either edge (at least ``[0, extent]``).
    """
    h, w = edges.shape
    px = pixel_pitch(grid)
    fit = np.empty((2, 2))  # per edge: offset at u = 0, slope
    fit[0, 0], fit[1, 0], fit[0, 1], fit[1, 1] = rho_a, rho_b, 0.0, 0.0
    u_lo, u_hi = 0.0, extent
    for band in range(len(FIT_BANDS_PX)):
        tol = FIT_BANDS_PX[band] * px
        reach = 0.0 if band == 0 else EXTEND  # the second pass may lengthen the line
        sums = np.zeros((2, 5))  # per edge: n, Σu, Σs, Σu², Σus
        u_lo, u_hi = 0.0, extent
        for r in range(h):
            y = row_y(r, grid)
            for c in range(w):
                if edges[r, c] == 0:
                    continue
                x = column_x(c, grid)
                u = x * frame.dx + y * frame.dy - frame.t_lo
                if u < -reach or u > extent + reach:
                    continue
                ps = x * frame.nx + y * frame.ny
                for e in range(2):
                    if abs(ps - fit[e, 0] - fit[e, 1] * u) < tol:
                        u_lo, u_hi = min(u_lo, u), max(u_hi, u)
                        add_edge_pixel(sums, e, u, ps)
        for e in range(2):
            if sums[e, 0] >= MIN_FIT_PIXELS:
                offset, slope, sloped = fit_edge(sums, e, MIN_FIT_SPREAD * extent)
                if sloped:  # too short a cluster keeps the previous fit
                    fit[e, 0], fit[e, 1] = offset, slope
    return fit, u_lo, u_hi
