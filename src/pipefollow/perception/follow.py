"""Following a pipe found as a straight leg along its two edges to the ends of the visible piece.

The detector's Hough step finds the pipe's strongest straight leg. A pipe that bends or curves in
view goes on beyond it, and the exact camera (:mod:`pipefollow.sim.camera`) reports the whole
visible piece: its far end lies after the bend. :func:`follow_pipe` walks from an end of the leg
in short steps; each step tries turns of up to :data:`MAX_TURN` and a pixel of sideways shift, and
takes the one whose two edge lines (half the measured edge separation either side of the centre)
fall on the most edge pixels. It stops where no step keeps both edges (the pipe ends, is buried
or leaves the footprint), which is the visible piece's end.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

STEP_PX = 4.0  # step length in pixels
SAMPLES = 8  # points on each edge line over a step's look-ahead
LOOK_AHEAD = 2.0  # steps: a step is scored on the edges this far ahead (a corner is not a dead end)
MAX_TURN = math.radians(60.0)  # largest turn per step (a bend of 90° takes two steps)
TURNS = 17  # turns tried per step, evenly from −MAX_TURN to MAX_TURN (7.5° apart)
MIN_HEADING = math.cos(math.radians(120.0))  # the walk turns at most 120° from its start's direction
MIN_HITS = 0.75  # share of the step's edge points that must lie on edge pixels
SHIFTS = 3  # sideways shifts tried per turn: 0, ±1 pixel
TAIL = 3  # steps: the end's line is refitted to the edge pixels of the walk's last TAIL steps


@njit(cache=True)
def on_edge(edges, x, y, half_width, depth, sx, sy):
    """1 if the point (camera metres) lies within a pixel of a set pixel of ``edges``, 0 if not, −1 outside.

    The pixel of tolerance lets an edge line a pixel off (a staircase edge, a step's rounding) hit.
    """
    h, w = edges.shape
    c = int(math.floor((x + half_width) / sx))
    r = int(math.floor((depth - y) / sy))
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
        ``(x, y, steps, tail_x, tail_y, exited)``: the last point on the pipe inside the footprint
        (on its border if the walk ``exited``), the steps taken, and the walk's point :data:`TAIL`
        steps before the end (or its start).
    """
    h, w = edges.shape
    sx, sy = 2.0 * half_width / w, depth / h
    px = max(sx, sy)
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
                        e = on_edge(edges, qx + side * half_sep * mx, qy + side * half_sep * my,
                                    half_width, depth, sx, sy)  # fmt: skip
                        if e >= 0:
                            valid += 1
                            hits += e
                if valid >= 4:
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
            return x + f * (bx - x), y + f * (by - y), n, tail_x[k], tail_y[k], True
        x, y, ux, uy = bx, by, bux, buy
        tail_x[n % (TAIL + 1)], tail_y[n % (TAIL + 1)] = x, y
    k = (n - min(n, TAIL)) % (TAIL + 1)
    return x, y, n, tail_x[k], tail_y[k], False


@njit(cache=True)
def refine_end(edges, tail_x, tail_y, x, y, half_sep, half_width, depth, exited):
    """The walk's end ``(x, y)`` moved onto the least-squares centre line of its last stretch.

    The walk's steps turn by whole multiples of 7.5° and shift by whole pixels, so its last step
    can be a few centimetres off the pipe's centre line, which a border crossing at a shallow
    angle magnifies. Each edge is fitted (offset across against position along) to its edge
    pixels within 1.5 pixels of the stretch from ``(tail_x, tail_y)`` to the end; the end is then
    the refitted centre line's point at the same distance along, or, if the walk ``exited``, where
    that line leaves the footprint. With too few edge pixels the end stays.
    """
    h, w = edges.shape
    sx, sy = 2.0 * half_width / w, depth / h
    px = max(sx, sy)
    ux, uy = x - tail_x, y - tail_y
    length = math.sqrt(ux * ux + uy * uy)
    if length < 2.0 * px:
        return x, y
    ux, uy = ux / length, uy / length
    nx, ny = -uy, ux
    tol = 1.5 * px
    reach = half_sep + 2.0 * tol
    sums = np.zeros((2, 5))  # n, Σa, Σs, Σaa, Σas per edge
    c_lo = max(int((min(tail_x, x) - reach + half_width) / sx), 0)
    c_hi = min(int((max(tail_x, x) + reach + half_width) / sx) + 1, w)
    r_lo = max(int((depth - max(tail_y, y) - reach) / sy), 0)
    r_hi = min(int((depth - min(tail_y, y) + reach) / sy) + 1, h)
    for r in range(r_lo, r_hi):
        qy = depth - (r + 0.5) * sy - tail_y
        for c in range(c_lo, c_hi):
            if edges[r, c] == 0:
                continue
            qx = -half_width + (c + 0.5) * sx - tail_x
            a = qx * ux + qy * uy
            if a < 0.0 or a > length + px:
                continue
            s = qx * nx + qy * ny
            for e in range(2):
                if abs(s - (2 * e - 1) * half_sep) < tol:
                    sums[e, 0] += 1.0
                    sums[e, 1] += a
                    sums[e, 2] += s
                    sums[e, 3] += a * a
                    sums[e, 4] += a * s
    icpt, slope = 0.0, 0.0
    for e in range(2):
        n_e, sa, ss, saa, sas = sums[e, 0], sums[e, 1], sums[e, 2], sums[e, 3], sums[e, 4]
        if n_e < 4:
            return x, y
        var = n_e * saa - sa * sa
        b = (n_e * sas - sa * ss) / var if math.sqrt(max(var, 0.0)) / n_e > 0.2 * length else 0.0
        icpt += 0.5 * ((ss - b * sa) / n_e)
        slope += 0.5 * b
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

    Each walk starts ``retract`` (m) back inside the leg, at most 0.4 of its length: the leg's
    fitted line may have been lengthened that far (the detector's ``EXTEND``) past a bend.

    Returns the number of steps taken beyond the leg's ends.
    """
    h, w = edges.shape
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
        back = min(retract, 0.4 * norm)
        x, y, n, tx, ty, exited = follow_pipe(edges, leg[e, 0] - back * ux, leg[e, 1] - back * uy, ux, uy,
                                              half_sep, half_width, depth, max_steps)  # fmt: skip
        if n * STEP_PX * max(2.0 * half_width / w, depth / h) < back:
            # it did not get back to the leg's end (patchy edges, or a start off a curved pipe):
            # from the leg's end itself, and where no step is taken there the fitted end stays
            x, y, n, tx, ty, exited = follow_pipe(edges, leg[e, 0], leg[e, 1], ux, uy, half_sep, half_width,
                                                  depth, max_steps)  # fmt: skip
            if n == 0:
                continue
        ends[e, 0], ends[e, 1] = refine_end(edges, tx, ty, x, y, half_sep, half_width, depth, exited)
        total += n
    return total
