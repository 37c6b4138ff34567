"""A classical pipe detector on grey camera images, with OpenCV.

The steps of the underwater pipeline-tracking literature: Canny edges, the probabilistic Hough
transform, the dominant direction of the line segments (a length-weighted angle histogram), the
pipe's two edges paired into a centre line (two parallel groups of segments about a pipe diameter
apart), each edge refined by a least-squares fit to its edge pixels, then both ends followed
along the two edges beyond the straight leg, through bends and curves. The result is the paper's
observation ``(x1, y1, x2)`` in camera metres by the pixel conventions of
:mod:`pipefollow.perception.pixels` (also ``y_near``), plus a confidence.

It works on any grey ``uint8`` image of the footprint, not only on this package's renders, and on
other sizes and footprints when told the footprint. OpenCV is the optional extra ``vision``
(``pip install "pipefollow[vision]"``); it is imported on the first detection.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.follow import add_edge_pixel, extend_ends, fit_edge
from pipefollow.perception.pixels import column_x, pixel_grid, pixel_pitch, row_y
from pipefollow.sim.camera import clip_segment

MIN_SIDE = 16  # smallest image side (pixels) the detector accepts

# The thresholds, each with its unit and what it guards against; docs/decisions.md ("edge
# thresholds", "Hough", "pairing", "refinement") has the measurements behind them.
# -- the edge image and the Hough segments (detect_pipe)
BLANK_SD = 2.0  # grey levels: below this s.d. the image is blank or saturated (no edges: skip the work)
SMOOTH_KERNEL = 5  # pixels: the Gaussian pre-blur's kernel side ...
SMOOTH_SIGMA = 1.0  # ... and σ (pixels): single-pixel noise and snow specks would give edges of their own
EDGE_FACTOR = 3.2  # Canny's high threshold in mean gradients (texture and noise): the pipe's stand 4–9× above
MIN_EDGE = 24.0  # ... and at least this (Canny's 3×3 Sobel units): a flat image's noise is no edge
SOBEL_GAIN = 8.0  # a 3×3 Sobel gives 8× the central-difference gradient
CANNY_LOW = 0.5  # Canny's low threshold, a share of the high one: weak pixels continue a strong edge only
HOUGH_RHO_PX = 1.0  # pixels: the Hough accumulator's offset step ...
HOUGH_THETA = math.pi / 180.0  # ... and angle step (rad), 1°: at 2° a staircase edge often gave no segment
HOUGH_MIN_VOTES = 8  # edge pixels a Hough line needs at least (tiny images), ...
HOUGH_SIDE_SHARE = 8  # ... and 1/this of the shorter side in votes and length: texture makes short segments
HOUGH_MAX_GAP = 6  # pixels a segment bridges: at 3 an edge cut by the border broke into unpairable pieces
# -- the strongest straight leg among the segments (leg)
ANGLE_BINS = 36  # bins of the direction histogram over 180° (5° each): finer bins split one edge's segments
NEIGHBOUR_WEIGHT = 0.5  # the histogram's circular smoothing: a direction on a bin's border counts in both
MAX_MISALIGNMENT = math.radians(12.0)  # rad from the peak: the pipe's segments; wider takes in a bend's leg
EDGE_LINK = 0.3  # diameters: segments closer than this across are one edge (a staircase edge's pieces)
MIN_PAIR_SEPARATION = 0.45  # diameters: the two edges at least this far apart and ... (texture lines are
MAX_PAIR_SEPARATION = 1.4  # ... at most this far: a pipe's edges are parallel, a diameter apart; ... not)
MIN_EDGE_SHARE = 0.1  # weaker edge's length / stronger's, ≥ this: one line is no pipe; one cut at a turn is
MIN_SUPPORT = 0.25  # the two edges' length, ≥ this share of the footprint's longer side (not a texture patch)
FIT_BANDS_PX = (2.5, 1.5)  # pixels: the refit's bands, around the Hough line (good to 1°), then the first fit
MIN_FIT_PIXELS = 6  # edge pixels an edge's refit needs; with fewer the Hough line stays (noise pixels)
MIN_FIT_SPREAD = 0.05  # share of the extent the pixels must spread along (s.d.) to tilt the line (a blob)
EXTEND = 0.4  # m: how far edge pixels may lengthen the Hough segments' extent (and the walk starts back)
SNAP_PX = 4.0  # pixels: an end this near the border goes onto it (Canny loses the last pixels at the border)
HOOK_MIN_TURN = math.radians(20.0)  # rad: a second leg's segments turn at least this from the first leg
HOOK_JOIN = 0.45  # m: a second leg starting this near an end stopped inside the view continues the pipe
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
    if image.ndim == 3 and image.shape[-1] == 1:  # the environment's (H, W, 1) observation
        image = image[..., 0]
    elif image.ndim == 3 and image.shape[0] == 1:  # channel first, as torch takes it
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
        image: ``uint8`` array of shape (H, W) (or the environment's (H, W, 1), or (1, H, W)); row 0
            is the far edge y = depth,
            column 0 the port edge x = −half_width.
        half_width: the footprint's lateral half-width (m).
        depth: the footprint's forward extent (m).
        pipe_diameter: the pipe's diameter (m); edge pairs from :data:`MIN_PAIR_SEPARATION` to
            :data:`MAX_PAIR_SEPARATION` of it apart are accepted.
        min_confidence: detections below this confidence count as not found.
        previous: the previous frame's detection, when the images come in a sequence: a pipe found
            in both has its ends ordered the previous one's way (:func:`same_way`).

    Returns:
        A :class:`Detection`. A blank, saturated or pure-noise image gives ``found=False``.
    """
    img = check_image(image)
    cv2 = require_cv2()
    h, w = img.shape
    if float(cv2.meanStdDev(img)[1][0, 0]) < BLANK_SD:  # blank or saturated: no edges to find
        return NOT_FOUND
    smooth = cv2.GaussianBlur(img, (SMOOTH_KERNEL, SMOOTH_KERNEL), SMOOTH_SIGMA)
    # thresholds from the image's own gradients: their mean is the texture's and the noise's (the
    # pipe's edges are a few percent of the pixels); an edge must stand out of it
    high = max(EDGE_FACTOR * SOBEL_GAIN * gradient_level(smooth), MIN_EDGE)
    edges = cv2.Canny(smooth, CANNY_LOW * high, high, L2gradient=True)
    short = min(h, w)
    segs = cv2.HoughLinesP(
        edges,
        HOUGH_RHO_PX,
        HOUGH_THETA,
        threshold=max(HOUGH_MIN_VOTES, short // HOUGH_SIDE_SHARE),
        minLineLength=short / HOUGH_SIDE_SHARE,
        maxLineGap=HOUGH_MAX_GAP,
    )
    if segs is None:
        return NOT_FOUND
    segs = np.asarray(segs, dtype=np.float64).reshape(-1, 4)  # (N, 1, 4) in OpenCV 4, (N, 4) in 5
    det = centre_line(segs, edges, half_width, depth, pipe_diameter, min_confidence)
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

    Returns a :class:`Detection` in camera metres (see :func:`detect_pipe`). The strongest straight
    leg is found first (:func:`leg`); a pipe that bends or curves in view goes on beyond it, so
    both ends are then followed along the pipe's two edges to the ends of the visible piece
    (:func:`~pipefollow.perception.follow.extend_ends`), as the exact camera's observation spans
    the visible piece from its near to its far end.
    """
    found, ends, confidence, sep = leg(segs, edges, half_width, depth, diameter, min_confidence)
    if not found:
        return Detection(False, 0.0, 0.0, 0.0, 0.0, confidence)
    direction = math.atan2(ends[1, 1] - ends[0, 1], ends[1, 0] - ends[0, 0])
    extend_ends(ends, edges, 0.5 * sep, half_width, depth, EXTEND)
    join_hook(ends, segs, edges, direction, half_width, depth, diameter, min_confidence)
    xa, ya, xb, yb = ends[0, 0], ends[0, 1], ends[1, 0], ends[1, 1]
    # the near end is the one nearer the AUV (the footprint's origin): the pipe comes from behind
    # it, also when it runs across the view after a turn
    if xa * xa + ya * ya > xb * xb + yb * yb:
        xa, ya, xb, yb = xb, yb, xa, ya
    x1 = min(max(xb, -half_width), half_width)
    y1 = min(max(yb, 0.0), depth)
    x2 = min(max(xa, -half_width), half_width)
    y_near = min(max(ya, 0.0), depth)
    return Detection(True, x1, y1, x2, y_near, confidence)


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


class Leg(NamedTuple):
    """What :func:`leg` found: the strongest straight piece of pipe."""

    found: bool
    ends: np.ndarray  # 2 × 2: the centre line's two ends inside the footprint (rows x, y; unordered)
    confidence: float  # in [0, 1] (:func:`pair_confidence`)
    separation: float  # distance between the two fitted edges (m)


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
    rho = np.empty(k)  # each segment's offset across, at its midpoint
    wk = np.empty(k)
    for j in range(k):
        i = idx[j]
        rho[j] = 0.5 * (sg.ax[i] + sg.bx[i]) * nx + 0.5 * (sg.ay[i] + sg.by[i]) * ny
        wk[j] = sg.length[i]
    group, g_rho, g_len = edge_groups(rho, wk, diameter)
    pa, pb, score = edge_pair(g_rho, g_len, diameter)
    if pa < 0:
        return Leg(False, nothing, 0.0, 0.0)
    # the pair's extent along the leg: from the first to the last end of its segments
    t_lo, t_hi = math.inf, -math.inf
    for j in range(k):
        if group[j] == pa or group[j] == pb:
            i = idx[j]
            ta = sg.ax[i] * dx + sg.ay[i] * dy
            tb = sg.bx[i] * dx + sg.by[i] * dy
            t_lo, t_hi = min(t_lo, ta, tb), max(t_hi, ta, tb)
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
    segment length; of those, the pair with the most segment length wins (``score``, m). An edge
    cut short by the border still counts.
    """
    pa, pb, score = -1, -1, 0.0
    for i in range(g_rho.size):
        for j in range(i + 1, g_rho.size):
            sep = g_rho[j] - g_rho[i]
            total = g_len[i] + g_len[j]
            if (
                MIN_PAIR_SEPARATION * diameter <= sep <= MAX_PAIR_SEPARATION * diameter
                and min(g_len[i], g_len[j]) >= MIN_EDGE_SHARE * max(g_len[i], g_len[j])
                and total > score
            ):
                pa, pb, score = i, j, total
    return pa, pb, score


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
