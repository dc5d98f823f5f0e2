"""Seam, periodic-plus-smooth, detail and fidelity metrics on synthetic and real textures."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from seamless_usd import metrics as M

from benchscripts import load_benchmark

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"


def periodic_noise(h=128, w=128, c=3, sigma=2.0, seed=0) -> np.ndarray:
    """Gaussian-filtered white noise, filtered in the Fourier domain: exactly periodic."""
    rng = np.random.default_rng(seed)
    n = rng.normal(size=(h, w, c))
    fy, fx = np.fft.fftfreq(h)[:, None], np.fft.fftfreq(w)[None, :]
    g = np.exp(-2 * (np.pi * sigma) ** 2 * (fx**2 + fy**2))
    out = np.real(np.fft.ifft2(np.fft.fft2(n, axes=(0, 1)) * g[..., None], axes=(0, 1)))
    return out / np.abs(out).max()


def sinusoids(h=96, w=128, n=24, seed=1) -> np.ndarray:
    """A sum of plane waves with integer periods over the image and random phases."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:h, 0:w]
    img = np.zeros((h, w))
    for _ in range(n):
        ky, kx = rng.integers(-12, 13, size=2)
        img += np.cos(2 * np.pi * (ky * y / h + kx * x / w) + rng.uniform(0, 2 * np.pi))
    return img / np.abs(img).max()


def load(name: str) -> np.ndarray:
    """A sample texture in the network domain [-1, 1]."""
    return oiio.ImageBuf(str(TEXTURES / name)).get_pixels(oiio.FLOAT) * 2.0 - 1.0


def window(img: np.ndarray, y=37, x=53, size=150) -> np.ndarray:
    return img[y : y + size, x : x + size]


# ---- values -------------------------------------------------------------------------------


@pytest.mark.parametrize("img", [periodic_noise(), sinusoids()], ids=["noise", "sinusoids"])
def test_periodic_image_has_seam_ratio_one_and_small_ps_score(img):
    r = M.seam_ratios(img)
    for key in ("seam_ratio_x", "seam_ratio_y", "seam_ratio2_x", "seam_ratio2_y"):
        assert 0.75 < r[key] < 1.3, (key, r[key])
    # A periodic image's smooth part is not exactly 0 (Moisan's boundary term counts the wrap
    # differences of a periodic image too), but small against a cut window's (> 0.15).
    assert M.ps_score(img) < 0.1


def test_periodic_component_is_periodic_and_sums_back():
    img = load("brick_roughness.png")
    p, s = M.periodic_smooth_decomposition(img)
    np.testing.assert_allclose(p + s, img, atol=1e-9)
    assert abs(s.mean()) < 1e-9
    assert M.seam_ratios(p)["seam_ratio_x"] < 1.3 < M.seam_ratios(img)["seam_ratio_x"]


def test_periodic_component_has_the_interior_laplacian():
    # Moisan's characterisation: laplacian_periodic(p) == laplacian_interior(u), where the interior
    # Laplacian only counts neighbours inside the image.
    u = window(load("wood_color.png"), size=40)[:, :33]
    p, _ = M.periodic_smooth_decomposition(u)
    lap_p = sum(np.roll(p, sh, axis=ax) for ax in (0, 1) for sh in (1, -1)) - 4 * p
    pad = np.pad(u, ((1, 1), (1, 1), (0, 0)))
    inside = np.pad(np.ones(u.shape[:2]), 1)[..., None]
    lap_u = np.zeros_like(u)
    for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)):
        nb = pad[1 + dy : 1 + dy + u.shape[0], 1 + dx : 1 + dx + u.shape[1]]
        has = inside[1 + dy : 1 + dy + u.shape[0], 1 + dx : 1 + dx + u.shape[1]]
        lap_u += has * (nb - u)
    np.testing.assert_allclose(lap_p, lap_u, atol=1e-9)


@pytest.mark.parametrize("name", ["brick_albedo.png", "brick_roughness.png", "wood_roughness.png", "cloth.png"])
def test_window_of_real_texture_is_not_tileable(name):
    cut = window(load(name))
    r = M.seam_ratios(cut)
    assert max(r["seam_ratio_x"], r["seam_ratio_y"]) > 2.0, r
    assert M.ps_score(cut) > 0.15


def test_tiling_a_window_periodically_makes_it_seamless():
    cut = window(load("brick_albedo.png"), size=64)
    # Mirror-tiling a window (a b / b' a') is periodic with period 2x.
    mirrored = np.concatenate([cut, cut[::-1]], axis=0)
    mirrored = np.concatenate([mirrored, mirrored[:, ::-1]], axis=1)
    r = M.seam_ratios(mirrored)
    assert r["seam_ratio_x"] < 1.3 and r["seam_ratio_y"] < 1.3


@pytest.mark.parametrize("name", ["brick_albedo.png", "brick_roughness.png", "wood_color.png", "cloth.png"])
def test_crossfade_blurs_the_seam_bands(name):
    src = load(name)
    tile = load_benchmark("baselines").crossfade_tile(src)
    assert M.detail_ratio(tile) < 0.99
    assert M.detail_ratio(tile) < M.detail_ratio(src)
    assert M.ps_score(tile) < 0.5 * M.ps_score(src)


def test_crossfade_of_noise_has_detail_ratio_well_below_one():
    noise = np.random.default_rng(3).uniform(-1, 1, size=(160, 160, 1))
    tile = load_benchmark("baselines").crossfade_tile(noise)
    # Linear crossfade of uncorrelated noise: RMS factor sqrt(a^2 + (1-a)^2) over the blend.
    assert 0.75 < M.detail_ratio(tile) < 0.95


def test_normals_use_angles():
    # A normal map tilting about y by an angle that grows by 1 degree per column, then jumps back.
    w = 40
    theta = np.deg2rad(np.arange(w, dtype=float))[None, :].repeat(8, axis=0)
    n = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
    r = M.seam_ratios(n, is_normal=True)
    assert r["seam_ratio_x"] == pytest.approx(w - 1, rel=1e-6)  # 39 degrees / 1 degree
    assert r["seam_ratio_y"] == pytest.approx(1.0)  # constant along y: 0 / 0
    # Scaling a vector does not change its direction, so lengths do not matter.
    r2 = M.seam_ratios(n * np.linspace(0.3, 1.0, w)[None, :, None], is_normal=True)
    assert r2["seam_ratio_x"] == pytest.approx(w - 1, rel=1e-6)
    # Two channels (x, y) rebuild z.
    r3 = M.seam_ratios(n[..., :2], is_normal=True)
    assert r3["seam_ratio_x"] == pytest.approx(w - 1, rel=1e-6)


def test_real_normal_map_window():
    cut = window(load("brick_normal.png"))
    m = M.map_metrics(cut, load("brick_normal.png"), is_normal=True)
    # Fine bump noise dominates the angles between neighbours of this map, so its seam is mild.
    assert max(m["seam_ratio_x"], m["seam_ratio_y"]) > 1.2
    assert all(np.isfinite(v) for v in m.values() if v is not None)
    assert 0.0 < m["ssim"] < 1.0


def test_ssim_of_the_source_itself_is_one_and_of_noise_is_low():
    src = load("wood_color.png")
    assert M.ssim_tiled(src, src) == pytest.approx(1.0)
    noise = np.random.default_rng(0).uniform(-1, 1, size=(64, 64, 3))
    assert M.ssim_tiled(noise, src) < 0.1


def test_tile_to_repeats_from_the_top_left():
    t = np.arange(6).reshape(2, 3)
    np.testing.assert_array_equal(M.tile_to(t, (3, 4)), [[0, 1, 2, 0], [3, 4, 5, 3], [0, 1, 2, 0]])


def test_gram_distance_with_a_feature_callable():
    def features(img):  # (H, W, C) -> layers of (K, h, w): the image and its 2x subsample
        chw = np.moveaxis(img, -1, 0)
        return [chw, chw[:, ::2, ::2]]

    a = load("cloth.png")
    assert M.gram_distance(a, a, features) == pytest.approx(0.0)
    assert M.gram_distance(a * 0.5, a, features) == pytest.approx(0.75)  # |0.25 - 1| / 1
    assert M.gram_distance(np.roll(a, 17, axis=1), a, features) < 0.02  # stationary statistics


def test_map_metrics_keys_are_stable():
    src = load("cloth.png")
    m = M.map_metrics(src, src, features=lambda x: [np.moveaxis(x, -1, 0)])
    assert tuple(m) == M.METRIC_KEYS
    assert m["ssim"] == pytest.approx(1.0) and m["gram_distance"] == pytest.approx(0.0)
    bare = M.map_metrics(src)
    assert bare["ssim"] is None and bare["gram_distance"] is None


def test_constant_image_is_seamless():
    m = M.map_metrics(np.full((16, 16, 3), 0.25), np.full((16, 16, 3), 0.25))
    assert m["seam_ratio_x"] == 1.0 and m["ps_score"] == 0.0 and m["detail_ratio"] == 1.0


def test_bands():
    mask = M.seam_band_mask((100, 50))
    assert mask[:, 0].all() and mask[0].all() and mask[-1].all() and mask[:, -1].all()
    assert mask[:, 4].all() and not mask[50, 5] and not mask[10, 25]
    centre = M.centre_band_mask((100, 50))
    assert centre[50].all() and centre[:, 25].all() and not centre[0, 0]
    with pytest.raises(ValueError, match="band"):
        M.seam_band_mask((10, 10), band=0.4)


# ---- shapes -------------------------------------------------------------------------------


def test_shapes_hw_and_hwc_agree():
    img = periodic_noise(c=1)[..., 0] + window(load("brick_roughness.png"), size=128)[..., 0]
    a = M.map_metrics(img, img)
    b = M.map_metrics(img[..., None], img[..., None])
    assert a == pytest.approx(b)


def test_non_square_and_multichannel():
    img = load("brick_albedo.png")[:100, :180]
    m = M.map_metrics(img, load("brick_albedo.png"))
    assert all(np.isfinite(v) for v in m.values() if v is not None)
    assert M.periodic_smooth_decomposition(img)[0].shape == img.shape


def test_bad_shapes_raise():
    with pytest.raises(ValueError, match="shape"):
        M.seam_ratios(np.zeros((1, 4, 4, 3)))
    with pytest.raises(ValueError, match="3x3"):
        M.seam_ratios(np.zeros((2, 8)))
    with pytest.raises(ValueError, match="2 or 3 channels"):
        M.seam_ratios(np.zeros((8, 8, 4)), is_normal=True)
    with pytest.raises(ValueError, match="channels"):
        M.ssim_tiled(np.zeros((8, 8, 3)), np.zeros((8, 8, 1)))


# ---- NaN / inf ----------------------------------------------------------------------------


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize(
    "fn",
    [M.seam_ratios, M.ps_score, M.detail_ratio, lambda t: M.map_metrics(t, t), lambda t: M.ssim_tiled(t, t)],
    ids=["seam", "ps", "detail", "map_metrics", "ssim"],
)
def test_non_finite_values_raise(fn, bad):
    img = periodic_noise(32, 32)
    img[3, 4, 1] = bad
    with pytest.raises(ValueError, match="1 non-finite"):
        fn(img)


def test_non_finite_source_raises():
    img = periodic_noise(32, 32)
    src = img.copy()
    src[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="source has 1 non-finite"):
        M.map_metrics(img, src)


# ---- pictures -----------------------------------------------------------------------------


def test_tile_2x2():
    img = load("cloth.png")
    t = M.tile_2x2(img)
    assert t.shape == (400, 400, 3)
    np.testing.assert_array_equal(t[200:, 200:], img)
    assert M.tile_2x2(img[..., 0]).shape == (400, 400)


def test_preview_uint8():
    rough = load("brick_roughness.png")
    p = M.preview_uint8(rough)
    assert p.shape == (256, 256, 3) and p.dtype == np.uint8
    np.testing.assert_array_equal(p[..., 0], p[..., 2])
    # Round trip of 8-bit file values: (2 v - 1 + 1) / 2 * 255 == v * 255.
    src = oiio.ImageBuf(str(TEXTURES / "brick_roughness.png")).get_pixels(oiio.UINT8)[..., 0]
    np.testing.assert_array_equal(p[..., 0], src)
    n = M.preview_uint8(load("brick_normal.png"), is_normal=True)
    assert n.shape == (256, 256, 3) and n[..., 2].mean() > 200  # mostly facing +z
    flat = M.preview_uint8(np.zeros((2, 2, 2)), is_normal=True)
    assert flat[0, 0].tolist() == [128, 128, 255]
    lin = M.preview_uint8(np.full((1, 1, 3), -0.5), linear=True)  # 0.25 linear -> 0.537 sRGB
    assert lin[0, 0, 0] == 137
    assert M.preview_uint8(np.array([[np.nan, np.inf]]))[0, :, 0].tolist() == [0, 255]
    assert M.preview_uint8(np.zeros((3, 3, 4))).shape == (3, 3, 3)


def test_centre_seam_ratio_sees_a_junction_at_the_centre_that_the_border_ratio_misses():
    rng = np.random.default_rng(3)
    smooth = np.cumsum(rng.normal(size=(64, 128)), axis=1)
    smooth = np.cumsum(smooth, axis=0)
    period = np.concatenate([smooth, smooth[:, ::-1]], axis=1)  # mirrored: continuous border
    period = np.concatenate([period, period[::-1]], axis=0)  # (128, 256), seamless both ways
    junction = np.roll(period, (0, 64), axis=(0, 1)).copy()
    junction[:, 128:] += 0.5 * np.abs(period).mean()  # a step at the centre column only
    m = M.map_metrics(junction)
    assert m["centre_seam_x"] > 2.0
    assert m["centre_seam_y"] < 1.5
    clean = M.map_metrics(period)
    assert clean["centre_seam_x"] < 1.5 and clean["centre_seam_y"] < 1.5
