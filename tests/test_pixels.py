"""The pixel ↔ camera-metre conventions of perception.pixels, and the least-squares edge fit."""

from __future__ import annotations

import numpy as np
import pytest

from pipefollow.perception.follow import add_edge_pixel, fit_edge
from pipefollow.perception.image import pixel_centres
from pipefollow.perception.pixels import column_at, column_x, pixel_grid, pixel_pitch, row_at, row_y
from pipefollow.perception.water import Water
from pipefollow.sim.camera import CameraParams

GRID = pixel_grid(1.0, 3.0, 96, 64)  # the default image: 64 columns over 2 m, 96 rows over 3 m


def test_the_default_grid_has_square_pixels_of_3_125_cm():
    assert (GRID.dx, GRID.dy) == (0.03125, 0.03125)
    assert pixel_pitch(GRID) == 0.03125
    assert pixel_pitch(pixel_grid(1.0, 3.0, 60, 64)) == 0.05  # the larger side


def test_pixel_centres_are_the_documented_ones():
    # column 0 starts at x = −1 (port), row 0 at the far edge y = 3
    assert column_x(0, GRID) == -1.0 + 0.5 * 2.0 / 64 and column_x(63, GRID) == 1.0 - 0.5 * 2.0 / 64
    assert row_y(0, GRID) == 3.0 - 0.5 * 3.0 / 96 and row_y(95, GRID) == 0.5 * 3.0 / 96


@pytest.mark.parametrize("camera", [CameraParams(), CameraParams(1.3, 2.7)])
def test_a_pixel_centre_lies_half_a_pixel_into_its_pixel(camera):
    grid = pixel_grid(camera.half_width, camera.depth, 112, 80)
    cols, rows = np.arange(80), np.arange(112)
    assert np.allclose(column_at(column_x(cols, grid), grid), cols + 0.5, atol=1e-9)
    assert np.allclose(row_at(row_y(rows, grid), grid), rows + 0.5, atol=1e-9)
    # the footprint's borders are the grid's outer pixel edges
    assert column_at(-camera.half_width, grid) == 0.0 and row_at(camera.depth, grid) == 0.0
    assert column_at(camera.half_width, grid) == pytest.approx(80.0)
    assert row_at(0.0, grid) == pytest.approx(112.0)


def test_pixel_centres_are_the_grids():
    water, camera = Water(width=80, height=112), CameraParams(1.3, 2.7)
    xs, ys = pixel_centres(water, camera)
    grid = pixel_grid(1.3, 2.7, 112, 80)
    assert np.array_equal(xs, [column_x(c, grid) for c in range(80)])
    assert np.array_equal(ys, [row_y(r, grid) for r in range(112)])


def test_the_edge_fit_recovers_a_line_and_keeps_a_short_cluster_flat():
    sums = np.zeros((2, 5))
    for u in np.linspace(0.0, 2.0, 21):
        add_edge_pixel(sums, 1, u, 0.3 + 0.05 * u)
    icpt, slope, sloped = fit_edge(sums, 1, 0.1)
    assert sloped and icpt == pytest.approx(0.3) and slope == pytest.approx(0.05)
    # pixels spread along less than min_spread: no slope, the mean offset
    icpt, slope, sloped = fit_edge(sums, 1, 1.0)
    assert not sloped and slope == 0.0 and icpt == pytest.approx(0.3 + 0.05 * 1.0)
    assert np.all(sums[0] == 0.0)  # the other edge's sums untouched
