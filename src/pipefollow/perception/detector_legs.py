"""The pipe detector's legs: the strongest straight piece of pipe, its ends, the border, the hook.

:func:`leg` chains the edge stages of :mod:`pipefollow.perception.detector_edges` into one
straight leg with its centre line's ends (:func:`leg_ends`, ends near the border carried onto it
by :func:`snap_to_border`); :func:`join_hook` carries an end that stops inside the footprint on
along a second leg after a sharp corner.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.detector_edges import (
    LegFrame,
    aligned_segments,
    dominant_direction,
    edge_groups,
    edge_pair,
    pair_confidence,
    pair_span,
    refine_edges,
    segment_geometry,
    segment_offsets,
)
from pipefollow.perception.pixels import pixel_grid, pixel_pitch
from pipefollow.sim.camera import clip_segment

# the thresholds of a leg, its ends and the hook (docs/decisions.md: "pairing", "refinement", "The detector
# at sharp corners")
MIN_SUPPORT = 0.25  # the two edges' length, ≥ this share of the footprint's longer side (not a texture patch)
SNAP_PX = 4.0  # pixels: an end this near the border goes onto it (Canny loses the last pixels at the border)
HOOK_MIN_TURN = math.radians(20.0)  # rad: a second leg's segments turn at least this from the first leg
HOOK_JOIN = 0.45  # m: a second leg starting this near an end stopped inside the view continues the pipe


class Leg(NamedTuple):
    """What :func:`leg` found: the strongest straight piece of pipe."""

    found: bool
    ends: np.ndarray  # 2 × 2: the centre line's two ends inside the footprint (rows x, y; unordered)
    confidence: float  # in [0, 1] (:func:`pair_confidence`)
    separation: float  # distance between the two fitted edges (m)


@njit(cache=True)
def leg(segs, edges, half_width, depth, diameter, min_confidence):
    """The strongest straight piece of pipe among the Hough segments, as a :class:`Leg`.

    The stages: the segments in metres (:func:`segment_geometry`), their dominant direction
    (:func:`dominant_direction`) and the segments along it (:func:`aligned_segments`), those
    grouped into edges by their offset across (:func:`edge_groups`), the pair of edges a pipe
    diameter apart (:func:`edge_pair`), its confidence (:func:`pair_confidence`), both edges
    refitted to the edge pixels (:func:`refine_edges`), and the centre line's ends
    (:func:`leg_ends`).
    """
    nothing = np.zeros((2, 2))
    h, w = edges.shape
    grid = pixel_grid(half_width, depth, h, w)
    sg = segment_geometry(segs, grid)
    idx, dirn = aligned_segments(sg.theta, sg.length, dominant_direction(sg.theta, sg.length))
    k = idx.size
    if k < 2:
        return Leg(False, nothing, 0.0, 0.0)
    dx, dy = math.cos(dirn), math.sin(dirn)
    nx, ny = -dy, dx
    rho, wk = segment_offsets(sg, idx, nx, ny)  # each segment's offset across, at its midpoint
    group, g_rho, g_len = edge_groups(rho, wk, diameter)
    pa, pb, score = edge_pair(g_rho, g_len, diameter)
    if pa < 0:
        return Leg(False, nothing, 0.0, 0.0)
    t_lo, t_hi = pair_span(sg, idx, group, pa, pb, dx, dy)  # the pair's extent along the leg
    extent = t_hi - t_lo
    confidence = pair_confidence(score, extent, g_rho[pb] - g_rho[pa], diameter)
    if confidence < min_confidence or score < MIN_SUPPORT * max(depth, 2.0 * half_width):
        return Leg(False, nothing, confidence, 0.0)
    frame = LegFrame(dx, dy, nx, ny, t_lo)
    fit, u_lo, u_hi = refine_edges(edges, grid, frame, extent, g_rho[pa], g_rho[pb])
    found, ends = leg_ends(fit, frame, u_lo, u_hi, grid)
    if not found:
        return Leg(False, nothing, confidence, 0.0)
    sep = abs(fit[1, 0] - fit[0, 0] + (fit[1, 1] - fit[0, 1]) * 0.5 * extent)
    return Leg(True, ends, confidence, sep)


@njit(cache=True)
def join_hook(ends, segs, edges, direction, half_width, depth, diameter, min_confidence):
    """Carry an end that stops inside the footprint on along a second leg that starts there (in place).

    The walk along the edges turns at most 60° a step and stops at a corner sharper than about
    100°. There the pipe goes on as a second straight leg in another direction: the strongest leg
    among the Hough segments more than :data:`HOOK_MIN_TURN` off the first leg's ``direction``
    (rad); if one of its ends lies within :data:`HOOK_JOIN` of the stopped end, that end moves to
    the second leg's other end.
    """
    h, w = edges.shape
    reach = SNAP_PX * pixel_pitch(pixel_grid(half_width, depth, h, w))
    inner = -1
    for e in range(2):
        x, y = ends[e, 0], ends[e, 1]
        if min(half_width - abs(x), y, depth - y) > reach:
            inner = e if inner < 0 else 2  # both inside: a short piece, no hook to follow
    if inner < 0 or inner == 2:
        return
    keep = np.zeros(segs.shape[0], dtype=np.bool_)
    for i in range(segs.shape[0]):
        # pixel rows run against y: the segment's direction in metres has its row difference negated
        t = math.atan2(-(segs[i, 3] - segs[i, 1]), segs[i, 2] - segs[i, 0])
        diff = abs((t - direction + 0.5 * math.pi) % math.pi - 0.5 * math.pi)
        keep[i] = diff > HOOK_MIN_TURN
    if keep.sum() < 2:
        return
    found, second, _, _ = leg(segs[keep], edges, half_width, depth, diameter, min_confidence)
    if not found:
        return
    x, y = ends[inner, 0], ends[inner, 1]
    da = math.hypot(second[0, 0] - x, second[0, 1] - y)
    db = math.hypot(second[1, 0] - x, second[1, 1] - y)
    if min(da, db) < HOOK_JOIN:
        o = 1 if da < db else 0
        ends[inner, 0], ends[inner, 1] = second[o, 0], second[o, 1]


@njit(cache=True)
def leg_ends(fit, frame, u_lo, u_hi, grid):
    """The centre line between two fitted edges, from ``u_lo`` to ``u_hi`` along, inside the footprint.

    Ends within :data:`SNAP_PX` pixels of the border are moved onto it (:func:`snap_to_border`);
    the line is then clipped to the footprint (the wider edges reach beyond the centre line's exit).

    Returns:
        ``(inside, ends)``: whether any of it lies inside, and its two ends (rows x, y).
    """
    icpt = 0.5 * (fit[0, 0] + fit[1, 0])
    slope = 0.5 * (fit[0, 1] + fit[1, 1])
    ends = np.empty((2, 2))
    for e in range(2):
        u = u_lo if e == 0 else u_hi
        s = icpt + slope * u
        t = frame.t_lo + u
        ends[e, 0], ends[e, 1] = t * frame.dx + s * frame.nx, t * frame.dy + s * frame.ny
    half_width, depth = grid.half_width, grid.depth
    snap_to_border(ends, half_width, depth, SNAP_PX * pixel_pitch(grid))
    ax0, ay0, bx0, by0 = ends[0, 0], ends[0, 1], ends[1, 0], ends[1, 1]
    t0, t1 = clip_segment(ax0, ay0, bx0, by0, -half_width, half_width, 0.0, depth)
    out = np.empty((2, 2))
    if t0 > t1:
        return False, out
    out[0, 0], out[0, 1] = ax0 + t0 * (bx0 - ax0), ay0 + t0 * (by0 - ay0)
    out[1, 0], out[1, 1] = ax0 + t1 * (bx0 - ax0), ay0 + t1 * (by0 - ay0)
    return True, out


@njit(cache=True)
def snap_to_border(ends, half_width, depth, reach):
    """Move each end (rows of ``ends``) within ``reach`` of the footprint's border onto it, along the line.

    Edge detectors lose the last pixels at the border; the truth's ends lie on it when the pipe
    crosses it.
    """
    for e in range(2):
        x, y = ends[e, 0], ends[e, 1]
        ox, oy = ends[1 - e, 0], ends[1 - e, 1]
        if min(half_width - abs(x), y, depth - y) >= reach:
            continue
        ddx, ddy = x - ox, y - oy
        best = math.inf
        # the smallest step beyond (x, y) along the line that reaches an edge of the rectangle
        for q in range(4):
            edge = half_width if q == 0 else (-half_width if q == 1 else (depth if q == 2 else 0.0))
            comp, delta = (x, ddx) if q < 2 else (y, ddy)
            if abs(delta) > 1e-12:
                step = (edge - comp) / delta
                if 0.0 <= step < best:
                    best = step
        if best * math.sqrt(ddx * ddx + ddy * ddy) < 2.0 * reach:
            ends[e, 0], ends[e, 1] = x + best * ddx, y + best * ddy
