"""Seamlessness and fidelity metrics for texture tiles (numpy only).

Used by the process report (per-map seam figures) and by ``benchmarks/quality.py``.

Conventions
-----------
Value domain
    Every function takes a tile as a float array of shape ``(H, W)`` or ``(H, W, C)``. The
    *network domain* is ``[-1, 1]`` (file value ``v`` in ``[0, 1]`` maps to ``2 v - 1``); it is
    what :mod:`seamless_usd.synthesis` produces and what the benchmark feeds in. The seam,
    periodic-plus-smooth and detail figures are ratios, so they do not depend on an affine change
    of the values: file values in ``[0, 1]`` give the same numbers. Only SSIM needs the value range
    (``data_range``, 2.0 for the network domain, 1.0 for file values).
Normal maps
    With ``is_normal=True`` the tile holds tangent-space normal *vectors* in ``[-1, 1]`` (the
    network domain; decode a ``[0, 1]`` file with ``2 v - 1`` first), with 2 channels (x, y; z is
    rebuilt as ``sqrt(1 - x^2 - y^2)``) or 3 channels. They are normalised to unit length, and
    differences between neighbours are measured as the angle between the unit normals.
Axes
    ``x`` names the seam met when walking horizontally across the tile's left/right border
    (between column ``W - 1`` and column ``0``), ``y`` the one met walking vertically across the
    top/bottom border (between row ``H - 1`` and row ``0``). These are exactly the seams of the
    2x2 tiling of the tile.
Non-finite values
    NaN or infinite pixels make every metric undefined: each function raises ``ValueError``
    saying how many there are. A ratio whose numerator and denominator are both zero (a constant
    image) is 1.0; a non-zero numerator over a zero denominator is ``inf``.

Metrics
-------
seam ratio (:func:`seam_ratios`)
    mean |wrap-around neighbour difference| / mean |interior neighbour difference|, per axis, and
    the same with second differences. About 1 for a tileable image, well above 1 across a seam.
periodic-plus-smooth score (:func:`ps_score`)
    Moisan (2011) splits ``u = p + s`` into a periodic part ``p`` and a smooth part ``s`` carrying
    the border discontinuities; the score is ``||s|| / ||u - mean(u)||`` (near 0 when tileable).
detail ratio (:func:`detail_ratio`)
    RMS of the high-pass image (``u`` minus its periodic Gaussian blur) inside the seam bands over
    the same outside them. A blurred seam (crossfade) gives < 1, a hard seam > 1.
fidelity (:func:`ssim_tiled`, :func:`gram_distance`)
    SSIM between the source and the tile repeated to the source's size (the SeamlessGAN paper's
    Table 2 protocol), and a Gram-statistics distance under a caller-given feature extractor.

Reference: L. Moisan, "Periodic plus smooth image decomposition", J. Math. Imaging Vis. 39 (2011).
"""
from __future__ import annotations

from typing import Callable, Iterable

import numpy as np

__all__ = [
    "METRIC_KEYS",
    "BAND_FRACTION",
    "HIGHPASS_SIGMA",
    "as_hwc",
    "unit_normals",
    "seam_ratios",
    "centre_seam_ratios",
    "periodic_smooth_decomposition",
    "ps_score",
    "seam_band_mask",
    "centre_band_mask",
    "highpass",
    "detail_ratio",
    "tile_to",
    "ssim_tiled",
    "gram_matrix",
    "gram_distance",
    "map_metrics",
    "tile_2x2",
    "preview_uint8",
]

#: Keys of :func:`map_metrics`' result, in a stable order (also the benchmark's table columns).
METRIC_KEYS: tuple[str, ...] = (
    "seam_ratio_x",
    "seam_ratio_y",
    "seam_ratio2_x",
    "seam_ratio2_y",
    "centre_seam_x",
    "centre_seam_y",
    "ps_score",
    "detail_ratio",
    "detail_ratio_centre",
    "ssim",
    "gram_distance",
)

#: Half-width of a seam band as a fraction of the tile's size along the crossing axis: the band
#: around each seam spans 2 x 10% = 20% of the size, the width of the bands the synthesis quality
#: function Q inspects.
BAND_FRACTION = 0.1

#: Standard deviation (px) of the Gaussian whose periodic blur is removed to get the high-pass
#: image: fine detail (about 2-6 px wavelengths) is what a crossfade or a blurry join destroys.
HIGHPASS_SIGMA = 1.5


# --------------------------------------------------------------------------------------------
# Input checks and conversions
# --------------------------------------------------------------------------------------------


def as_hwc(img: np.ndarray, name: str = "tile") -> np.ndarray:
    """Return ``img`` as a finite float64 array of shape ``(H, W, C)``.

    Parameters
    ----------
    img : array_like
        ``(H, W)`` or ``(H, W, C)`` values.
    name : str
        What to call the array in error messages.

    Raises
    ------
    ValueError
        On another number of dimensions, a side shorter than 3 px, no channel, or NaN/inf values.

    Examples
    --------
    >>> as_hwc(np.zeros((4, 5))).shape
    (4, 5, 1)
    """
    a = np.asarray(img, dtype=np.float64)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3:
        raise ValueError(f"{name} must have shape (H, W) or (H, W, C), got {a.shape}")
    h, w, c = a.shape
    if h < 3 or w < 3 or c < 1:
        raise ValueError(f"{name} must be at least 3x3 px with one channel, got {a.shape}")
    bad = int(a.size - np.count_nonzero(np.isfinite(a)))
    if bad:
        raise ValueError(f"{name} has {bad} non-finite values (NaN/inf); metrics are undefined")
    return a


def unit_normals(img: np.ndarray) -> np.ndarray:
    """Unit tangent-space normals ``(H, W, 3)`` from network-domain vectors.

    Parameters
    ----------
    img : array_like
        ``(H, W, 2)`` (x, y; z rebuilt as ``sqrt(max(0, 1 - x^2 - y^2))``) or ``(H, W, 3)``
        vectors in ``[-1, 1]``.

    Returns
    -------
    numpy.ndarray
        Vectors of unit length; a zero vector becomes ``(0, 0, 1)``.
    """
    a = as_hwc(img, "normal map")
    if a.shape[-1] == 2:
        z = np.sqrt(np.clip(1.0 - a[..., 0] ** 2 - a[..., 1] ** 2, 0.0, None))
        a = np.concatenate([a, z[..., None]], axis=-1)
    elif a.shape[-1] != 3:
        raise ValueError(f"a normal map needs 2 or 3 channels, got {a.shape[-1]}")
    n = np.linalg.norm(a, axis=-1, keepdims=True)
    flat = n[..., 0] < 1e-12
    a = a / np.where(n < 1e-12, 1.0, n)
    a[flat] = (0.0, 0.0, 1.0)
    return a


def _prepare(img: np.ndarray, is_normal: bool, name: str = "tile") -> np.ndarray:
    return unit_normals(img) if is_normal else as_hwc(img, name)


def _ratio(num: float, den: float) -> float:
    if den > 0:
        return float(num / den)
    return 1.0 if num == 0 else float("inf")


# --------------------------------------------------------------------------------------------
# Seam ratios
# --------------------------------------------------------------------------------------------


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (radians) between unit vectors along the last axis; stable near 0 and pi."""
    # atan2(|a x b|, a . b) keeps precision for small angles, unlike arccos(a . b).
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    return np.arctan2(cross, np.sum(a * b, axis=-1))


def _first_diffs(u: np.ndarray, axis: int, is_normal: bool) -> tuple[np.ndarray, np.ndarray]:
    """(wrap, interior) first-difference magnitudes along ``axis`` (0 rows, 1 columns)."""
    first = np.take(u, [0], axis=axis)
    last = np.take(u, [-1], axis=axis)
    lo = np.take(u, np.arange(u.shape[axis] - 1), axis=axis)
    hi = np.take(u, np.arange(1, u.shape[axis]), axis=axis)
    if is_normal:
        return _angle(first, last), _angle(lo, hi)
    return np.abs(first - last), np.abs(hi - lo)


def _second_diffs(u: np.ndarray, axis: int, is_normal: bool) -> tuple[np.ndarray, np.ndarray]:
    """(wrap, interior) second-difference magnitudes along ``axis``.

    The wrap terms are the two second differences centred on the border pixels (``u[-1], u[0],
    u[1]`` and ``u[-2], u[-1], u[0]``); the interior ones those centred on pixels 1 .. n-2. For
    normals the magnitude is the Euclidean length of the second difference of the unit vectors,
    which equals the change of angle for small rotations (in radians).
    """
    n = u.shape[axis]
    r = np.roll(u, 1, axis=axis)  # r[i] = u[i - 1]
    f = np.roll(u, -1, axis=axis)  # f[i] = u[i + 1]
    d2 = f - 2.0 * u + r
    mag = np.linalg.norm(d2, axis=-1) if is_normal else np.abs(d2)
    wrap = np.take(mag, [0, n - 1], axis=axis)
    interior = np.take(mag, np.arange(1, n - 1), axis=axis)
    return wrap, interior


def seam_ratios(tile: np.ndarray, is_normal: bool = False) -> dict[str, float]:
    """Seam ratios of a tile across its wrap-around borders, per axis.

    ``seam_ratio_x`` = mean |u[:, 0] - u[:, W-1]| / mean |u[:, j+1] - u[:, j]| (all rows and
    channels), ``seam_ratio_y`` the same across rows; ``seam_ratio2_*`` use second differences
    (see :func:`_second_diffs`). For normal maps the difference of two neighbours is the angle
    between their unit normals.

    Parameters
    ----------
    tile : array_like
        ``(H, W)`` or ``(H, W, C)``; any affine value domain (the ratio does not depend on it).
    is_normal : bool
        Whether the tile holds normal vectors (see the module notes).

    Returns
    -------
    dict
        ``seam_ratio_x``, ``seam_ratio_y``, ``seam_ratio2_x``, ``seam_ratio2_y``: about 1 for a
        tileable tile, well above 1 across a visible seam.

    Examples
    --------
    White noise is periodic in distribution; a ramp jumps back at the border:

    >>> noise = np.random.default_rng(0).uniform(size=(256, 256))
    >>> 0.8 < seam_ratios(noise)["seam_ratio_x"] < 1.2
    True
    >>> round(seam_ratios(np.tile(np.arange(10.0), (4, 1)))["seam_ratio_x"], 1)
    9.0
    """
    u = _prepare(tile, is_normal)
    out: dict[str, float] = {}
    for axis, label in ((1, "x"), (0, "y")):
        wrap, interior = _first_diffs(u, axis, is_normal)
        out[f"seam_ratio_{label}"] = _ratio(wrap.mean(), interior.mean())
    for axis, label in ((1, "x"), (0, "y")):
        wrap, interior = _second_diffs(u, axis, is_normal)
        out[f"seam_ratio2_{label}"] = _ratio(wrap.mean(), interior.mean())
    return out


# --------------------------------------------------------------------------------------------
# Periodic plus smooth decomposition (Moisan 2011)
# --------------------------------------------------------------------------------------------


def periodic_smooth_decomposition(img: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split an image into periodic and smooth components, ``u = p + s`` (Moisan 2011).

    ``s`` solves ``laplacian(s) = v`` with periodic boundary conditions, where ``v`` is the
    boundary image holding the jumps across the wrap-around borders, and has zero mean; it is
    computed per channel in the Fourier domain:
    ``s_hat(q, r) = v_hat(q, r) / (2 cos(2 pi q / H) + 2 cos(2 pi r / W) - 4)``, ``s_hat(0, 0) = 0``.

    Parameters
    ----------
    img : array_like
        ``(H, W)`` or ``(H, W, C)`` finite values.

    Returns
    -------
    p, s : numpy.ndarray
        Periodic and smooth components, each of the input's shape (float64).
    """
    shape = np.shape(img)
    u = as_hwc(img, "image")
    h, w, _ = u.shape
    v = np.zeros_like(u)
    top_bottom = u[-1] - u[0]  # (W, C)
    left_right = u[:, -1] - u[:, 0]  # (H, C)
    v[0] += top_bottom
    v[-1] -= top_bottom
    v[:, 0] += left_right
    v[:, -1] -= left_right
    q = np.arange(h)[:, None]
    r = np.arange(w)[None, :]
    den = 2.0 * np.cos(2.0 * np.pi * q / h) + 2.0 * np.cos(2.0 * np.pi * r / w) - 4.0
    den[0, 0] = 1.0  # the mean of s is set to 0 below
    v_hat = np.fft.fft2(v, axes=(0, 1))
    s_hat = v_hat / den[..., None]
    s_hat[0, 0] = 0.0
    s = np.real(np.fft.ifft2(s_hat, axes=(0, 1)))
    p = u - s
    return p.reshape(shape), s.reshape(shape)


def ps_score(tile: np.ndarray, is_normal: bool = False) -> float:
    """Periodic-plus-smooth score ``||s|| / ||u - mean(u)||`` (0 for a perfectly periodic tile).

    Norms are Euclidean over all pixels and channels; for normal maps ``u`` is the unit-normal
    vector field. A constant tile scores 0.

    Parameters
    ----------
    tile : array_like
        ``(H, W)`` or ``(H, W, C)``.
    is_normal : bool
        Whether the tile holds normal vectors.

    Returns
    -------
    float
        Energy share of the border discontinuities: near 0 when tileable.
    """
    u = _prepare(tile, is_normal)
    _, s = periodic_smooth_decomposition(u)
    centred = u - u.mean(axis=(0, 1), keepdims=True)
    den = float(np.linalg.norm(centred))
    num = float(np.linalg.norm(s))
    return 0.0 if den == 0 else num / den


# --------------------------------------------------------------------------------------------
# Detail ratio
# --------------------------------------------------------------------------------------------


def _band_1d(n: int, half_width: float, centre: bool) -> np.ndarray:
    """Pixels within ``half_width`` px of the wrap seam (or of the centre line) along one axis."""
    i = np.arange(n) + 0.5  # pixel centres; the wrap seam is at 0 == n, the centre line at n / 2
    if centre:
        dist = np.abs(i - n / 2.0)
    else:
        dist = np.minimum(i, n - i)
    return dist < half_width


def seam_band_mask(shape: tuple[int, ...], band: float = BAND_FRACTION) -> np.ndarray:
    """Boolean ``(H, W)`` mask of the seam bands of a tile.

    The seams of the 2x2 tiling of an ``H x W`` tile are its wrap-around borders. A pixel whose
    centre lies less than ``band * W`` px from the left/right border (or ``band * H`` px from the
    top/bottom border) is in a band, so each band spans ``2 * band`` of the size, centred on the
    seam as seen in the tiled view.

    Parameters
    ----------
    shape : tuple
        The tile's shape; only ``H, W`` are used.
    band : float
        Half-width of a band as a fraction of the size, in ``(0, 0.25]``.
    """
    h, w = shape[:2]
    if not 0 < band <= 0.25:
        raise ValueError(f"band must be in (0, 0.25], got {band}")
    return _band_1d(h, band * h, False)[:, None] | _band_1d(w, band * w, False)[None, :]


def centre_band_mask(shape: tuple[int, ...], band: float = BAND_FRACTION) -> np.ndarray:
    """Boolean ``(H, W)`` mask of the vertical and horizontal bands through the tile's centre.

    SeamlessGAN builds a tile from a 2x2-repeated latent, so the joins of the latent copies fall
    on the tile's centre lines (the bands the quality function Q checks), not on its borders. The
    bands are defined as in :func:`seam_band_mask`, around ``x = W / 2`` and ``y = H / 2``.
    """
    h, w = shape[:2]
    if not 0 < band <= 0.25:
        raise ValueError(f"band must be in (0, 0.25], got {band}")
    return _band_1d(h, band * h, True)[:, None] | _band_1d(w, band * w, True)[None, :]


def highpass(img: np.ndarray, sigma: float = HIGHPASS_SIGMA) -> np.ndarray:
    """``u`` minus its periodic Gaussian blur (FFT), so the high-pass sees the tiled view.

    Parameters
    ----------
    img : array_like
        ``(H, W)`` or ``(H, W, C)`` finite values.
    sigma : float
        Gaussian standard deviation in px (> 0).

    Returns
    -------
    numpy.ndarray
        ``(H, W, C)`` float64 high-pass image (zero mean per channel).
    """
    if sigma <= 0:
        raise ValueError(f"sigma must be > 0, got {sigma}")
    u = as_hwc(img, "image")
    h, w, _ = u.shape
    fy = np.fft.fftfreq(h)[:, None]
    fx = np.fft.fftfreq(w)[None, :]
    gauss = np.exp(-2.0 * (np.pi * sigma) ** 2 * (fx**2 + fy**2))
    blurred = np.real(np.fft.ifft2(np.fft.fft2(u, axes=(0, 1)) * gauss[..., None], axes=(0, 1)))
    return u - blurred


def detail_ratio(
    tile: np.ndarray,
    is_normal: bool = False,
    *,
    band: float = BAND_FRACTION,
    sigma: float = HIGHPASS_SIGMA,
    where: str = "seams",
) -> float:
    """High-pass RMS inside the seam bands over the same outside them.

    The high-pass image is :func:`highpass` of the tile (of the unit-normal vectors for normal
    maps), pooled over channels. ``where="seams"`` uses :func:`seam_band_mask` (the borders,
    where the 2x2 tiling's seams fall: what a border crossfade blurs); ``where="centre"`` uses
    :func:`centre_band_mask` (where SeamlessGAN's latent copies join).

    Returns
    -------
    float
        About 1 when detail is even; < 1 for a blurred seam, > 1 for a hard seam (its step adds
        high frequencies). A linear crossfade mixes two unrelated signals with weights ``a`` and
        ``1 - a``, which scales their high-pass RMS by ``sqrt(a^2 + (1 - a)^2)`` (0.71 at the
        middle of the blend, 0.82 averaged over it); as its blend covers only part of the default
        bands, a crossfade over 1/8 of the size measures about 0.85-0.95 on real maps.
    """
    masks = {"seams": seam_band_mask, "centre": centre_band_mask}
    if where not in masks:
        raise ValueError(f"where must be one of {sorted(masks)}, got {where!r}")
    u = _prepare(tile, is_normal)
    inside = masks[where](u.shape, band)
    energy = np.sum(highpass(u, sigma) ** 2, axis=-1)  # (H, W)
    return _ratio(np.sqrt(energy[inside].mean()), np.sqrt(energy[~inside].mean()))


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


def centre_seam_ratios(tile: np.ndarray, is_normal: bool = False) -> dict[str, float]:
    """Seam ratios across the tile's centre lines (row ``H/2``, column ``W/2``), per axis.

    SeamlessGAN's latent copies meet there (the tile is one period of the tiled latent, centred
    on the junction, as the paper crops it), so a junction artefact shows here while the border
    stays continuous. Computed as :func:`seam_ratios` of the tile rolled by half its size, so the
    figures compare with the border ratios; about 1 when the centre lines are not seams.

    >>> ramp = np.tile(np.arange(10.0), (4, 1))  # a jump at the border, none at the centre
    >>> round(centre_seam_ratios(ramp)["centre_seam_x"], 1)
    1.0
    """
    u = _prepare(tile, is_normal)
    rolled = np.roll(u, (u.shape[0] // 2, u.shape[1] // 2), axis=(0, 1))
    r = seam_ratios(rolled, is_normal)
    return {"centre_seam_x": r["seam_ratio_x"], "centre_seam_y": r["seam_ratio_y"]}


# --------------------------------------------------------------------------------------------
# Everything at once
# --------------------------------------------------------------------------------------------


def map_metrics(
    tile: np.ndarray,
    source: np.ndarray | None = None,
    is_normal: bool = False,
    *,
    features: FeatureFn | None = None,
    data_range: float = 2.0,
    band: float = BAND_FRACTION,
    sigma: float = HIGHPASS_SIGMA,
) -> dict[str, float | None]:
    """All metrics of one map's tile, keyed by :data:`METRIC_KEYS` (in that order).

    Parameters
    ----------
    tile : array_like
        The tileable output ``(H, W)`` or ``(H, W, C)``, network domain ``[-1, 1]``.
    source : array_like, optional
        The input map in the same domain; without it ``ssim`` and ``gram_distance`` are None.
    is_normal : bool
        Whether the map holds normal vectors.
    features : callable, optional
        Feature extractor for :func:`gram_distance`; without it ``gram_distance`` is None.
        Normal maps are passed to it as unit vectors.
    data_range : float
        SSIM value range (2.0 for the network domain).
    band, sigma : float
        Seam band half-width fraction and high-pass sigma (see :func:`detail_ratio`).

    Returns
    -------
    dict
        ``seam_ratio_x``, ``seam_ratio_y``, ``seam_ratio2_x``, ``seam_ratio2_y``,
        ``centre_seam_x``, ``centre_seam_y`` (across the centre lines), ``ps_score``,
        ``detail_ratio`` (seam bands), ``detail_ratio_centre`` (centre bands), ``ssim``,
        ``gram_distance``.

    Raises
    ------
    ValueError
        On NaN/inf values or unusable shapes.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> m = map_metrics(rng.uniform(-1, 1, (32, 32, 3)), rng.uniform(-1, 1, (48, 48, 3)))
    >>> list(m) == list(METRIC_KEYS)
    True
    """
    u = _prepare(tile, is_normal)
    out: dict[str, float | None] = dict.fromkeys(METRIC_KEYS)
    out.update(seam_ratios(u, is_normal))
    out.update(centre_seam_ratios(u, is_normal))
    out["ps_score"] = ps_score(u)
    out["detail_ratio"] = detail_ratio(u, band=band, sigma=sigma, where="seams")
    out["detail_ratio_centre"] = detail_ratio(u, band=band, sigma=sigma, where="centre")
    if source is not None:
        s = _prepare(source, is_normal, "source")
        out["ssim"] = ssim_tiled(u, s, data_range=2.0 if is_normal else data_range)
        if features is not None:
            out["gram_distance"] = gram_distance(tile_to(u, s.shape), s, features)
    return out


# --------------------------------------------------------------------------------------------
# Pictures
# --------------------------------------------------------------------------------------------


def tile_2x2(img: np.ndarray) -> np.ndarray:
    """The 2x2 tiling of an image: ``(H, W[, C])`` to ``(2H, 2W[, C])``.

    Examples
    --------
    >>> tile_2x2(np.arange(4).reshape(2, 2)).tolist()
    [[0, 1, 0, 1], [2, 3, 2, 3], [0, 1, 0, 1], [2, 3, 2, 3]]
    """
    a = np.asarray(img)
    if a.ndim not in (2, 3):
        raise ValueError(f"expected (H, W) or (H, W, C), got {a.shape}")
    return np.tile(a, (2, 2) + (1,) * (a.ndim - 2))


def _srgb_encode(x: np.ndarray) -> np.ndarray:
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0.0031308), 1 / 2.4) - 0.055)


def preview_uint8(img: np.ndarray, is_normal: bool = False, *, linear: bool = False) -> np.ndarray:
    """An ``(H, W, 3)`` uint8 display picture of a network-domain map.

    Values ``x`` in ``[-1, 1]`` go to ``(x + 1) / 2`` in ``[0, 1]``. Colour maps are shown as
    their values (already display-encoded when the map is sRGB); with ``linear=True`` the sRGB
    transfer function is applied first, for linear-light colour. One channel is shown as grey,
    two as (R, G, 0), four and more by their first three (alpha is dropped). Normal maps are
    renormalised (z rebuilt for two channels) and shown in the usual ``n / 2 + 1/2`` colours.
    NaN shows as black, +/-inf as the clipped extreme.

    Parameters
    ----------
    img : array_like
        ``(H, W)`` or ``(H, W, C)`` in ``[-1, 1]``.
    is_normal : bool
        Whether the map holds normal vectors.
    linear : bool
        Whether colour values are linear light (then sRGB-encoded for display).

    Examples
    --------
    >>> preview_uint8(np.array([[-1.0, 0.0, 1.0]]))[0, :, 0].tolist()
    [0, 128, 255]
    """
    a = np.asarray(img, dtype=np.float64)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3:
        raise ValueError(f"expected (H, W) or (H, W, C), got {a.shape}")
    a = np.nan_to_num(a, nan=-1.0, posinf=1.0, neginf=-1.0)
    if is_normal:
        n = np.clip(a, -1.0, 1.0)
        if n.shape[-1] == 2:
            z = np.sqrt(np.clip(1.0 - n[..., 0] ** 2 - n[..., 1] ** 2, 0.0, None))
            n = np.concatenate([n, z[..., None]], axis=-1)
        n = n[..., :3]
        length = np.linalg.norm(n, axis=-1, keepdims=True)
        rgb = np.where(length > 1e-12, n / np.where(length > 1e-12, length, 1.0), 0.0) * 0.5 + 0.5
    else:
        c = a.shape[-1]
        if c == 1:
            a = np.repeat(a, 3, axis=-1)
        elif c == 2:
            a = np.concatenate([a, np.full(a.shape[:2] + (1,), -1.0)], axis=-1)
        rgb = np.clip((a[..., :3] + 1.0) * 0.5, 0.0, 1.0)
        if linear:
            rgb = _srgb_encode(rgb)
    return np.clip(np.rint(rgb * 255.0), 0, 255).astype(np.uint8)
