"""Pixels ↔ camera metres: the one place the camera image's pixel conventions are written.

The image of ``rows × columns`` pixels covers the footprint ``x ∈ [−half_width, half_width]``,
``y ∈ [0, depth]``: column 0 starts at x = −half_width (port), row 0 at the far edge y = depth,
the last row ends at y = 0. Pixel ``(r, c)`` has its centre at

    x = −half_width + (c + ½)·dx,   y = depth − (r + ½)·dy,   dx = 2·half_width / columns, dy = depth / rows

(by default ``x = −1 + (c + ½)·2/64``, ``y = 3 − (r + ½)·3/96``: square pixels of 3.125 cm).
:func:`column_x` and :func:`row_y` give a pixel's centre; :func:`column_at` and :func:`row_at`
are their inverses, a point's continuous pixel coordinates (pixel ``c`` spans ``[c, c + 1)``, so
``floor`` gives the pixel a point lies in).

The functions are inlined into the compiled code that calls them (``inline="always"``), so they
compile to the same arithmetic as the expressions written out, under the caller's own
floating-point flags. They also take NumPy arrays.
"""

from __future__ import annotations

from typing import NamedTuple

from numba import njit


class PixelGrid(NamedTuple):
    """Where an image's pixels lie in the footprint (made by :func:`pixel_grid`)."""

    half_width: float  # the footprint's lateral half-width (m): column 0 starts at x = −half_width
    depth: float  # the footprint's forward extent (m): row 0 starts at y = depth
    dx: float  # a column's width (m): 2·half_width / columns
    dy: float  # a row's height (m): depth / rows


@njit(cache=True, inline="always")
def pixel_grid(half_width, depth, rows, columns):
    """The :class:`PixelGrid` of a ``rows × columns`` image of the footprint."""
    return PixelGrid(half_width, depth, 2.0 * half_width / columns, depth / rows)


@njit(cache=True, inline="always")
def pixel_pitch(grid):
    """The larger side of a pixel (m): the unit of the detector's tolerances."""
    return max(grid.dx, grid.dy)


@njit(cache=True, inline="always")
def column_x(c, grid):
    """The lateral position x (m) of column ``c``'s centre."""
    return -grid.half_width + (c + 0.5) * grid.dx


@njit(cache=True, inline="always")
def row_y(r, grid):
    """The forward position y (m) of row ``r``'s centre."""
    return grid.depth - (r + 0.5) * grid.dy


@njit(cache=True, inline="always")
def column_at(x, grid):
    """The continuous column coordinate of lateral position ``x`` (m): column ``c`` spans ``[c, c + 1)``."""
    return (x + grid.half_width) / grid.dx


@njit(cache=True, inline="always")
def row_at(y, grid):
    """The continuous row coordinate of forward position ``y`` (m): row ``r`` spans ``[r, r + 1)``."""
    return (grid.depth - y) / grid.dy
