"""The downward camera's grey image of the footprint (a rendered seabed, pipe and water).

Pixel conventions, which tests and users rely on (written once, in
:mod:`pipefollow.perception.pixels`): the image covers the footprint ``x ∈ [−hw, hw]`` (columns,
column 0 at x = −hw, port) and ``y ∈ [0, depth]`` (rows, row 0 at the far edge y = depth, the
last row at y = 0). Pixel ``(r, c)`` has its centre at ``x = −hw + (c + ½)·2hw/W``,
``y = depth − (r + ½)·depth/H``; by default hw = 1 m, depth = 3 m, W × H = 64 × 96 (square pixels
of 3.125 cm), grey ``uint8``.

Contents, in the order they are made:

* the seabed: a seeded texture tile (:mod:`pipefollow.perception.textures`) fixed in the earth
  frame, so it moves through the image as the AUV moves;
* the pipe: a shaded cylinder of ``water.pipe_diameter`` around the pipeline's centre line
  (brightness ∝ 0.55 + 0.45·n_z, n_z the surface normal's vertical part); ``water.burial`` covers
  that share of its width with sand from its starboard edge (looking along the pipe); patches of
  marine growth (a second texture fixed along the pipe's arc length) cover ``water.growth`` of it;
* light and water: the vehicle's light falls off towards the edges (to ``1 − light_falloff`` at
  the corners); along the light's path ``L = 2·√(altitude² + x² + (y − depth/2)²)`` the direct
  signal is attenuated by ``exp(−c·L)`` and a veil ``V·(1 − exp(−c·L))`` rises (c =
  ``turbidity``); the camera's gain holds the image centre's mean level where it is in clear water;
* marine snow (Poisson count of bright specks), blur (the optics' σ plus forward scattering
  ``2·c`` pixels), Gaussian sensor noise.

All randomness comes from the ``numpy.random.Generator`` passed in.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pipefollow.perception.pixels import column_at, column_x, pixel_grid, row_at, row_y
from pipefollow.perception.textures import SEABED_ALBEDO, TILE_RES, Textures
from pipefollow.perception.water import CLEAR, Water
from pipefollow.sim.camera import PAPER_CAMERA, CameraParams

PIPE_ALBEDO = 0.78  # the pipe's coating
SAND_ALBEDO = 0.44  # sand over a buried pipe
GROWTH_ALBEDO = 0.22  # marine growth (dark)
VEIL = 0.6  # backscatter level relative to an albedo of 1
SCATTER_BLUR = 2.0  # forward-scattering blur σ per unit of turbidity (pixels per 1/m)
SNOW_LEVEL = (60.0, 140.0)  # grey levels a marine-snow speck adds (uniform range)
NOISE_BANK = 1 << 18  # standard normals a renderer draws once for its sensor noise


class FrameSettings(NamedTuple):
    """What every frame of a :class:`Renderer` shares: the footprint, the pipe and the optics."""

    half_width: float  # the footprint's lateral half-width (m)
    depth: float  # the footprint's forward extent (m)
    radius: float  # the pipe's radius (m)
    burial: float  # share of the pipe's width covered by sand, from its starboard edge
    growth: float  # share of the pipe's surface covered by marine growth
    blur: float  # σ of the Gaussian blur (pixels): the optics' and the forward scattering's
    noise: float  # sensor noise s.d. (grey levels)


class Buffers(NamedTuple):
    """A renderer's per-pixel working arrays (H × W, float32), reused frame after frame."""

    img: np.ndarray  # the grey levels being made
    tmp: np.ndarray  # the blur's first pass
    dist: np.ndarray  # distance to the pipe's centre line (m); inf far from the pipe
    across: np.ndarray  # signed offset across the pipe (m), positive to its starboard
    along: np.ndarray  # arc length along the pipe (m)


class Lighting(NamedTuple):
    """Per pixel (H × W, float32): grey level = ``gain``·albedo + ``veil`` (:func:`light_and_water`)."""

    gain: np.ndarray  # grey levels per unit of albedo: the light's fall-off and the water's attenuation
    veil: np.ndarray  # grey levels of backscatter


@njit(cache=True)
def pipe_segments(points, cum, x, y, psi, hw, depth, margin):
    """The pipeline's segments near the footprint, in camera coordinates.

    Returns a ``(k, 5)`` array of rows ``(ax, ay, bx, by, s_a)`` (ends a, b and a's arc length)
    for the segments whose bounding box comes within ``margin`` of the footprint.
    """
    n = points.shape[0] - 1
    out = np.empty((n, 5))
    k = 0
    cs, sn = math.cos(psi), math.sin(psi)
    dx, dy = points[0, 0] - x, points[0, 1] - y
    ax, ay = -sn * dx + cs * dy, cs * dx + sn * dy
    for i in range(n):
        dx, dy = points[i + 1, 0] - x, points[i + 1, 1] - y
        bx, by = -sn * dx + cs * dy, cs * dx + sn * dy
        if not (
            max(ax, bx) < -hw - margin
            or min(ax, bx) > hw + margin
            or max(ay, by) < -margin
            or min(ay, by) > depth + margin
        ):
            out[k, 0], out[k, 1], out[k, 2], out[k, 3], out[k, 4] = ax, ay, bx, by, cum[i]
            k += 1
        ax, ay = bx, by
    return out[:k]


@njit(cache=True)
def _pipe_distance(segs, grid, radius, buffers):
    """Per pixel: distance to the pipe's centre line, signed offset across it, arc length.

    Only pixels within ``radius`` of a segment are visited (a row's column range per segment);
    ``buffers.dist`` must hold ``inf`` on entry.
    """
    dist, across, along = buffers.dist, buffers.across, buffers.along
    h, w = dist.shape
    for j in range(segs.shape[0]):
        ax, ay, bx, by, s0 = segs[j, 0], segs[j, 1], segs[j, 2], segs[j, 3], segs[j, 4]
        ex, ey = bx - ax, by - ay
        length2 = ex * ex + ey * ey
        length = math.sqrt(length2)
        r_lo = int(row_at(max(ay, by) + radius, grid))
        r_hi = int(row_at(min(ay, by) - radius, grid)) + 1
        for r in range(max(r_lo, 0), min(r_hi, h)):
            cy = row_y(r, grid)
            # columns within the capsule: the segment's x at this row ± radius/|sin|, inside its box
            x_lo, x_hi = min(ax, bx) - radius, max(ax, bx) + radius
            if abs(ey) > 1e-12:
                xc = ax + ex * (cy - ay) / ey
                half = radius * length / abs(ey)
                x_lo, x_hi = max(x_lo, xc - half - radius), min(x_hi, xc + half + radius)
            c_lo = int(column_at(x_lo, grid))
            c_hi = int(column_at(x_hi, grid)) + 1
            for c in range(max(c_lo, 0), min(c_hi, w)):
                cx = column_x(c, grid)
                qx, qy = cx - ax, cy - ay
                t = (qx * ex + qy * ey) / length2
                t = min(max(t, 0.0), 1.0)
                dx, dy = qx - t * ex, qy - t * ey
                d = math.sqrt(dx * dx + dy * dy)
                if d < dist[r, c]:
                    dist[r, c] = d
                    # positive to starboard of the pipe's direction (cross product a→b × a→p)
                    across[r, c] = d if ex * qy - ey * qx < 0.0 else -d
                    along[r, c] = s0 + t * length


def light_and_water(water: Water, camera: CameraParams) -> Lighting:
    """Per pixel, the gain on the albedo and the veil: grey level = gain·albedo + veil.

    They depend only on the water and the geometry, not on the pose, so a renderer computes them
    once. The gain puts the seabed's mean albedo at the image centre at grey level 100.
    """
    xs, ys = pixel_centres(water, camera)
    cx, cy = xs[None, :], ys[:, None] - 0.5 * camera.depth
    k_light = -math.log(1.0 - water.light_falloff)
    light = np.exp(-0.5 * k_light * ((cx / camera.half_width) ** 2 + (cy / (0.5 * camera.depth)) ** 2))
    path = 2.0 * np.sqrt(water.altitude**2 + cx**2 + cy**2)
    t = np.exp(-water.turbidity * path)
    t0 = math.exp(-water.turbidity * 2.0 * water.altitude)
    gain = 100.0 / (SEABED_ALBEDO[0] * t0 + VEIL * (1.0 - t0))
    veil = gain * light * VEIL * (1.0 - t)
    return Lighting((gain * light * t).astype(np.float32), veil.astype(np.float32))


@njit(cache=True)
def _compose(img, pose, settings, textures, buffers, light):
    """Albedo per pixel (seabed, pipe, sand, growth) times the light's gain plus its veil.

    ``pose`` is (x, y, ψ); ``settings`` a :class:`FrameSettings`, ``textures`` the scene's
    :class:`Textures`, ``buffers`` the :class:`Buffers` filled by :func:`_pipe_distance`,
    ``light`` the :class:`Lighting`.
    """
    h, w = img.shape
    x, y, psi = pose
    radius, burial, growth_share = settings.radius, settings.burial, settings.growth
    seabed, growth = textures.seabed, textures.growth
    dist, across, along, a, b = buffers.dist, buffers.across, buffers.along, light.gain, light.veil
    grid = pixel_grid(settings.half_width, settings.depth, h, w)
    cs, sn = math.cos(psi), math.sin(psi)
    mask = seabed.shape[0] - 1  # the tile's size is a power of two
    sand_from = radius * (1.0 - 2.0 * burial)
    # the seabed, bilinear in the earth-fixed tile: a row's tile coordinates advance by a fixed
    # step per column; the row first without the pipe (a loop without branches), then its pipe pixels
    dex, dey = -sn * grid.dx / TILE_RES, cs * grid.dx / TILE_RES
    ground = np.empty(w, dtype=np.float32)
    one = np.float32(1.0)
    for r in range(h):
        cy = row_y(r, grid)
        cx = column_x(0, grid)  # the row's first column; the next ones a step (dex, dey) on
        ex = (x + cs * cy - sn * cx) / TILE_RES
        ey = (y + sn * cy + cs * cx) / TILE_RES
        for c in range(w):
            fx, fy = math.floor(ex), math.floor(ey)
            i0, j0 = int(fx) & mask, int(fy) & mask
            i1, j1 = (i0 + 1) & mask, (j0 + 1) & mask
            wx, wy = np.float32(ex - fx), np.float32(ey - fy)
            s00, s01, s10, s11 = seabed[i0, j0], seabed[i0, j1], seabed[i1, j0], seabed[i1, j1]
            ground[c] = (one - wx) * (s00 + wy * (s01 - s00)) + wx * (s10 + wy * (s11 - s10))
            img[r, c] = a[r, c] * ground[c] + b[r, c]
            ex += dex
            ey += dey
        for c in range(w):
            if dist[r, c] >= radius:
                continue
            u = across[r, c]
            if burial > 0.0 and u > sand_from:
                albedo = 0.5 * (ground[c] + SAND_ALBEDO)
            else:
                nz = math.sqrt(max(1.0 - (u / radius) ** 2, 0.0))
                albedo = PIPE_ALBEDO * (0.55 + 0.45 * nz)
                if growth_share > 0.0:
                    g = growth[int(along[r, c] / TILE_RES) & mask, int((u + radius) / TILE_RES) & mask]
                    if g < growth_share:
                        albedo = GROWTH_ALBEDO * (0.7 + 0.6 * g / growth_share)
            img[r, c] = a[r, c] * albedo + b[r, c]


@njit(cache=True)
def _blur(img, tmp, sigma):
    """Separable Gaussian blur of ``img`` in place (edges replicated), ``tmp`` a same-size buffer."""
    if sigma < 0.05:
        return
    rad = int(math.ceil(3.0 * sigma))
    k = np.empty(2 * rad + 1, dtype=np.float32)
    total = 0.0
    for i in range(-rad, rad + 1):
        k[i + rad] = math.exp(-0.5 * (i / sigma) ** 2)
        total += k[i + rad]
    k /= total
    h, w = img.shape
    # each pass tap by tap over whole rows, loops the compiler vectorizes (a loop over the taps per
    # pixel took 3× as long); the row is padded with its edge values
    row = np.empty(w + 2 * rad, dtype=np.float32)
    for r in range(h):
        for c in range(w):
            row[c + rad] = img[r, c]
        for c in range(rad):
            row[c] = img[r, 0]
            row[w + rad + c] = img[r, w - 1]
        out = tmp[r]
        for c in range(w):
            out[c] = k[0] * row[c]
        for i in range(1, 2 * rad + 1):
            ki = k[i]
            for c in range(w):
                out[c] += ki * row[c + i]
    for r in range(h):
        dst = img[r]
        for c in range(w):
            dst[c] = 0.0
        for i in range(2 * rad + 1):
            src = tmp[min(max(r + i - rad, 0), h - 1)]
            ki = k[i]
            for c in range(w):
                dst[c] += ki * src[c]


@njit(cache=True)
def _finish(img, noise, sd, out):
    """Add sensor noise and quantize to ``uint8`` with saturation."""
    h, w = img.shape
    for r in range(h):
        for c in range(w):
            v = img[r, c] + sd * noise[r, c] + 0.5
            out[r, c] = 0 if v < 0.0 else (255 if v >= 255.0 else np.uint8(v))


@njit(cache=True)
def _render(out, buffers, light, settings, segs, textures, snow, noise, pose):
    """One frame in one compiled call (a Python call per stage cost more than some stages).

    ``segs`` are the pipe's segments near the footprint (:func:`pipe_segments`), ``snow`` three
    uniform numbers per marine-snow speck (row, column, brightness), ``noise`` a frame of standard
    normals, ``pose`` (x, y, ψ); the records as in :func:`_compose`.
    """
    img = buffers.img
    h, w = img.shape
    buffers.dist[:] = np.inf
    _pipe_distance(segs, pixel_grid(settings.half_width, settings.depth, h, w), settings.radius, buffers)
    _compose(img, pose, settings, textures, buffers, light)
    lo, span = SNOW_LEVEL[0], SNOW_LEVEL[1] - SNOW_LEVEL[0]
    for i in range(snow.size // 3):
        r = min(int(snow[3 * i] * h), h - 1)
        c = min(int(snow[3 * i + 1] * w), w - 1)
        img[r, c] += lo + span * snow[3 * i + 2]
    _blur(img, buffers.tmp, settings.blur)
    _finish(img, noise, np.float32(settings.noise), out)


class Renderer:
    """Renders camera images of one geometry; holds its buffers so a frame allocates nothing."""

    def __init__(self, water: Water = CLEAR, camera: CameraParams = PAPER_CAMERA) -> None:
        self.water, self.camera = water, camera
        shape = (water.height, water.width)
        self._buffers = Buffers(*(np.zeros(shape, dtype=np.float32) for _ in Buffers._fields))
        self._light = light_and_water(water, camera)
        self._no_pipe = np.zeros((0, 5))
        self._settings = FrameSettings(
            half_width=float(camera.half_width),
            depth=float(camera.depth),
            radius=0.5 * water.pipe_diameter,
            burial=float(water.burial),
            growth=float(water.growth),
            blur=math.hypot(water.blur, SCATTER_BLUR * water.turbidity),
            noise=float(water.noise),
        )
        self._noise_bank: np.ndarray | None = None  # drawn from the first frame's generator

    def render(
        self,
        points: np.ndarray,
        cum: np.ndarray,
        pose: tuple[float, float, float],
        textures: Textures,
        rng: np.random.Generator,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """The image (``uint8``, H × W) seen from ``pose`` = (x, y, ψ) above the pipeline.

        ``points``/``cum``: the pipeline's vertices and cumulative arc lengths (an empty pipeline,
        ``points`` of shape (0, 2), gives a frame without pipe).
        """
        wt, cam = self.water, self.camera
        x, y, psi = pose
        n_snow = rng.poisson(wt.snow) if wt.snow > 0.0 else 0
        snow = rng.random(3 * n_snow)  # row, column and brightness of each speck
        if out is None:
            out = np.empty((wt.height, wt.width), dtype=np.uint8)
        segs = self._no_pipe
        if points.shape[0] >= 2:
            segs = pipe_segments(points, cum, x, y, psi, cam.half_width, cam.depth, 0.5 * wt.pipe_diameter)
        noise = self._noise_frame(rng)
        pose = (float(x), float(y), float(psi))
        _render(out, self._buffers, self._light, self._settings, segs, textures, snow, noise, pose)
        return out

    def _noise_frame(self, rng: np.random.Generator) -> np.ndarray:
        """A frame of standard normals: a window of a bank read from a random offset.

        Drawing 6,144 fresh normals per frame cost ≈ 90 µs; the bank of :data:`NOISE_BANK` normals
        is drawn once from the first frame's generator, and every frame reads it from an offset
        drawn from its own generator.
        """
        size = self._buffers.img.size
        if self._noise_bank is None:
            self._noise_bank = rng.standard_normal(max(NOISE_BANK, 4 * size), dtype=np.float32)
        start = int(rng.integers(0, self._noise_bank.size - size))
        return self._noise_bank[start : start + size].reshape(self._buffers.img.shape)


def pixel_centres(water: Water = CLEAR, camera: CameraParams = PAPER_CAMERA) -> tuple[np.ndarray, np.ndarray]:
    """Camera coordinates (m) of the columns' and the rows' pixel centres (:mod:`.pixels`)."""
    grid = pixel_grid(float(camera.half_width), float(camera.depth), water.height, water.width)
    return column_x(np.arange(water.width), grid), row_y(np.arange(water.height), grid)
