"""Input checks and conversions shared by the metrics."""
from __future__ import annotations

import numpy as np

__all__ = ["as_hwc", "unit_normals", "BAND_FRACTION", "HIGHPASS_SIGMA"]

#: Half-width of a seam band as a fraction of the tile's size along the crossing axis: the band
#: around each seam spans 2 x 10% = 20% of the size, the width of the bands the synthesis quality
#: function Q inspects.
BAND_FRACTION = 0.1

#: Standard deviation (px) of the Gaussian whose periodic blur is removed to get the high-pass
#: image: fine detail (about 2-6 px wavelengths) is what a crossfade or a blurry join destroys.
HIGHPASS_SIGMA = 1.5




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


