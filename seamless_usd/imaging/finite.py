"""The NaN / inf policy for float images: replace with finite values and report, never crash.

Renders and bakes sometimes leave NaN or infinite texels in EXR files. They are replaced before
decoding: NaN by 0, +inf by the largest finite value of that channel, -inf by the smallest (0
when a channel has no finite value). The counts are returned so the caller reports them (the
stack loader adds a ``non-finite-pixels`` warning finding); decode/encode functions themselves
refuse non-finite input with a ``ValueError``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["NonFinite", "replace_nonfinite"]


@dataclass(frozen=True)
class NonFinite:
    """How many values were replaced."""

    nan: int = 0
    posinf: int = 0
    neginf: int = 0

    @property
    def total(self) -> int:
        return self.nan + self.posinf + self.neginf

    def __str__(self) -> str:
        return f"{self.nan} NaN, {self.posinf} +inf, {self.neginf} -inf"


def replace_nonfinite(pixels: np.ndarray) -> tuple[np.ndarray, NonFinite]:
    """Replace NaN and inf values channel by channel (see the module docstring).

    Parameters
    ----------
    pixels
        ``(H, W)`` or ``(H, W, C)`` values.

    Returns
    -------
    pixels : np.ndarray
        The same array when everything is finite, otherwise a float copy with replacements.
    counts : NonFinite
        What was replaced.

    Examples
    --------
    >>> fixed, counts = replace_nonfinite(np.array([[1.0, np.nan, np.inf, 3.0]]))
    >>> fixed.tolist(), counts.total
    ([[1.0, 0.0, 3.0, 3.0]], 2)
    """
    p = np.asarray(pixels)
    finite = np.isfinite(p)
    if finite.all():
        return p, NonFinite()
    counts = NonFinite(
        nan=int(np.isnan(p).sum()), posinf=int(np.isposinf(p).sum()), neginf=int(np.isneginf(p).sum())
    )
    out = p.astype(np.result_type(p.dtype, np.float32), copy=True)
    planes = out[..., None] if out.ndim == 2 else out
    ok_planes = finite[..., None] if out.ndim == 2 else finite
    for c in range(planes.shape[-1]):
        plane, ok = planes[..., c], ok_planes[..., c]
        good = plane[ok]
        top = float(good.max()) if good.size else 0.0
        bottom = float(good.min()) if good.size else 0.0
        plane[np.isnan(plane)] = 0.0
        plane[np.isposinf(plane)] = top
        plane[np.isneginf(plane)] = bottom
    return out, counts
