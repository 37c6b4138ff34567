"""The scene's textures from the bank: distributed as fields drawn afresh, seamless, seeded."""

import numpy as np
import pytest
import scipy.fft
import scipy.stats

from pipefollow.perception.textures import SEABED_ALBEDO, TILE, bank, make_textures

SCENES = 48


def fresh_seabed(rng: np.random.Generator, beta: float = 1.2) -> np.ndarray:
    """A seabed tile made as it was before the bank: white noise filtered by 1/f^beta (scipy's FFT)."""
    f = scipy.fft.fftfreq(TILE)
    k = np.hypot(f[:, None], f[None, :])
    k[0, 0] = 1.0
    field = scipy.fft.ifft2(scipy.fft.fft2(rng.standard_normal((TILE, TILE))) / k**beta).real
    field = (field - field.mean()) / field.std()
    return np.clip(SEABED_ALBEDO[0] + SEABED_ALBEDO[1] * field, 0.05, 0.95)


def radial_power(tiles) -> tuple[np.ndarray, np.ndarray]:
    """Mean power per ring of integer wavenumber 1 … TILE/2 − 1 (cycles per tile), over ``tiles``."""
    f = scipy.fft.fftfreq(TILE, 1.0 / TILE)
    ring = np.rint(np.hypot(f[:, None], f[None, :])).astype(int).ravel()
    rings = np.arange(1, TILE // 2)
    power = np.zeros(rings.size)
    for t in tiles:
        p = np.abs(scipy.fft.fft2(t - t.mean())).ravel() ** 2
        power += np.bincount(ring, p, minlength=TILE)[rings] / np.bincount(ring, minlength=TILE)[rings]
    return rings, power / len(tiles)


@pytest.fixture(scope="module")
def scenes():
    return [make_textures(np.random.default_rng(s)) for s in range(SCENES)]


def test_each_seabed_has_the_albedos_mean_and_spread_and_a_normal_histogram(scenes):
    tiles = np.array([s.seabed for s in scenes], dtype=float)
    # normalised per tile (the clip at 4.4 and 8.4 s.d. hardly acts)
    np.testing.assert_allclose(tiles.mean(axis=(1, 2)), SEABED_ALBEDO[0], atol=1e-4)
    np.testing.assert_allclose(tiles.std(axis=(1, 2)), SEABED_ALBEDO[1], rtol=1e-3)
    # pooled, the albedo is normal: its quantiles are the normal distribution's and those of fresh tiles
    q = np.array([0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99])
    normal = scipy.stats.norm.ppf(q, *SEABED_ALBEDO)
    rng = np.random.default_rng(0)
    fresh = np.array([fresh_seabed(rng) for _ in range(SCENES)])
    np.testing.assert_allclose(np.quantile(tiles, q), normal, atol=0.1 * SEABED_ALBEDO[1])
    np.testing.assert_allclose(np.quantile(tiles, q), np.quantile(fresh, q), atol=0.1 * SEABED_ALBEDO[1])


def test_the_seabeds_spectrum_falls_as_one_over_f_to_the_1_2_as_fresh_tiles_do(scenes):
    rings, power = radial_power([s.seabed.astype(float) for s in scenes])
    # amplitude ∝ 1/f^1.2: power ∝ f^−2.4 (a least-squares slope in log-log over the rings)
    slope = np.polyfit(np.log(rings), np.log(power), 1)[0]
    assert slope == pytest.approx(-2.4, abs=0.1)
    rng = np.random.default_rng(1)
    _, fresh = radial_power([fresh_seabed(rng) for _ in range(SCENES)])
    # band by band (octaves of wavenumber) the power is that of fresh tiles within 15 %
    for lo in (1, 2, 4, 8, 16, 32, 64):
        band = (rings >= lo) & (rings < 2 * lo)
        assert power[band].sum() / fresh[band].sum() == pytest.approx(1.0, abs=0.15), lo


def test_the_tiles_are_seamless_the_wrap_is_like_any_neighbouring_texels(scenes):
    # the tile repeats in the earth frame: its last and first rows (columns) must be neighbours
    for s in scenes[:8]:
        t = s.seabed.astype(float)
        inner = np.abs(np.diff(t, axis=0)).mean()
        assert np.abs(t[0] - t[-1]).mean() == pytest.approx(inner, rel=0.25)
        inner = np.abs(np.diff(t, axis=1)).mean()
        assert np.abs(t[:, 0] - t[:, -1]).mean() == pytest.approx(inner, rel=0.25)


def test_growth_tiles_hold_every_rank_once_so_a_share_g_covers_g(scenes):
    levels = np.arange(TILE * TILE) / (TILE * TILE)
    for s in scenes[:4]:
        np.testing.assert_array_equal(np.sort(s.growth.ravel()), levels)
        for g in (0.1, 0.35, 0.8):
            assert np.mean(s.growth < g) == pytest.approx(g, abs=1 / TILE**2)


def test_seeds_give_their_own_scenes_and_the_same_seed_the_same_one(scenes):
    again = make_textures(np.random.default_rng(3))
    np.testing.assert_array_equal(again.seabed, scenes[3].seabed)
    np.testing.assert_array_equal(again.growth, scenes[3].growth)
    flat = np.array([s.seabed.ravel() for s in scenes], dtype=float)
    rho = np.corrcoef(flat)[np.triu_indices(len(scenes), 1)]
    # independent 1/f^1.2 tiles correlate by chance only (low frequencies dominate: |ρ| of a few 0.1)
    assert np.abs(rho).max() < 0.6 and np.abs(rho).mean() < 0.15
    growth = np.array([s.growth.ravel() for s in scenes[:12]], dtype=float)
    assert np.abs(np.corrcoef(growth)[np.triu_indices(12, 1)]).max() < 0.8


def test_a_scene_draws_the_same_numbers_with_or_without_growth():
    with_growth, without = np.random.default_rng(9), np.random.default_rng(9)
    a, b = make_textures(with_growth), make_textures(without, growth=False)
    np.testing.assert_array_equal(a.seabed, b.seabed)
    assert not b.growth.any() and a.growth.any()
    assert with_growth.random() == without.random()


def test_an_unknown_bank_is_refused_by_name():
    with pytest.raises(ValueError, match="texture bank 'sand'"):
        bank("sand")
