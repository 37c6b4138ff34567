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

This module holds the public face (:func:`detect_pipe`, :class:`Detection`, the image's checks)
and the edge image; the edges' stages from the Hough segments to the fitted pair are in
:mod:`pipefollow.perception.detector_edges`, the legs (a straight leg's ends, the border, the
second leg after a sharp corner) in :mod:`pipefollow.perception.detector_legs`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.detector_border import BORDER_HOUGH_SHARE, border_piece
from pipefollow.perception.detector_edges import EXTEND
from pipefollow.perception.detector_legs import join_hook, leg
from pipefollow.perception.follow import extend_ends

MIN_SIDE = 16  # smallest image side (pixels) the detector accepts

# The thresholds, each with its unit and what it guards against; docs/decisions.md ("edge
# thresholds", "Hough") has the measurements behind them; the legs' thresholds are in
# detector_edges and detector_legs.
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
    border_pieces: bool = False,
) -> Detection:
    """Find the pipe in a grey image of the footprint ``x ∈ [−half_width, half_width]``, ``y ∈ [0, depth]``.

    Args:
        image: ``uint8`` array of shape (H, W) (or the environment's (H, W, 1), or (1, H, W)); row 0
            is the far edge y = depth,
            column 0 the port edge x = −half_width.
        half_width: the footprint's lateral half-width (m).
        depth: the footprint's forward extent (m).
        pipe_diameter: the pipe's diameter (m); edge pairs from
            :data:`~pipefollow.perception.detector_edges.MIN_PAIR_SEPARATION` to
            :data:`~pipefollow.perception.detector_edges.MAX_PAIR_SEPARATION` of it apart are accepted.
        min_confidence: detections below this confidence count as not found.
        previous: the previous frame's detection, when the images come in a sequence: a pipe found
            in both has its ends ordered the previous one's way (:func:`same_way`).
        border_pieces: where nothing is found, look again for a short piece cut by the border
            (:func:`second_look`). For a tracker, which orders the ends itself: the piece's way is
            a guess (docs/decisions.md, "a short piece at the border").

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
    if border_pieces and not det.found:  # a second look: a short piece cut by the border
        det = second_look(smooth, edges, half_width, depth, pipe_diameter, min_confidence, det)
    if previous is None or not previous.found or not det.found:
        return det
    return same_way(det, previous)


def second_look(smooth, edges, half_width, depth, diameter, min_confidence, first: Detection) -> Detection:
    """A short piece at the border on shorter Hough segments (:mod:`~pipefollow.perception.detector_border`).

    ``first`` (the first look's miss) is returned when there is none.
    """
    cv2 = require_cv2()
    short = min(edges.shape)
    segs = cv2.HoughLinesP(
        edges,
        HOUGH_RHO_PX,
        HOUGH_THETA,
        threshold=max(HOUGH_MIN_VOTES // 2, short // BORDER_HOUGH_SHARE),
        minLineLength=short / BORDER_HOUGH_SHARE,
        maxLineGap=HOUGH_MAX_GAP,
    )
    if segs is None:
        return first
    segs = np.asarray(segs, dtype=np.float64).reshape(-1, 4)
    piece = border_piece(segs, edges, smooth, half_width, depth, diameter, min_confidence)
    if not piece.found:
        return first
    return as_detection(piece.ends, piece.confidence, half_width, depth)


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
    leg is found first (:func:`~pipefollow.perception.detector_legs.leg`); a pipe that bends or
    curves in view goes on beyond it, so both ends are then followed along the pipe's two edges to
    the ends of the visible piece (:func:`~pipefollow.perception.follow.extend_ends`), as the
    exact camera's observation spans the visible piece from its near to its far end.
    """
    found, ends, confidence, sep = leg(segs, edges, half_width, depth, diameter, min_confidence)
    if not found:
        return Detection(False, 0.0, 0.0, 0.0, 0.0, confidence)
    direction = math.atan2(ends[1, 1] - ends[0, 1], ends[1, 0] - ends[0, 0])
    extend_ends(ends, edges, 0.5 * sep, half_width, depth, EXTEND)
    join_hook(ends, segs, edges, direction, half_width, depth, diameter, min_confidence)
    return as_detection(ends, confidence, half_width, depth)


@njit(cache=True)
def as_detection(ends, confidence, half_width, depth):
    """The centre line's two ends (rows x, y) as a :class:`Detection`: near end first, in the footprint."""
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
