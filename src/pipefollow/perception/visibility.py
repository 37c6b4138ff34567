"""How much a camera frame shows: its contrast over its noise, measured from the image alone.

A vehicle does not know the water's turbidity; it sees what turbidity does to its images. The
direct signal of the seabed and the pipe falls as ``exp(−c·L)`` along the light's path while the
sensor's noise, the veil's grain and the marine snow stay or grow, so the ratio of the image's
coarse structure to its pixel noise falls with the water's clarity.

:func:`contrast_to_noise` is that ratio for one grey frame:

* the noise: Immerkær's estimate of an image's Gaussian noise (J. Immerkær, "Fast noise variance
  estimation", Computer Vision and Image Understanding 64(2), 300–302, 1996): the mean absolute
  response to the mask ``[[1, −2, 1], [−2, 4, −2], [1, −2, 1]]`` (the difference of two Laplacians,
  which cancels the image's smooth structure to second order) times ``√(π/2) / 6``;
* the contrast: the standard deviation of the image's ``block × block`` block means (8 × 8 pixels,
  25 cm on the seabed by default), the structure a detector of a 0.25 m pipe works on.

Compiled (no ``fastmath``): ≈ 15 µs for a 64 × 96 frame (33 µs with the sums in floats, measured in
one process).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

BLOCK = 8  # pixels: the side of the blocks whose means make the contrast
# a frame's contrast over its noise below which the fused sensor does not search it for the pipe:
# clear water's frames lie at 3.2–6.8, moderate water's (0.2/m) at 1.7–3.2 and turbid water's
# (0.25/m) at 1.3–2.1 (1st–99th percentiles; docs/decisions.md, "Murky frames left to the sonar")
MIN_CONTRAST = 2.15
# ... and below which the pipe tracker does not carry a short piece at the view's edge longer: the
# detector's misses there are not of short pieces (turbid water's median frame, moderate water's
# 1st percentile 1.7; docs/decisions.md, "Murky frames left to the sonar")
EDGE_CONTRAST = 1.9


@njit(cache=True)
def noise_sd(image) -> float:
    """Immerkær's estimate of the Gaussian noise's standard deviation in a grey image (module docstring).

    A ``uint8`` frame's mask responses and their sum are integers (exact: the number summing them
    as floats gives, in a quarter of the time); a float image's are floats.
    """
    h, w = image.shape
    total = 0
    for r in range(1, h - 1):
        for c in range(1, w - 1):
            v = (
                image[r - 1, c - 1] - 2 * image[r - 1, c] + image[r - 1, c + 1]
                - 2 * image[r, c - 1] + 4 * image[r, c] - 2 * image[r, c + 1]
                + image[r + 1, c - 1] - 2 * image[r + 1, c] + image[r + 1, c + 1]
            )  # fmt: skip
            total += abs(v)
    return math.sqrt(0.5 * math.pi) / 6.0 * total / ((w - 2) * (h - 2))


@njit(cache=True)
def block_contrast(image, block) -> float:
    """The standard deviation of the means of the image's whole ``block × block`` blocks."""
    h, w = image.shape
    nr, nc = h // block, w // block
    means = np.empty(nr * nc)
    k = 0
    for i in range(nr):
        for j in range(nc):
            s = 0  # a uint8 frame's sum an integer (exact)
            for r in range(i * block, (i + 1) * block):
                for c in range(j * block, (j + 1) * block):
                    s += image[r, c]
            means[k] = s / (block * block)
            k += 1
    return float(np.std(means))


def contrast_to_noise(image: np.ndarray, block: int = BLOCK) -> float:
    """The frame's coarse contrast over its pixel noise (module docstring); inf for a noise-free frame."""
    if image.ndim != 2 or image.shape[0] < max(3, block) or image.shape[1] < max(3, block):
        side = max(3, block)
        raise ValueError(f"a grey image of at least {side} × {side} pixels, got shape {image.shape}")
    noise = noise_sd(image)
    contrast = block_contrast(image, block)
    if noise == 0.0:
        return math.inf if contrast > 0.0 else 0.0
    return contrast / noise


def clear_enough(contrast: float) -> bool:
    """Whether the fused sensor searches a frame of this :func:`contrast_to_noise` for the pipe.

    At least :data:`MIN_CONTRAST`: in murkier frames the detector's finds are mostly wrong ones
    that the tracker takes (docs/decisions.md, the fused sensor), so the sonar alone feeds the track.
    """
    return contrast >= MIN_CONTRAST


__all__ = [
    "BLOCK", "EDGE_CONTRAST", "MIN_CONTRAST", "block_contrast", "clear_enough", "contrast_to_noise",
    "noise_sd",
]  # fmt: skip
