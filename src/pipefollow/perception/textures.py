"""The scene's textures: the seabed's albedo and the marine growth on the pipe, periodic tiles.

A scene's tiles are made from a bank of noise fields drawn once per process from a fixed seed
(:func:`bank`), so a reset pays for no Fourier transform and no sort:

* the seabed is ``cos θ·A + sin θ·B`` for two different fields A and B of the bank, each rolled
  by its own offset and turned its own way (as drawn, transposed, mirrored, or transposed and
  mirrored: a quarter turn), brought to mean 0 and s.d. 1, then to albedo (mean 0.36, s.d. 0.07,
  clipped to [0.05, 0.95]). The bank's fields are 1/f^1.2 Gaussian noise, not normalised; a roll
  or a symmetry of the periodic square leaves that process as it is (white noise and the filter
  1/|f|^β are unchanged by them), and ``cos θ·A + sin θ·B`` of two independent copies of a
  Gaussian field is another copy, so a scene's seabed is distributed as a field drawn afresh
  (tested: histogram and spectrum). What the bank gives up is independence between scenes: two
  scenes may share a field, seen shifted, turned and mixed with another partner at another weight.
* the growth tile holds the ranks of a 1/f^1.6 field divided by their number (uniform in [0, 1),
  so a growth share g covers the share g of the pipe); a scene's tile is one field of the bank,
  rolled and turned: a permutation of the texels, still exactly uniform.

The bank stores each field transposed too and each row twice, so a scene's row is a slice of a
bank row, read by loops the compiler vectorizes. A scene draws 13 numbers from the generator it
is given, with or without marine growth. The tiles are the same bits on every CPU: the bank is
rounded to 16-bit integers (a last-bit difference of its Fourier transforms between libraries
changes a value only on a rounding boundary), and a scene is made with + − × / and a square root
in a fixed order (no fastmath, no libm).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit

TILE = 256  # texture tile size (texels)
TILE_RES = 0.025  # texel size (m): the seabed texture repeats every 6.4 m
SEABED_ALBEDO = (0.36, 0.07)  # mean and s.d. of the seabed's albedo
SEABED_BETA = 1.2  # the seabed's amplitude spectrum falls as 1/f^beta
GROWTH_BETA = 1.6  # the marine growth's
BANK_FIELDS = 16  # noise fields per bank
BANK_SEED = 20261202  # the banks' seed: the same fields in every process


class Textures(NamedTuple):
    """The seabed and marine-growth textures of a scene (``TILE × TILE`` float32 tiles)."""

    seabed: np.ndarray  # albedo, indexed by earth (x, y) / TILE_RES modulo TILE
    growth: np.ndarray  # ranks in [0, 1), indexed by (arc length, position across the pipe)


def smooth_noise(rng: np.random.Generator, beta: float) -> np.ndarray:
    """A periodic ``TILE × TILE`` field of 1/f^beta Gaussian noise (white noise filtered, not normalised)."""
    white = rng.standard_normal((TILE, TILE))
    f = np.fft.fftfreq(TILE)
    k = np.sqrt(f[:, None] ** 2 + f[None, :] ** 2)
    k[0, 0] = 1.0
    return np.fft.ifft2(np.fft.fft2(white) / k**beta).real


@functools.cache
def bank(kind: str) -> np.ndarray:
    """The process's fields of ``kind`` ("seabed" or "growth"), ``(2, BANK_FIELDS, TILE, 2·TILE)``.

    Drawn on first use from :data:`BANK_SEED`: the seabed's 1/f^1.2 fields as they are, on one
    scale for all as ``int16`` (steps of 1/32,000 of the largest value); the growth's 1/f^1.6
    fields as their ranks, ``uint16``. ``[1]`` holds ``[0]``'s fields transposed (a scene reads
    either along its rows), and every row is stored twice (a rolled row is one slice). Small
    integers, because a reset's time goes into reading two fields.
    """
    if kind not in ("seabed", "growth"):
        raise ValueError(f"texture bank {kind!r}: unknown (seabed or growth)")
    rng = np.random.default_rng(np.random.SeedSequence([BANK_SEED, int(kind == "growth")]))
    if kind == "seabed":
        raw = np.stack([smooth_noise(rng, SEABED_BETA) for _ in range(BANK_FIELDS)])
        fields = np.round(raw * (32_000.0 / np.abs(raw).max())).astype(np.int16)
    else:
        fields = np.empty((BANK_FIELDS, TILE, TILE), np.uint16)
        for k in range(BANK_FIELDS):
            ranks = np.empty(TILE * TILE, np.uint16)
            ranks[np.argsort(smooth_noise(rng, GROWTH_BETA).ravel(), kind="stable")] = np.arange(TILE * TILE)
            fields[k] = ranks.reshape(TILE, TILE)
    both = np.stack([fields, fields.transpose(0, 2, 1)])
    both = np.concatenate([both, both], axis=3)
    both.flags.writeable = False  # shared by every scene of the process
    return both


@njit(cache=True)
def _row(r, shift, mirror):
    """The bank field's row that a scene's row ``r`` reads: rolled by ``shift``, then mirrored."""
    i = (r + shift) & (TILE - 1)
    return (TILE - i) & (TILE - 1) if mirror else i


@njit(cache=True)
def _seabed(fields, picks, weight_a, weight_b, albedo, out):
    """``out`` = albedo of ``weight_a``·A + ``weight_b``·B brought to mean 0 and s.d. 1.

    ``picks`` as drawn by :func:`make_textures`: A is field ``picks[0]`` of ``fields`` (a
    :func:`bank`), its texel (r, c) the bank's (row(r), c + roll) in the orientation ``picks[6]``
    (bit 2: transposed, bit 1: rows mirrored), the rolls ``picks[2:4]``; B the same with
    ``picks[1]``, ``picks[4:6]``, ``picks[7]``. ``albedo`` = (mean, s.d., lowest, highest). The
    sums run per column, then over the columns, in a fixed order (no fastmath): the tile is the
    same on every CPU.
    """
    n = out.shape[0]
    fa, fb = fields[picks[6] >> 1, picks[0]], fields[picks[7] >> 1, picks[1]]
    ca, cb = picks[3], picks[5]
    s1, s2, mix = np.zeros(n), np.zeros(n), np.empty(n)
    for r in range(n):  # the mix into ``out`` (the fields read once), its sums per column
        ra = fa[_row(r, picks[2], picks[6] & 1)][ca : ca + n]
        rb = fb[_row(r, picks[4], picks[7] & 1)][cb : cb + n]
        o = out[r]
        # three simple loops, which the compiler vectorizes (one loop doing all three: 3× the time)
        for c in range(n):
            mix[c] = weight_a * np.float64(ra[c]) + weight_b * np.float64(rb[c])
        for c in range(n):
            s1[c] += mix[c]
            s2[c] += mix[c] * mix[c]
        for c in range(n):
            o[c] = mix[c]
    total, squares = 0.0, 0.0
    for c in range(n):
        total += s1[c]
        squares += s2[c]
    mu = total / (n * n)
    scale = albedo[1] / math.sqrt(squares / (n * n) - mu * mu)
    lo, hi = albedo[2], albedo[3]
    for r in range(n):
        o = out[r]
        for c in range(n):
            o[c] = min(max(albedo[0] + scale * (o[c] - mu), lo), hi)


@njit(cache=True)
def _growth(fields, picks, out):
    """``out`` = ranks / TILE² of the growth field ``picks[8]`` (:func:`make_textures`).

    Rolled by ``picks[9:11]`` and turned by ``picks[11]`` as :func:`_seabed` rolls and turns A.
    """
    n = out.shape[0]
    f, c0, scale = fields[picks[11] >> 1, picks[8]], picks[10], np.float32(1.0 / (n * n))
    for r in range(n):
        row, o = f[_row(r, picks[9], picks[11] & 1)][c0 : c0 + n], out[r]
        for c in range(n):
            o[c] = scale * np.float32(row[c])


def make_textures(rng: np.random.Generator, growth: bool = True) -> Textures:
    """A new scene's textures chosen by ``rng`` from the banks (module docstring).

    ``growth=False`` leaves the marine-growth tile blank (zeros: a renderer without growth never
    reads it) but draws its numbers all the same, so ``rng`` ends where it would have.
    """
    n = BANK_FIELDS
    # the seabed's two fields (the second another than the first), their rolls (row, column) and
    # orientations (bit 2: transposed, bit 1: rows mirrored); the growth's field, roll, orientation
    picks = rng.integers(0, [n, n - 1, TILE, TILE, TILE, TILE, 4, 4, n, TILE, TILE, 4])
    picks[1] = (picks[0] + 1 + picks[1]) % n
    # the weights (cos θ, sin θ) for θ = 2·atan(t), t uniform in [−1, 1): θ in [−90°, 90°), written
    # with + − × / only, so they are the same bits on every platform (no libm)
    t = 2.0 * rng.random() - 1.0
    seabed = np.empty((TILE, TILE), np.float32)
    _seabed(bank("seabed"), picks, (1.0 - t * t) / (1.0 + t * t), 2.0 * t / (1.0 + t * t), _ALBEDO, seabed)
    tile = np.zeros((TILE, TILE), np.float32)
    if growth:
        _growth(bank("growth"), picks, tile)
    return Textures(seabed, tile)


_ALBEDO = np.array([*SEABED_ALBEDO, 0.05, 0.95])  # the seabed's mean, s.d., lowest and highest albedo


class TextureCache:
    """A scene's textures made once per generator state: the same seed gives them without the work.

    The textures are a pure function of the generator's state when they are drawn, so :meth:`draw`
    keys them by that state: on a hit it returns the stored tiles and moves the generator to the
    state their drawing left it in, so everything drawn after them (every frame's noise) is what it
    would have been. A miss draws them (:func:`make_textures`) and keeps them; at most ``size``
    scenes are kept, the least recently used leaving first.
    """

    def __init__(self, size: int = 32) -> None:
        self.size = size
        self._scenes: dict[tuple, tuple[Textures, dict]] = {}

    def draw(self, rng: np.random.Generator, growth: bool = True) -> Textures:
        """The textures :func:`make_textures` would draw from ``rng``, ``rng`` left as it would leave it."""
        bits = rng.bit_generator
        key = (growth, repr(bits.state))
        hit = self._scenes.pop(key, None)
        if hit is not None:
            self._scenes[key] = hit  # the most recently used
            bits.state = hit[1]
            return hit[0]
        textures = make_textures(rng, growth)
        self._scenes[key] = (textures, bits.state)
        while len(self._scenes) > self.size:
            del self._scenes[next(iter(self._scenes))]
        return textures


SCENES = TextureCache()  # the process's scenes, shared by the environments' cameras
