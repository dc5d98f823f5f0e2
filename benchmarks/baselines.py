"""Baseline ways of making a texture "tileable", to compare SeamlessGAN against.

``naive``
    The input itself, repeated: faithful, but every border is a seam.
``crossfade``
    The linear border crossfade of common "make seamless" scripts (overlap-and-blend). Along each
    axis in turn (x, then y), a band of ``b`` pixels at the end of the image is laid over the
    first ``b`` pixels and mixed in with a linear ramp, and the band is then cut off::

        out[:, j] = (1 - a_j) * u[:, W - b + j] + a_j * u[:, j],   a_j = (j + 0.5) / b,  j < b
        out[:, j] = u[:, j],                                                  b <= j < W - b

    so the output is ``(H - b_y) x (W - b_x)`` and its wrap-around is continuous: the pixel after
    the last column ``u[:, W-b-1]`` is (almost) ``u[:, W-b]``, its true neighbour. The price is a
    band where two unrelated parts of the image are averaged, which lowers contrast and fine
    detail along the seams (``b`` = 1/8 of the size by default).

Both work on network-domain maps (``(H, W, C)`` in ``[-1, 1]``) and renormalise normal vectors.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

__all__ = ["CROSSFADE_FRACTION", "naive_tile", "crossfade_tile", "BASELINES", "get_baseline"]

#: Width of the crossfade band as a fraction of the image size along the axis.
CROSSFADE_FRACTION = 0.125


def _renormalise(n: np.ndarray) -> np.ndarray:
    """Unit-length normals for 3-channel maps; 2-channel (x, y) maps are returned clipped."""
    if n.shape[-1] != 3:
        return np.clip(n, -1.0, 1.0)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    return n / np.maximum(length, 1e-12)


def naive_tile(pixels: np.ndarray, is_normal: bool = False) -> np.ndarray:
    """The input unchanged (its repetition is the naive tiling).

    Parameters
    ----------
    pixels : numpy.ndarray
        ``(H, W, C)`` map.
    is_normal : bool
        Unused; for a uniform baseline signature.
    """
    return np.array(pixels, dtype=np.float32, copy=True)


def _crossfade_axis(u: np.ndarray, axis: int, b: int) -> np.ndarray:
    n = u.shape[axis]
    head = np.take(u, np.arange(b), axis=axis)
    tail = np.take(u, np.arange(n - b, n), axis=axis)
    body = np.take(u, np.arange(b, n - b), axis=axis)
    ramp_shape = [1] * u.ndim
    ramp_shape[axis] = b
    a = ((np.arange(b) + 0.5) / b).reshape(ramp_shape)
    blended = (1.0 - a) * tail + a * head
    return np.concatenate([blended, body], axis=axis)


def crossfade_tile(
    pixels: np.ndarray, is_normal: bool = False, *, fraction: float = CROSSFADE_FRACTION
) -> np.ndarray:
    """Linear border crossfade (see the module notes): a ``(H - b_y, W - b_x, C)`` tile.

    Parameters
    ----------
    pixels : numpy.ndarray
        ``(H, W, C)`` map in ``[-1, 1]``.
    is_normal : bool
        Renormalise the blended normal vectors.
    fraction : float
        Band width as a fraction of the size, in ``(0, 0.5)``.

    Examples
    --------
    >>> crossfade_tile(np.zeros((64, 48, 3), np.float32)).shape
    (56, 42, 3)
    """
    if not 0 < fraction < 0.5:
        raise ValueError(f"fraction must be in (0, 0.5), got {fraction}")
    u = np.asarray(pixels, dtype=np.float64)
    if u.ndim != 3:
        raise ValueError(f"expected (H, W, C), got {u.shape}")
    for axis in (1, 0):
        b = max(1, int(round(fraction * u.shape[axis])))
        u = _crossfade_axis(u, axis, b)
    if is_normal:
        u = _renormalise(u)
    return u.astype(np.float32)


#: Baselines by name: ``fn(pixels (H, W, C), is_normal) -> tile (h, w, C)``.
BASELINES: dict[str, Callable[..., np.ndarray]] = {
    "naive": naive_tile,
    "crossfade": crossfade_tile,
}


def get_baseline(name: str) -> Callable[..., np.ndarray]:
    """The baseline called ``name``; ``ValueError`` listing the valid names otherwise."""
    try:
        return BASELINES[name]
    except KeyError:
        raise ValueError(f"unknown baseline {name!r}; valid: {', '.join(BASELINES)}") from None
