"""Figures that compare a tile with its source: SSIM of the repeated tile, Gram distance, feature
scale and patch-distribution distance."""
from __future__ import annotations

from typing import Callable, Iterable

import numpy as np

from ..memo import ContentMemo
from .common import _prepare, _ratio, as_hwc

__all__ = ["tile_to", "ssim_tiled", "FeatureFn", "gram_matrix", "gram_distance", "mean_log_frequency",
           "kept_log_frequency", "scale_ratio", "patch_sw", "patch_distance", "source_halves", "SCALE_MAX_FREQUENCY"]

# --------------------------------------------------------------------------------------------
# Fidelity
# --------------------------------------------------------------------------------------------


def tile_to(tile: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """Repeat ``tile`` from its top-left corner and crop it to ``shape[:2]`` (Table 2 protocol)."""
    a = np.asarray(tile)
    h, w = shape[:2]
    reps = (-(-h // a.shape[0]), -(-w // a.shape[1])) + (1,) * (a.ndim - 2)
    return np.tile(a, reps)[:h, :w]


def ssim_tiled(
    tile: np.ndarray, source: np.ndarray, is_normal: bool = False, *, data_range: float = 2.0
) -> float:
    """SSIM between ``source`` and ``tile`` repeated to the source's size.

    Uses :func:`skimage.metrics.structural_similarity` (7x7 uniform window, per channel, then
    averaged). Normal maps are compared as unit vectors (``data_range`` 2).

    Parameters
    ----------
    tile, source : array_like
        ``(H, W)`` or ``(H, W, C)`` with the same channel count.
    data_range : float
        Value range: 2.0 for the network domain ``[-1, 1]``, 1.0 for file values.
    """
    from skimage.metrics import structural_similarity

    t = _prepare(tile, is_normal)
    s = _prepare(source, is_normal, "source")
    if t.shape[-1] != s.shape[-1]:
        raise ValueError(f"tile has {t.shape[-1]} channels, source {s.shape[-1]}")
    if min(s.shape[:2]) < 7:
        raise ValueError(f"SSIM needs a source of at least 7x7 px, got {s.shape[:2]}")
    t = tile_to(t, s.shape)
    rng = 2.0 if is_normal else data_range
    return float(structural_similarity(s, t, data_range=rng, channel_axis=-1))


FeatureFn = Callable[[np.ndarray], Iterable[np.ndarray]]


def gram_matrix(features: np.ndarray) -> np.ndarray:
    """Gram matrix ``F F^T / (h w)`` of one feature map.

    Parameters
    ----------
    features : array_like
        ``(K, h, w)`` (leading axes of length 1, e.g. a batch of one, are dropped).

    Returns
    -------
    numpy.ndarray
        ``(K, K)`` float64.
    """
    f = np.asarray(features, dtype=np.float64)
    while f.ndim > 3 and f.shape[0] == 1:
        f = f[0]
    if f.ndim != 3:
        raise ValueError(f"a feature map must be (K, h, w), got {f.shape}")
    k = f.shape[0]
    flat = f.reshape(k, -1)
    return flat @ flat.T / flat.shape[1]


def gram_distance(a: np.ndarray, b: np.ndarray, features: FeatureFn) -> float:
    """Relative Gram-statistics distance of ``a`` to the reference ``b``.

    ``mean over layers l of ||G_l(a) - G_l(b)||_F / ||G_l(b)||_F``, where ``G_l`` is the Gram
    matrix of the ``l``-th feature map returned by ``features``. 0 for identical statistics.

    Parameters
    ----------
    a, b : array_like
        ``(H, W, C)`` images (sizes may differ; Gram matrices do not depend on size).
    features : callable
        ``features(img) -> iterable of (K, h, w) arrays`` for an ``(H, W, C)`` float32 image,
        e.g. an adapter around the synthesis engine's default random multi-scale extractor.

    Returns
    -------
    float
        Mean relative Frobenius distance over layers.
    """
    fa = list(features(np.asarray(as_hwc(a, "image"), dtype=np.float32)))
    fb = list(features(np.asarray(as_hwc(b, "reference"), dtype=np.float32)))
    if not fa or len(fa) != len(fb):
        raise ValueError(f"features gave {len(fa)} and {len(fb)} layers; expected the same, > 0")
    dists = []
    for la, lb in zip(fa, fb):
        ga, gb = gram_matrix(la), gram_matrix(lb)
        dists.append(_ratio(float(np.linalg.norm(ga - gb)), float(np.linalg.norm(gb))))
    return float(np.mean(dists))




# --------------------------------------------------------------------------------------------
# Feature scale (spectral) and patch-distribution distance
# --------------------------------------------------------------------------------------------

#: Highest radial frequency (cycles per pixel) the feature-scale figure looks at (Nyquist).
SCALE_MAX_FREQUENCY = 0.5


#: Patch side and pyramid scales of :func:`patch_distance`.
PATCH_SIZE = 7
PATCH_SCALES = (1, 2, 4)


def _signal(img: np.ndarray, is_normal: bool) -> np.ndarray:
    """(H, W, C') float64 channels whose spectra describe the map: unit-normal x, y for normals."""
    u = _prepare(img, is_normal).astype(np.float64)
    return u[..., :2] if is_normal else u


def mean_log_frequency(img: np.ndarray, is_normal: bool = False,
                       max_frequency: float = SCALE_MAX_FREQUENCY) -> float:
    """Mean log radial frequency (cycles/px) of the image's gradient-weighted power spectrum.

    Each channel is mean-removed and Hann-windowed (so the border of a non-periodic source adds no
    spurious power); the power ``P(f)`` of all channels is summed and weighted by ``f`` (half-way
    to gradient energy, so neither the overall shading nor pixel noise dominates), over
    ``0 < f <= max_frequency``. Magnifying an image by ``m`` lowers the figure by about ``log m``;
    blurring lowers it too. Measured on real textures (brick, wood, cloth; 200-512 px): the two
    halves of one photo agree within 16 %, a 2x bilinear magnification scores 0.37-0.49.
    """
    u = _signal(img, is_normal)
    h, w = u.shape[:2]
    if min(h, w) < 8:
        raise ValueError(f"image {h}x{w} is too small for a spectrum (need at least 8x8)")
    window = np.outer(np.hanning(h), np.hanning(w))[..., None]
    u = (u - u.mean(axis=(0, 1), keepdims=True)) * window
    power = (np.abs(np.fft.rfft2(u, axes=(0, 1))) ** 2).sum(axis=-1)  # (H, W//2+1)
    fy = np.fft.fftfreq(h)[:, None]
    fx = np.fft.rfftfreq(w)[None, :]
    f = np.sqrt(fy ** 2 + fx ** 2)
    band = (f > 0) & (f <= max_frequency)
    weight = power[band] * f[band]
    total = weight.sum()
    if total <= 0:  # a constant image: no features at all
        return float(np.log(max_frequency))
    return float((weight * np.log(f[band])).sum() / total)


def scale_ratio(tile: np.ndarray, source: np.ndarray, is_normal: bool = False) -> float:
    """Feature-scale / sharpness ratio of ``tile`` against ``source``.

    ``exp(mean_log_frequency(tile) - mean_log_frequency(source))``: about 1 when the tile keeps the
    source's feature size and crispness, about 0.5 when its features are magnified 2x or blurred
    away, above 1 when they shrink or noise is invented.

    >>> rng = np.random.default_rng(0)
    >>> img = rng.normal(size=(128, 128))
    >>> round(scale_ratio(img, img), 3)
    1.0
    """
    return float(np.exp(kept_log_frequency(tile, is_normal) - kept_log_frequency(source, is_normal)))


#: Each picture's mean log frequency, by its content: the verdict and the report measure the same tile
#: against the same source, and the source's scale tolerance measures it against each of its quarters.
_LOG_FREQUENCIES: ContentMemo[float] = ContentMemo()


def kept_log_frequency(img: np.ndarray, is_normal: bool = False) -> float:
    """:func:`mean_log_frequency` at the default band, computed once per picture (by content) and kept."""
    return _LOG_FREQUENCIES.get((img,), (is_normal, SCALE_MAX_FREQUENCY), lambda: mean_log_frequency(img, is_normal))


def _patches(u: np.ndarray, count: int, rng: np.random.Generator, size: int = PATCH_SIZE) -> np.ndarray:
    """Up to ``count`` random ``size`` x ``size`` patches of ``u`` (H, W, C), flattened: (N, size*size*C)."""
    h, w = u.shape[:2]
    ny, nx = h - size + 1, w - size + 1
    n = min(count, ny * nx)
    idx = rng.choice(ny * nx, size=n, replace=False)
    ys, xs = np.divmod(idx, nx)
    offs = np.arange(size)
    rows = (ys[:, None] + offs[None, :])[:, :, None]  # (N, size, 1)
    cols = (xs[:, None] + offs[None, :])[:, None, :]  # (N, 1, size)
    return u[rows, cols].reshape(n, -1)


def _quantiles(sorted_proj: np.ndarray, count: int) -> np.ndarray:
    """(count, K) quantiles of sorted projections (N, K) at evenly spaced levels."""
    n = len(sorted_proj)
    if n == count:
        return sorted_proj
    pos = np.linspace(0.0, n - 1, count)
    lo = np.floor(pos).astype(int)
    hi = np.minimum(lo + 1, n - 1)
    t = (pos - lo)[:, None]
    return sorted_proj[lo] * (1 - t) + sorted_proj[hi] * t


def _sliced_wasserstein(a: np.ndarray, b: np.ndarray, directions: np.ndarray) -> float:
    """Sliced 2-Wasserstein distance between point sets ``a`` (N, D) and ``b`` (M, D). The projections are
    sorted as float32 (the sort is most of the cost; half as long) and compared in float64: the distance
    moves by a few parts in 10^8."""
    pa = np.sort((a @ directions).astype(np.float32), axis=0)
    pb = np.sort((b @ directions).astype(np.float32), axis=0)
    count = max(len(pa), len(pb))
    diff = _quantiles(pa, count).astype(np.float64) - _quantiles(pb, count)
    return float(np.sqrt(np.mean(diff * diff)))


def _box_means(u: np.ndarray, sides: set[int]) -> dict[int, np.ndarray]:
    """``{s: m}``: the mean of every ``s`` x ``s`` window of ``u``, ``m[i, j]`` over the window whose
    top-left texel is ``(i, j)`` (from summed-area tables). Any grid's box-downsampled image is a
    strided slice of one of them: ``m[py::s, px::s]`` is ``u[py:, px:]`` downsampled ``s`` times."""
    table = np.pad(u.cumsum(0).cumsum(1), ((1, 0), (1, 0), (0, 0)))
    return {s: (table[s:, s:] - table[:-s, s:] - table[s:, :-s] + table[:-s, :-s]) / (s * s) for s in sides}


def _band_level(boxes: dict[int, np.ndarray], scales: tuple[int, ...], level: int, phase: tuple[int, int]
                ) -> np.ndarray:
    """One Laplacian-pyramid style level of an image, on its box grid shifted by ``phase`` px
    (``boxes``: its :func:`_box_means`): for each scale ``s`` but the last, the detail of the
    ``s``-downsampled image (minus its 2x2 box average brought back up); the last is the low-pass
    image. Detail levels carry fine structure (what blur removes and checkerboards add) without being
    drowned by the colour variation the low-pass level measures."""
    py, px = phase
    s = scales[level]
    d = boxes[s][py::s, px::s]
    if level < len(scales) - 1:
        coarse = boxes[2 * s][py::2 * s, px::2 * s]
        up = np.repeat(np.repeat(coarse, 2, 0), 2, 1)
        d = d[: up.shape[0], : up.shape[1]] - up
    return d


def _phase_patches(boxes: dict[int, np.ndarray], scales: tuple[int, ...], level: int, samples: int,
                   rng: np.random.Generator) -> np.ndarray | None:
    """About ``samples`` random patches of one pyramid level (:func:`_band_level`), drawn evenly from
    the level computed on every phase of its box grid (shifted by 0 .. m - 1 px along each axis, m
    the grid's period in px): the box filters of a single grid see a sharp edge differently at each
    offset, so a plain crop of a periodic source read 2-3x its own half-vs-half figure at some offsets
    and under 1 at others. None when the level is too small for patches."""
    period = scales[level] * (2 if level < len(scales) - 1 else 1)
    per_phase = -(-samples // period ** 2)
    out = []
    for py in range(period):
        for px in range(period):
            d = _band_level(boxes, scales, level, (py, px))
            if min(d.shape[:2]) < 2 * PATCH_SIZE:
                return None
            out.append(_patches(d, per_phase, rng))
    return np.concatenate(out)


def _level_distances(a: np.ndarray, b: np.ndarray, is_normal: bool, samples: int, directions: int,
                     scales: tuple[int, ...], seed: int) -> list[float | None]:
    ua, ub = _signal(a, is_normal), _signal(b, is_normal)
    if ua.shape[-1] != ub.shape[-1]:
        raise ValueError(f"channel counts differ: {ua.shape[-1]} vs {ub.shape[-1]}")
    sides = {s for s in scales} | {2 * s for s in scales[:-1]}
    if min(ua.shape[:2] + ub.shape[:2]) < max(sides):
        return [None] * len(scales)
    boxes_a, boxes_b = _box_means(ua, sides), _box_means(ub, sides)
    out: list[float | None] = []
    for level in range(len(scales)):
        rng = np.random.default_rng([seed, level])  # same directions for every pair at this level
        dirs = rng.normal(size=(PATCH_SIZE * PATCH_SIZE * ua.shape[-1], directions))
        dirs /= np.linalg.norm(dirs, axis=0, keepdims=True)
        pa = _phase_patches(boxes_a, scales, level, samples, rng)
        pb = None if pa is None else _phase_patches(boxes_b, scales, level, samples, rng)
        out.append(None if pb is None else _sliced_wasserstein(pa, pb, dirs))
    return out


def patch_sw(a: np.ndarray, b: np.ndarray, is_normal: bool = False, *, samples: int = 4096,
             directions: int = 64, scales: tuple[int, ...] = PATCH_SCALES, seed: int = 0) -> list[float | None]:
    """Sliced Wasserstein distances between the 7x7 patch distributions of ``a`` and ``b``, one per
    pyramid level (:func:`_band_level`, pooled over the phases of its box grid; None where a level is
    too small for patches)."""
    return _level_distances(a, b, is_normal, samples, directions, scales, seed)


def source_halves(source: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two halves of ``source`` across its longer side."""
    s = np.asarray(source)
    if s.shape[1] >= s.shape[0]:
        half = s.shape[1] // 2
        return s[:, :half], s[:, half: 2 * half]
    half = s.shape[0] // 2
    return s[:half], s[half: 2 * half]


def patch_distance(tile: np.ndarray, source: np.ndarray, is_normal: bool = False, *, seed: int = 0) -> float:
    """Patch-distribution distance of ``tile`` to ``source``, in units of the source's own variation.

    Per pyramid level, :func:`patch_sw` (tile, source) divided by the same between the two halves
    of the source; the mean over levels. About 1 or below for a tile made of the source's own patches in their variety; blur,
    checkerboards, invented detail and lost variety all raise it.
    """
    return _PATCH_DISTANCES.get((tile, source), (is_normal, seed), lambda: _patch_distance(tile, source, is_normal, seed))


#: Patch distances, and each source's own half-vs-half figures, kept by the arrays' content: the verdict and
#: the report measure the same tile, and seeds, candidates and duplicated stacks the same source.
_PATCH_DISTANCES: ContentMemo[float] = ContentMemo()
_OWN_SPREAD: ContentMemo[list[float | None]] = ContentMemo()


def _patch_distance(tile: np.ndarray, source: np.ndarray, is_normal: bool, seed: int) -> float:
    own = _OWN_SPREAD.get((source,), (is_normal, seed), lambda: patch_sw(*source_halves(source), is_normal, seed=seed))
    d = patch_sw(tile, source, is_normal, seed=seed)
    ratios = [_ratio(x, o) for x, o in zip(d, own) if x is not None and o is not None]
    if not ratios:
        raise ValueError(f"tile {np.shape(tile)[:2]} and source {np.shape(source)[:2]} are too small for "
                         f"{PATCH_SIZE}x{PATCH_SIZE} patches")
    return float(np.mean(ratios))
