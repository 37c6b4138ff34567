"""Following a pipe found as a straight leg along its two edges to the ends of the visible piece.

The detector's Hough step finds the pipe's strongest straight leg. A pipe that bends or curves in
view goes on beyond it, and the exact camera (:mod:`pipefollow.sim.camera`) reports the whole
visible piece: its far end lies after the bend. :func:`follow_pipe` walks from an end of the leg
in short steps; each step tries turns of up to :data:`MAX_TURN` and a pixel of sideways shift, and
takes the one whose two edge lines (half the measured edge separation either side of the centre)
fall on the most edge pixels. It stops where no step keeps both edges (the pipe ends, is buried
or leaves the footprint), which is the visible piece's end.

:func:`add_edge_pixel` and :func:`fit_edge` are the least-squares fit of an edge (offset across
against position along) that both the detector's leg and the walk's end refit use.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.pixels import column_at, column_x, pixel_grid, pixel_pitch, row_at, row_y

STEP_PX = 4.0  # step length in pixels
SAMPLES = 8  # points on each edge line over a step's look-ahead
LOOK_AHEAD = 2.0  # steps: a step is scored on the edges this far ahead (a corner is not a dead end)
MAX_TURN = math.radians(60.0)  # largest turn per step (a bend of 90° takes two steps)
TURNS = 17  # turns tried per step, evenly from −MAX_TURN to MAX_TURN (7.5° apart)
MIN_HEADING = math.cos(math.radians(120.0))  # the walk turns at most 120° from its start's direction
MIN_HITS = 0.75  # share of the step's edge points that must lie on edge pixels
SHIFTS = 3  # sideways shifts tried per turn: 0, ±1 pixel
TAIL = 3  # steps: the end's line is refitted to the edge pixels of the walk's last TAIL steps
MAX_RETRACT = 0.4  # share of a leg's length a walk may start back inside it (the rest is trusted)
MIN_VALID = 4  # edge points inside the footprint a step needs to be scored (fewer: it looks out of view)
REFIT_BAND_PX = 1.5  # pixels: edge pixels this close to an edge line count for the end's refit
MIN_REFIT_STRETCH_PX = 2.0  # pixels: a shorter last stretch gives no direction, the end stays
MIN_REFIT_PIXELS = 4  # edge pixels per edge the end's refit needs; with fewer the end stays
MIN_REFIT_SPREAD = 0.2  # share of the stretch the pixels' positions along must spread (s.d.) for a slope


class Walk(NamedTuple):
    """Where :func:`follow_pipe` stopped."""

    x: float  # the last point on the pipe inside the footprint (camera metres), lateral ...
    y: float  # ... and forward; on the border if the walk exited
    steps: int  # steps taken
    tail_x: float  # the walk's point TAIL steps before the end (or its start), lateral ...
    tail_y: float  # ... and forward
    exited: bool  # whether the walk left the footprint


@njit(cache=True)
def add_edge_pixel(sums, e, u, s):
    """Add an edge pixel at position ``u`` along and offset ``s`` across to edge ``e``'s sums.

    ``sums[e]`` holds n, Σu, Σs, Σu², Σus: the sufficient statistics of :func:`fit_edge`.
    """
    sums[e, 0] += 1.0
    sums[e, 1] += u
    sums[e, 2] += s
    sums[e, 3] += u * u
    sums[e, 4] += u * s


@njit(cache=True)
def fit_edge(sums, e, min_spread):
    """Least-squares line ``s = intercept + slope·u`` through edge ``e``'s pixels (:func:`add_edge_pixel`).

    The detector's leg and the walk's ends both fit an edge as its offset across against the
    position along. The slope is fitted only if the pixels' positions along spread (s.d.) more
    than ``min_spread``: a short cluster gives no direction, so the slope is then 0 and the
    intercept the mean offset. ``sums[e, 0]`` (the pixel count) must be positive.

    Returns:
        ``(intercept, slope, sloped)``, ``sloped`` whether the slope was fitted.
    """
    n, su, ss, suu, sus = sums[e, 0], sums[e, 1], sums[e, 2], sums[e, 3], sums[e, 4]
    var = n * suu - su * su  # n² times the positions' variance
    slope = 0.0
    sloped = math.sqrt(max(var, 0.0)) / n > min_spread
    if sloped:
        slope = (n * sus - su * ss) / var
    return (ss - slope * su) / n, slope, sloped


@njit(cache=True)
def on_edge(edges, x, y, grid):
    """1 if the point (camera metres) lies within a pixel of a set pixel of ``edges``, 0 if not, −1 outside.

    ``grid`` is the image's :class:`~pipefollow.perception.pixels.PixelGrid`. The pixel of
    tolerance lets an edge line a pixel off (a staircase edge, a step's rounding) hit.
    """
    h, w = edges.shape
    c = int(math.floor(column_at(x, grid)))
    r = int(math.floor(row_at(y, grid)))
    if c < 0 or c >= w or r < 0 or r >= h:
        return -1
    for rr in range(max(r - 1, 0), min(r + 2, h)):
        for cc in range(max(c - 1, 0), min(c + 2, w)):
            if edges[rr, cc] != 0:
                return 1
    return 0


@njit(cache=True)
def follow_pipe(edges, x, y, ux, uy, half_sep, half_width, depth, max_steps):
    """Walk along the pipe from the centre-line point ``(x, y)`` in direction ``(ux, uy)`` (unit).

    Args:
        edges: the edge image, row 0 the far edge y = ``depth``.
        x: the start's lateral position, on the centre line (camera metres).
        y: the start's forward position.
        ux: the walk's direction, a unit vector: lateral component ...
        uy: ... and forward component.
        half_sep: half the distance between the pipe's two edges (m).
        half_width: the footprint's lateral half-width (m).
        depth: the footprint's forward extent (m).
        max_steps: at most this many steps.

    Returns:
        A :class:`Walk`: the last point on the pipe inside the footprint (on its border if the
        walk ``exited``), the steps taken, and the walk's point :data:`TAIL` steps before the end
        (or its start).
    """
    h, w = edges.shape
    grid = pixel_grid(half_width, depth, h, w)
    px = pixel_pitch(grid)
    step = STEP_PX * px
    n = 0
    tail_x, tail_y = np.empty(TAIL + 1), np.empty(TAIL + 1)  # the last points, a ring
    tail_x[0], tail_y[0] = x, y
    ux0, uy0 = ux, uy
    while n < max_steps:
        best, bx, by, bux, buy = -1.0, 0.0, 0.0, 0.0, 0.0
        for t in range(TURNS):
            # turns in the order 0, +, −, ++, −−, ...: a tie keeps the smaller turn
            k = (t + 1) // 2
            turn = (k if t % 2 == 1 else -k) * MAX_TURN / ((TURNS - 1) // 2)
            cs, sn = math.cos(turn), math.sin(turn)
            vx, vy = cs * ux - sn * uy, sn * ux + cs * uy
            if vx * ux0 + vy * uy0 < MIN_HEADING:  # not back along the pipe it came
                continue
            mx, my = -vy, vx
            for d in range(SHIFTS):
                shift = (0.0, px, -px)[d]
                hits, valid = 0, 0
                for s in range(1, SAMPLES + 1):
                    a = LOOK_AHEAD * step * s / SAMPLES
                    qx, qy = x + shift * mx + a * vx, y + shift * my + a * vy
                    for side in (-1.0, 1.0):
                        e = on_edge(edges, qx + side * half_sep * mx, qy + side * half_sep * my, grid)
                        if e >= 0:
                            valid += 1
                            hits += e
                if valid >= MIN_VALID:
                    score = hits / valid
                    if score > best:
                        best = score
                        bx, by = x + shift * mx + step * vx, y + shift * my + step * vy
                        bux, buy = vx, vy
                if best == 1.0:  # nothing beats it, and ties keep the first
                    break
            if best == 1.0:
                break
        if best < MIN_HITS:
            break
        n += 1
        if abs(bx) > half_width or by < 0.0 or by > depth:
            # the step leaves the footprint: its end is where the step crosses the border
            f = 1.0
            if abs(bx) > half_width:
                f = min(f, (math.copysign(half_width, bx) - x) / (bx - x))
            if by < 0.0:
                f = min(f, -y / (by - y))
            if by > depth:
                f = min(f, (depth - y) / (by - y))
            f = max(f, 0.0)
            k = (n - min(n, TAIL)) % (TAIL + 1)
            return Walk(x + f * (bx - x), y + f * (by - y), n, tail_x[k], tail_y[k], True)
        x, y, ux, uy = bx, by, bux, buy
        tail_x[n % (TAIL + 1)], tail_y[n % (TAIL + 1)] = x, y
    k = (n - min(n, TAIL)) % (TAIL + 1)
    return Walk(x, y, n, tail_x[k], tail_y[k], False)


@njit(cache=True)
def refine_end(edges, tail_x, tail_y, x, y, half_sep, half_width, depth, exited):
    """The walk's end ``(x, y)`` moved onto the least-squares centre line of its last stretch.

    The walk's steps turn by whole multiples of 7.5° and shift by whole pixels, so its last step
    can be a few centimetres off the pipe's centre line, which a border crossing at a shallow
    angle magnifies. Each edge is fitted (offset across against position along, :func:`fit_edge`)
    to its edge pixels within :data:`REFIT_BAND_PX` pixels of the stretch from ``(tail_x, tail_y)``
    to the end; the end is then the refitted centre line's point at the same distance along, or,
    if the walk ``exited``, where that line leaves the footprint. With too few edge pixels
    (:data:`MIN_REFIT_PIXELS`) the end stays.
    """
    h, w = edges.shape
    grid = pixel_grid(half_width, depth, h, w)
    px = pixel_pitch(grid)
    ux, uy = x - tail_x, y - tail_y
    length = math.sqrt(ux * ux + uy * uy)
    if length < MIN_REFIT_STRETCH_PX * px:
        return x, y
    ux, uy = ux / length, uy / length
    nx, ny = -uy, ux
    tol = REFIT_BAND_PX * px
    # the box around the stretch that holds every pixel within tol of an edge line
    reach = half_sep + 2.0 * tol
    sums = np.zeros((2, 5))  # per edge: n, Σa, Σs, Σa², Σas (a along from the tail, s across)
    c_lo = max(int(column_at(min(tail_x, x) - reach, grid)), 0)
    c_hi = min(int(column_at(max(tail_x, x) + reach, grid)) + 1, w)
    r_lo = max(int(row_at(max(tail_y, y) + reach, grid)), 0)
    r_hi = min(int(row_at(min(tail_y, y) - reach, grid)) + 1, h)
    for r in range(r_lo, r_hi):
        qy = row_y(r, grid) - tail_y
        for c in range(c_lo, c_hi):
            if edges[r, c] == 0:
                continue
            qx = column_x(c, grid) - tail_x
            a = qx * ux + qy * uy
            if a < 0.0 or a > length + px:
                continue
            s = qx * nx + qy * ny
            for e in range(2):
                if abs(s - (2 * e - 1) * half_sep) < tol:
                    add_edge_pixel(sums, e, a, s)
    icpt, slope = 0.0, 0.0  # of the centre line: the mean of the two edges' fits
    for e in range(2):
        if sums[e, 0] < MIN_REFIT_PIXELS:
            return x, y
        edge_icpt, edge_slope, _ = fit_edge(sums, e, MIN_REFIT_SPREAD * length)
        icpt += 0.5 * edge_icpt
        slope += 0.5 * edge_slope
    # the refitted centre line: tail + a·u + (icpt + slope·a)·n
    dx, dy = ux + slope * nx, uy + slope * ny
    norm = math.sqrt(dx * dx + dy * dy)
    dx, dy = dx / norm, dy / norm
    ox, oy = tail_x + icpt * nx, tail_y + icpt * ny
    if not exited:
        ex, ey = ox + length * ux + slope * length * nx, oy + length * uy + slope * length * ny
        return min(max(ex, -half_width), half_width), min(max(ey, 0.0), depth)
    # where the refitted line leaves the footprint, going on from its start
    best = math.inf
    if dx > 1e-12:
        best = min(best, (half_width - ox) / dx)
    elif dx < -1e-12:
        best = min(best, (-half_width - ox) / dx)
    if dy > 1e-12:
        best = min(best, (depth - oy) / dy)
    elif dy < -1e-12:
        best = min(best, -oy / dy)
    if not (0.0 <= best < math.inf):
        return x, y
    return min(max(ox + best * dx, -half_width), half_width), min(max(oy + best * dy, 0.0), depth)


@njit(cache=True)
def extend_ends(ends, edges, half_sep, half_width, depth, retract):
    """Follow the pipe beyond both ends of a straight leg (rows of ``ends``, in place).

    Each walk starts ``retract`` (m) back inside the leg, at most :data:`MAX_RETRACT` of its
    length: the leg's fitted line may have been lengthened that far (the detector's ``EXTEND``)
    past a bend.

    Returns the number of steps taken beyond the leg's ends.
    """
    h, w = edges.shape
    px = pixel_pitch(pixel_grid(half_width, depth, h, w))
    max_steps = int((h + w) / STEP_PX) + 1
    total = 0
    leg = ends.copy()
    for e in range(2):
        dx, dy = leg[e, 0] - leg[1 - e, 0], leg[e, 1] - leg[1 - e, 1]
        norm = math.sqrt(dx * dx + dy * dy)
        if norm == 0.0:
            continue
        ux, uy = dx / norm, dy / norm
        # start back inside the leg: its fitted line may overshoot a bend along the other leg's edge
        back = min(retract, MAX_RETRACT * norm)
        walk = follow_pipe(edges, leg[e, 0] - back * ux, leg[e, 1] - back * uy, ux, uy,
                           half_sep, half_width, depth, max_steps)  # fmt: skip
        if walk.steps * STEP_PX * px < back:
            # it did not get back to the leg's end (patchy edges, or a start off a curved pipe):
            # from the leg's end itself, and where no step is taken there the fitted end stays
            walk = follow_pipe(edges, leg[e, 0], leg[e, 1], ux, uy, half_sep, half_width, depth, max_steps)
            if walk.steps == 0:
                continue
        ends[e, 0], ends[e, 1] = refine_end(
            edges, walk.tail_x, walk.tail_y, walk.x, walk.y, half_sep, half_width, depth, walk.exited
        )
        total += walk.steps
    return total
