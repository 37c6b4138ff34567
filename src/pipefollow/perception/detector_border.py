"""The pipe detector's second look: a short piece of pipe cut by the view's border.

Where the pipe only crosses a corner or runs along a side of the footprint, its visible piece is
shorter than the Hough segments :func:`~pipefollow.perception.detector.detect_pipe` asks for
(1/8 of the shorter side) and than the support a straight leg needs (a share of the footprint's
longer side), so the first look misses it. When the first look finds nothing, :func:`border_piece`
looks again at segments half as long, near the border only, with thresholds relative to the
piece's own visible length: the pair of edges a diameter apart (tighter than the first look's),
both ends of its centre line on the border (the piece is short because the border cuts it), its
edges covering the piece, and the pipe brighter between its edges than the seabed beside them.
docs/decisions.md ("a short piece at the border") has the measurements behind the thresholds.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pipefollow.perception.detector_edges import (
    LegFrame,
    aligned_segments,
    best_pair,
    dominant_direction,
    edge_groups,
    pair_confidence,
    pair_span,
    refine_edges,
    segment_geometry,
    segment_offsets,
)
from pipefollow.perception.detector_legs import Leg, leg_ends
from pipefollow.perception.pixels import column_at, pixel_grid, row_at

BORDER_HOUGH_SHARE = 16  # the second look's Hough segments: 1/this of the shorter side in votes and length
BORDER_BAND = 0.5  # m: a segment of the second look lies with both ends this near the border
BORDER_MIN_SEP = 0.7  # diameters: the two edges at least this far apart and ...
BORDER_MAX_SEP = 1.3  # ... at most this far (the first look: MIN_PAIR_SEPARATION to MAX_PAIR_SEPARATION)
BORDER_MIN_SHARE = 0.1  # weaker edge's length / stronger's, ≥ this
BORDER_REACH = 0.25  # m: both ends of the centre line this near the border (the border cuts the piece)
BORDER_SUPPORT = 0.8  # the two edges' length, ≥ this share of the centre line's visible length
BORDER_MAX_LENGTH = 1.2  # m: a longer piece is the first look's to find
BORDER_CONTRAST = 4.0  # grey levels: the pipe's middle brighter than the seabed beside each edge, by this


@njit(cache=True)
def border_piece(segs, edges, smooth, half_width, depth, diameter, min_confidence):
    """A short piece of pipe cut by the border among low-threshold Hough segments, as a ``Leg``.

    ``segs`` are Hough segments (pixels ``x0, y0, x1, y1``) of the second look, ``edges`` the
    Canny image and ``smooth`` the pre-blurred grey image. The stages are the first look's
    (dominant direction, edge groups, refit, ends) on the segments within :data:`BORDER_BAND` of
    the border, with the checks of the module's docstring.
    """
    nothing = np.zeros((2, 2))
    fail = Leg(False, nothing, 0.0, 0.0)
    h, w = edges.shape
    grid = pixel_grid(half_width, depth, h, w)
    sg = segment_geometry(segs, grid)
    m = segs.shape[0]
    near = np.zeros(m, dtype=np.bool_)
    for i in range(m):
        da = min(half_width - abs(sg.ax[i]), sg.ay[i], depth - sg.ay[i])
        db = min(half_width - abs(sg.bx[i]), sg.by[i], depth - sg.by[i])
        near[i] = max(da, db) < BORDER_BAND
    if near.sum() < 2:
        return fail
    sel = np.nonzero(near)[0]
    theta, length = sg.theta[sel], sg.length[sel]
    idx_local, dirn = aligned_segments(theta, length, dominant_direction(theta, length))
    k = idx_local.size
    if k < 2:
        return fail
    dx, dy = math.cos(dirn), math.sin(dirn)
    nx, ny = -dy, dx
    idx = sel[idx_local]
    rho, wk = segment_offsets(sg, idx, nx, ny)
    group, g_rho, g_len = edge_groups(rho, wk, diameter)
    pa, pb, score = best_pair(g_rho, g_len, diameter, BORDER_MIN_SEP, BORDER_MAX_SEP, BORDER_MIN_SHARE)
    if pa < 0:
        return fail
    t_lo, t_hi = pair_span(sg, idx, group, pa, pb, dx, dy)
    extent = t_hi - t_lo
    confidence = pair_confidence(score, extent, g_rho[pb] - g_rho[pa], diameter)
    if confidence < min_confidence:
        return Leg(False, nothing, confidence, 0.0)
    frame = LegFrame(dx, dy, nx, ny, t_lo)
    fit, u_lo, u_hi = refine_edges(edges, grid, frame, extent, g_rho[pa], g_rho[pb])
    found, ends = leg_ends(fit, frame, u_lo, u_hi, grid)
    if not found:
        return Leg(False, nothing, confidence, 0.0)
    visible = math.hypot(ends[1, 0] - ends[0, 0], ends[1, 1] - ends[0, 1])
    if visible > BORDER_MAX_LENGTH or score < BORDER_SUPPORT * visible:
        return Leg(False, nothing, confidence, 0.0)
    for e in range(2):
        x, y = ends[e, 0], ends[e, 1]
        if min(half_width - abs(x), y, depth - y) > BORDER_REACH:
            return Leg(False, nothing, confidence, 0.0)
    sep = abs(fit[1, 0] - fit[0, 0] + (fit[1, 1] - fit[0, 1]) * 0.5 * extent)
    if not brighter_inside(smooth, grid, ends, nx, ny, sep):
        return Leg(False, nothing, confidence, 0.0)
    return Leg(True, ends, confidence, sep)


@njit(cache=True)
def brighter_inside(smooth, grid, ends, nx, ny, sep):
    """Whether the grey level along the centre line exceeds that a separation beside it, on each side in view.

    Samples along the line between ``ends`` (rows x, y) at the centre and offset by ``±sep``
    across (``nx, ny``); a side with fewer than 3 samples inside the image does not count; at
    least one side must count and every side that counts must be darker by :data:`BORDER_CONTRAST`.
    """
    h, w = smooth.shape
    n = 16
    sums = np.zeros(3)
    counts = np.zeros(3)
    for q in range(n):
        f = (q + 0.5) / n
        x0 = ends[0, 0] + f * (ends[1, 0] - ends[0, 0])
        y0 = ends[0, 1] + f * (ends[1, 1] - ends[0, 1])
        for side in range(3):
            off = 0.0 if side == 0 else (sep if side == 1 else -sep)
            c = int(math.floor(column_at(x0 + off * nx, grid)))
            r = int(math.floor(row_at(y0 + off * ny, grid)))
            if 0 <= r < h and 0 <= c < w:
                sums[side] += float(smooth[r, c])
                counts[side] += 1.0
    if counts[0] < 3:
        return False
    centre = sums[0] / counts[0]
    sides = 0
    for side in range(1, 3):
        if counts[side] >= 3:
            sides += 1
            if sums[side] / counts[side] > centre - BORDER_CONTRAST:
                return False
    return sides > 0
