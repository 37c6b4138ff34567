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

from numba import njit

STEP_PX = 4.0  # step length in pixels
SAMPLES = 4  # points per step on each edge line
MAX_TURN = math.radians(60.0)  # largest turn per step (a bend of 90° takes two steps)
TURNS = 17  # turns tried per step, evenly from −MAX_TURN to MAX_TURN
RETRACT = 0.4  # m: the walk starts this far back inside the leg (the refinement's EXTEND)
MIN_HITS = 0.75  # share of the step's edge points that must lie on edge pixels


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
        ``(x, y, steps)``: the last point on the pipe inside the footprint and the steps taken.
    """
    h, w = edges.shape
    sx, sy = 2.0 * half_width / w, depth / h
    px = max(sx, sy)
    step = STEP_PX * px
    n = 0
    while n < max_steps:
        best, bx, by, bux, buy = -1.0, 0.0, 0.0, 0.0, 0.0
        for t in range(TURNS):
            # turns in the order 0, +, −, ++, −−, ...: a tie keeps the smaller turn
            k = (t + 1) // 2
            turn = (k if t % 2 == 1 else -k) * MAX_TURN / ((TURNS - 1) // 2)
            cs, sn = math.cos(turn), math.sin(turn)
            vx, vy = cs * ux - sn * uy, sn * ux + cs * uy
            mx, my = -vy, vx
            for d in range(3):
                shift = (0.0, px, -px)[d]
                hits, valid = 0, 0
                for s in range(1, SAMPLES + 1):
                    a = step * s / SAMPLES
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
            return x + f * (bx - x), y + f * (by - y), n
        x, y, ux, uy = bx, by, bux, buy
    return x, y, n


@njit(cache=True)
def extend_ends(ends, edges, half_sep, half_width, depth):
    """Follow the pipe beyond both ends of a straight leg (rows of ``ends``, in place).

    Returns the number of steps taken beyond the leg's ends.
    """
    h, w = edges.shape
    max_steps = int((h + w) / STEP_PX) + 1
    total = 0
    for e in range(2):
        dx, dy = ends[e, 0] - ends[1 - e, 0], ends[e, 1] - ends[1 - e, 1]
        norm = math.sqrt(dx * dx + dy * dy)
        if norm == 0.0:
            continue
        ux, uy = dx / norm, dy / norm
        # start back inside the leg: its fitted line may overshoot a bend along the other leg's edge
        back = min(RETRACT, 0.4 * norm)
        x, y, n = follow_pipe(edges, ends[e, 0] - back * ux, ends[e, 1] - back * uy, ux, uy, half_sep,
                              half_width, depth, max_steps)  # fmt: skip
        ends[e, 0], ends[e, 1] = x, y
        total += n
    return total
