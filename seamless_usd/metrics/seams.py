"""Seam figures that compare a tile with itself: seam ratios across the border and the centre lines,
the periodic-plus-smooth score, detail ratios in the seam bands."""
from __future__ import annotations

import numpy as np

from .common import BAND_FRACTION, HIGHPASS_SIGMA, _prepare, _ratio, as_hwc

__all__ = ["seam_ratios", "centre_seam_ratios", "periodic_smooth_decomposition", "ps_score", "seam_band_mask",
           "centre_band_mask", "highpass", "detail_ratio"]

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




def centre_seam_ratios(tile: np.ndarray, is_normal: bool = False) -> dict[str, float]:
    """Seam ratios across the tile's centre lines (row ``H/2``, column ``W/2``), per axis.

    SeamlessGAN's latent copies meet there (the tile is one period of the tiled latent, centred
    on the junction, as the paper crops it), so a junction artefact shows here while the border
    stays continuous. Computed as :func:`seam_ratios` of the tile rolled by half its size, so the
    figures compare with the border ratios; about 1 when the centre lines are not seams.

    A ramp jumps back at its border; rolled by half, at its centre:

    >>> ramp = np.tile(np.arange(10.0), (4, 1))
    >>> round(centre_seam_ratios(np.roll(ramp, 5, axis=1))["centre_seam_x"], 1)
    9.0
    >>> round(centre_seam_ratios(ramp)["centre_seam_x"], 1)  # its one jump is now inside the tile
    0.5
    """
    u = _prepare(tile, is_normal)
    rolled = np.roll(u, (u.shape[0] // 2, u.shape[1] // 2), axis=(0, 1))
    r = seam_ratios(rolled, is_normal)
    return {"centre_seam_x": r["seam_ratio_x"], "centre_seam_y": r["seam_ratio_y"]}
