"""A camera frame's contrast over its noise (pipefollow.perception.visibility)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pipefollow.perception.visibility import block_contrast, contrast_to_noise, noise_sd


def test_the_noise_estimate_is_the_gaussian_noise_s_standard_deviation():
    # Immerkær's estimator is unbiased for Gaussian noise on a smooth image: a plane (which the
    # mask cancels exactly) plus noise of s.d. 5 reads 5 within the estimate's sampling error
    rng = np.random.default_rng(1)
    r, c = np.mgrid[0:300, 0:300]
    plane = 40.0 + 0.3 * r + 0.2 * c
    assert noise_sd(plane) == pytest.approx(0.0, abs=1e-9)
    assert noise_sd(plane + 5.0 * rng.standard_normal(plane.shape)) == pytest.approx(5.0, rel=0.03)


def test_the_block_contrast_is_the_standard_deviation_of_the_block_means():
    # two halves of 0 and 100 grey levels: block means 0 and 100 in equal numbers, s.d. 50
    image = np.zeros((16, 32), dtype=np.uint8)
    image[:, 16:] = 100
    assert block_contrast(image, 8) == pytest.approx(50.0)
    # a block straddling the edge averages it: blocks of 0, 50 and 100 (one each per row of blocks)
    shifted = np.zeros((8, 24), dtype=np.uint8)
    shifted[:, 12:] = 100
    assert block_contrast(shifted, 8) == pytest.approx(np.std([0.0, 50.0, 100.0]))


def test_pure_noise_has_the_contrast_of_its_block_means():
    # 8 × 8 block means of white noise of s.d. σ have s.d. σ / 8: the ratio is 1/8
    rng = np.random.default_rng(2)
    image = 100.0 + 6.0 * rng.standard_normal((400, 400))
    assert contrast_to_noise(image) == pytest.approx(1.0 / 8.0, rel=0.08)
    assert contrast_to_noise(np.full((16, 16), 7.0)) == 0.0
    halves = np.zeros((16, 16))
    halves[:, 8:] = 1.0  # a step constant down the columns: the mask (an outer product of
    assert noise_sd(halves) == 0.0  # [1, −2, 1] with itself) cancels it, a noise-free frame
    assert contrast_to_noise(halves) == math.inf


def test_the_frame_must_be_a_grey_image_of_a_block_at_least():
    with pytest.raises(ValueError, match="grey image of at least 8 × 8 pixels"):
        contrast_to_noise(np.zeros((4, 40)))
    with pytest.raises(ValueError, match="grey image"):
        contrast_to_noise(np.zeros((16, 16, 3)))
