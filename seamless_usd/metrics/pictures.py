"""Display pictures of network-domain maps (2x2 tilings, uint8 previews)."""
from __future__ import annotations

import numpy as np

__all__ = ["tile_2x2", "preview_uint8"]

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
