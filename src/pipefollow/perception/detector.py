"""A classical pipe detector on grey camera images (issue 15, item 2), with OpenCV.

The steps of the underwater pipeline-tracking literature: Canny edges, the probabilistic Hough
transform, the dominant direction of the line segments (a length-weighted angle histogram), the
pipe's two edges paired into a centre line (two parallel groups of segments about a pipe diameter
apart), each edge refined by a least-squares fit to its edge pixels, then both ends followed
along the two edges beyond the straight leg, through bends and curves. The result is the paper's
observation ``(x1, y1, x2)`` in camera metres by the pixel conventions of
:mod:`pipefollow.perception.image` (also ``y_near``), plus a confidence.

It works on any grey ``uint8`` image of the footprint, not only on this package's renders, and on
other sizes and footprints when told the footprint. OpenCV is the optional extra ``vision``
(``pip install "pipefollow[vision]"``); it is imported on the first detection.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.follow import extend_ends
from pipefollow.sim.camera import clip_segment

MIN_SIDE = 16  # smallest image side (pixels) the detector accepts
EDGE_FACTOR = 3.2  # Canny's high threshold in mean gradients of the image ...
MIN_EDGE = 24.0  # ... and at least this (Canny's 3×3 Sobel units)
MIN_EDGE_SHARE = 0.1  # the weaker edge's segment length, at least this share of the stronger's
MIN_SUPPORT = 0.25  # the two edges' segment length, at least this share of the footprint's longer side
EXTEND = 0.4  # m: how far edge pixels may lengthen the Hough segments' extent (and the walk starts back)
SOBEL_GAIN = 8.0  # a 3×3 Sobel gives 8× the central-difference gradient
_CV2 = None


class Detection(NamedTuple):
    """What :func:`detect_pipe` found: ``found`` and, if so, the pipe's centre line in view.

    ``(x2, y_near)`` is the near end (the end nearer the AUV's centre, the footprint's origin:
    the pipe comes from behind the AUV), ``(x1, y1)`` the far end, in camera metres;
    ``confidence`` in [0, 1]. Without a pipe the numbers are 0.
    """

    found: bool
    x1: float = 0.0
    y1: float = 0.0
    x2: float = 0.0
    y_near: float = 0.0
    confidence: float = 0.0


NOT_FOUND = Detection(False)


def require_cv2():
    """OpenCV's module, set to one thread; a one-line ``ImportError`` naming the extra when it is missing."""
    global _CV2
    if _CV2 is None:
        try:
            import cv2
        except ImportError:
            raise ImportError(
                "the vision camera needs OpenCV: install the extra 'vision' "
                '(pip install "pipefollow[vision]")'
            ) from None
        # OpenCV's worker threads cost more than they give on a 64 × 96 image: one thread (decisions.md)
        cv2.setNumThreads(1)
        _CV2 = cv2
    return _CV2


def check_image(image) -> np.ndarray:
    """``image`` as a 2-D ``uint8`` array; a one-line ``ValueError`` naming what it got otherwise."""
    if not isinstance(image, np.ndarray):
        raise ValueError(f"image must be a numpy array of uint8, got {type(image).__name__}")
    if image.ndim == 3 and image.shape[0] == 1:  # the environment's (1, H, W) observation
        image = image[0]
    if image.ndim != 2 or min(image.shape) < MIN_SIDE:
        raise ValueError(
            f"image must be a grey image of shape (H, W) with sides ≥ {MIN_SIDE}, got shape {image.shape}"
        )
    if image.dtype != np.uint8:
        raise ValueError(f"image must have dtype uint8, got {image.dtype}")
    return image


def detect_pipe(
    image: np.ndarray,
    half_width: float = 1.0,
    depth: float = 3.0,
    pipe_diameter: float = 0.25,
    min_confidence: float = 0.3,
    previous: Detection | None = None,
) -> Detection:
    """Find the pipe in a grey image of the footprint ``x ∈ [−half_width, half_width]``, ``y ∈ [0, depth]``.

    Args:
        image: ``uint8`` array of shape (H, W) (or (1, H, W)); row 0 is the far edge y = depth,
            column 0 the port edge x = −half_width.
        half_width: the footprint's lateral half-width (m).
        depth: the footprint's forward extent (m).
        pipe_diameter: the pipe's diameter (m); edge pairs from 0.45 to 1.4 of it are accepted.
        min_confidence: detections below this confidence count as not found.
        previous: the previous frame's detection, when the images come in a sequence: a pipe found
            in both has its ends ordered the previous one's way (:func:`same_way`).

    Returns:
        A :class:`Detection`. A blank, saturated or pure-noise image gives ``found=False``.
    """
    img = check_image(image)
    cv2 = require_cv2()
    h, w = img.shape
    if float(cv2.meanStdDev(img)[1][0, 0]) < 2.0:  # blank or saturated: no edges to find
        return NOT_FOUND
    smooth = cv2.GaussianBlur(img, (5, 5), 1.0)
    # thresholds from the image's own gradients: their mean is the texture's and the noise's (the
    # pipe's edges are a few percent of the pixels); an edge must stand out of it
    high = max(EDGE_FACTOR * SOBEL_GAIN * gradient_level(smooth), MIN_EDGE)
    edges = cv2.Canny(smooth, 0.5 * high, high, L2gradient=True)
    short = min(h, w)
    segs = cv2.HoughLinesP(
        edges, 1.0, math.pi / 180.0, threshold=max(8, short // 8), minLineLength=short / 8.0, maxLineGap=6
    )
    if segs is None:
        return NOT_FOUND
    segs = np.asarray(segs, dtype=np.float64).reshape(-1, 4)  # (N, 1, 4) in OpenCV 4, (N, 4) in 5
    found, x1, y1, x2, y_near, confidence = centre_line(
        segs, edges, half_width, depth, pipe_diameter, min_confidence
    )
    det = Detection(bool(found), x1, y1, x2, y_near, confidence)
    if previous is None or not previous.found or not det.found:
        return det
    return same_way(det, previous)


def same_way(det: Detection, previous: Detection) -> Detection:
    """``det`` with its ends swapped if its near-to-far direction opposes ``previous``'s.

    Which end is the near one (the one the pipe comes from) is ambiguous in one image where the
    pipe crosses the view; between two frames the pipe's direction in view turns little.
    """
    dot = (det.x1 - det.x2) * (previous.x1 - previous.x2) + (det.y1 - det.y_near) * (
        previous.y1 - previous.y_near
    )
    if dot >= 0.0:
        return det
    return det._replace(x1=det.x2, y1=det.y_near, x2=det.x1, y_near=det.y1)


@njit(cache=True)
def gradient_level(img):
    """Mean gradient magnitude of a grey image (central differences, grey levels per pixel)."""
    h, w = img.shape
    total = 0.0
    for r in range(1, h - 1):
        for c in range(1, w - 1):
            gx = 0.5 * (float(img[r, c + 1]) - float(img[r, c - 1]))
            gy = 0.5 * (float(img[r + 1, c]) - float(img[r - 1, c]))
            total += math.sqrt(gx * gx + gy * gy)
    return total / ((h - 2) * (w - 2))


@njit(cache=True)
def centre_line(segs, edges, half_width, depth, diameter, min_confidence):
    """From Hough segments (pixels ``x0, y0, x1, y1``) and the edge image to the pipe's centre line.

    Returns ``(found, x1, y1, x2, y_near, confidence)`` in camera metres (see :func:`detect_pipe`).
    The strongest straight leg is found first (:func:`leg`); a pipe that bends or curves in view
    goes on beyond it, so both ends are then followed along the pipe's two edges to the ends of the
    visible piece (:func:`~pipefollow.perception.follow.extend_ends`), as the exact camera's
    observation spans the visible piece from its near to its far end.
    """
    found, ends, confidence, sep = leg(segs, edges, half_width, depth, diameter, min_confidence)
    if not found:
        return False, 0.0, 0.0, 0.0, 0.0, confidence
    extend_ends(ends, edges, 0.5 * sep, half_width, depth, EXTEND)
    xa, ya, xb, yb = ends[0, 0], ends[0, 1], ends[1, 0], ends[1, 1]
    # the near end is the one nearer the AUV (the footprint's origin): the pipe comes from behind
    # it, also when it runs across the view after a turn
    if xa * xa + ya * ya > xb * xb + yb * yb:
        xa, ya, xb, yb = xb, yb, xa, ya
    x1 = min(max(xb, -half_width), half_width)
    y1 = min(max(yb, 0.0), depth)
    x2 = min(max(xa, -half_width), half_width)
    y_near = min(max(ya, 0.0), depth)
    return True, x1, y1, x2, y_near, confidence


@njit(cache=True)
def leg(segs, edges, half_width, depth, diameter, min_confidence):
    """The strongest straight piece of pipe among the Hough segments.

    Returns ``(found, ends, confidence, separation)``: the centre line's two ends inside the
    footprint (a 2 × 2 array, unordered) and the distance between the two fitted edges (m).
    """
    nothing = np.zeros((2, 2))
    h, w = edges.shape
    sx, sy = 2.0 * half_width / w, depth / h  # metres per column, per row
    m = segs.shape[0]
    ax = -half_width + (segs[:, 0] + 0.5) * sx
    ay = depth - (segs[:, 1] + 0.5) * sy
    bx = -half_width + (segs[:, 2] + 0.5) * sx
    by = depth - (segs[:, 3] + 0.5) * sy
    length = np.sqrt((bx - ax) ** 2 + (by - ay) ** 2)
    theta = np.empty(m)
    for i in range(m):
        theta[i] = math.atan2(by[i] - ay[i], bx[i] - ax[i]) % math.pi
    # the dominant direction: length-weighted histogram of 5° bins, circularly smoothed
    bins = 36
    hist = np.zeros(bins)
    for i in range(m):
        hist[int(theta[i] / math.pi * bins) % bins] += length[i]
    best_bin, best_val = 0, -1.0
    for b in range(bins):
        v = hist[b] + 0.5 * (hist[(b - 1) % bins] + hist[(b + 1) % bins])
        if v > best_val:
            best_bin, best_val = b, v
    peak = (best_bin + 0.5) * math.pi / bins
    keep = np.zeros(m, dtype=np.bool_)
    s2, c2 = 0.0, 0.0  # doubled angles average a direction modulo π
    for i in range(m):
        diff = abs((theta[i] - peak + 0.5 * math.pi) % math.pi - 0.5 * math.pi)
        if diff < math.radians(12.0):
            keep[i] = True
            s2 += length[i] * math.sin(2.0 * theta[i])
            c2 += length[i] * math.cos(2.0 * theta[i])
    idx = np.nonzero(keep)[0]
    k = idx.size
    if k < 2:
        return False, nothing, 0.0, 0.0
    dirn = 0.5 * math.atan2(s2, c2)
    dx, dy = math.cos(dirn), math.sin(dirn)
    nx, ny = -dy, dx
    rho = np.empty(k)
    wk = np.empty(k)
    for j in range(k):
        i = idx[j]
        rho[j] = 0.5 * (ax[i] + bx[i]) * nx + 0.5 * (ay[i] + by[i]) * ny
        wk[j] = length[i]
    # edges: groups of segments whose offsets across lie within 0.3 diameters (single linkage)
    order = np.argsort(rho)
    group = np.empty(k, dtype=np.int64)
    g = 0
    group[order[0]] = 0
    for j in range(1, k):
        if rho[order[j]] - rho[order[j - 1]] >= 0.3 * diameter:
            g += 1
        group[order[j]] = g
    n_groups = g + 1
    g_rho = np.zeros(n_groups)
    g_len = np.zeros(n_groups)
    for j in range(k):
        g_rho[group[j]] += wk[j] * rho[j]
        g_len[group[j]] += wk[j]
    g_rho /= g_len
    # the pair 0.45–1.4 diameters apart whose weaker edge has the most segment length
    # (an edge cut short by the border still counts: the pair's score is its total length, and
    # the weaker edge must reach MIN_EDGE_SHARE of the stronger)
    pa, pb, score = -1, -1, 0.0
    for i in range(n_groups):
        for j in range(i + 1, n_groups):
            sep = g_rho[j] - g_rho[i]
            total = g_len[i] + g_len[j]
            if (
                0.45 * diameter <= sep <= 1.4 * diameter
                and min(g_len[i], g_len[j]) >= MIN_EDGE_SHARE * max(g_len[i], g_len[j])
                and total > score
            ):
                pa, pb, score = i, j, total
    if pa < 0:
        return False, nothing, 0.0, 0.0
    t_lo, t_hi = math.inf, -math.inf
    for j in range(k):
        if group[j] == pa or group[j] == pb:
            i = idx[j]
            ta = ax[i] * dx + ay[i] * dy
            tb = bx[i] * dx + by[i] * dy
            t_lo, t_hi = min(t_lo, ta, tb), max(t_hi, ta, tb)
    extent = t_hi - t_lo
    sep = g_rho[pb] - g_rho[pa]
    confidence = min(1.0, 0.5 * score / extent) * math.exp(-(((sep - diameter) / diameter) ** 2))
    if confidence < min_confidence or score < MIN_SUPPORT * max(depth, 2.0 * half_width):
        return False, nothing, confidence, 0.0
    # refine each edge: least squares of the offset across against the position along, on its
    # edge pixels near it; twice, the second time in a narrower band around the first fit (the
    # Hough direction is only good to a degree or two)
    fit = np.empty((2, 2))  # offset at t_lo and slope, per edge
    fit[0, 0], fit[1, 0], fit[0, 1], fit[1, 1] = g_rho[pa], g_rho[pb], 0.0, 0.0
    u_lo, u_hi = 0.0, extent
    for tol in (2.5 * max(sx, sy), 1.5 * max(sx, sy)):
        sums = np.zeros((2, 5))  # n, Σu, Σs, Σuu, Σus per edge
        reach = 0.0 if tol > 2.0 * max(sx, sy) else EXTEND  # the second pass may lengthen the line
        u_lo, u_hi = 0.0, extent
        for r in range(h):
            py = depth - (r + 0.5) * sy
            for c in range(w):
                if edges[r, c] == 0:
                    continue
                px = -half_width + (c + 0.5) * sx
                u = px * dx + py * dy - t_lo
                if u < -reach or u > extent + reach:
                    continue
                ps = px * nx + py * ny
                for e in range(2):
                    if abs(ps - fit[e, 0] - fit[e, 1] * u) < tol:
                        u_lo, u_hi = min(u_lo, u), max(u_hi, u)
                        sums[e, 0] += 1.0
                        sums[e, 1] += u
                        sums[e, 2] += ps
                        sums[e, 3] += u * u
                        sums[e, 4] += u * ps
        for e in range(2):
            n_e, su, ss, suu, sus = sums[e, 0], sums[e, 1], sums[e, 2], sums[e, 3], sums[e, 4]
            var = n_e * suu - su * su
            if n_e >= 6 and math.sqrt(max(var, 0.0)) / n_e > 0.05 * extent:
                fit[e, 1] = (n_e * sus - su * ss) / var
                fit[e, 0] = (ss - fit[e, 1] * su) / n_e
    icpt = 0.5 * (fit[0, 0] + fit[1, 0])
    slope = 0.5 * (fit[0, 1] + fit[1, 1])
    ends = np.empty((2, 2))
    for e in range(2):
        u = u_lo if e == 0 else u_hi
        s = icpt + slope * u
        t = t_lo + u
        ends[e, 0], ends[e, 1] = t * dx + s * nx, t * dy + s * ny
    snap_to_border(ends, half_width, depth, 4.0 * max(sx, sy))
    # the centre line's part inside the footprint (the wider edges reach beyond its exit)
    ax0, ay0, bx0, by0 = ends[0, 0], ends[0, 1], ends[1, 0], ends[1, 1]
    t0, t1 = clip_segment(ax0, ay0, bx0, by0, -half_width, half_width, 0.0, depth)
    if t0 > t1:
        return False, nothing, confidence, 0.0
    out = np.empty((2, 2))
    out[0, 0], out[0, 1] = ax0 + t0 * (bx0 - ax0), ay0 + t0 * (by0 - ay0)
    out[1, 0], out[1, 1] = ax0 + t1 * (bx0 - ax0), ay0 + t1 * (by0 - ay0)
    sep = abs(fit[1, 0] - fit[0, 0] + (fit[1, 1] - fit[0, 1]) * 0.5 * extent)
    return True, out, confidence, sep


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
