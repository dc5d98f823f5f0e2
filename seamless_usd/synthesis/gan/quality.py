"""Discriminator-guided quality function Q (paper section 4.2)."""
from __future__ import annotations

import numpy as np

from ..types import QResult

__all__ = ["band_masks", "quality"]


def band_masks(height: int, width: int, fraction: float = 0.2) -> tuple[np.ndarray, np.ndarray]:
    """(vertical, horizontal) bool masks (H, W) of the bands through the centre, each ``fraction`` of its dimension."""
    def band(n: int) -> np.ndarray:
        width_ = max(1, int(round(fraction * n)))
        start = (n - width_) // 2
        m = np.zeros(n, dtype=bool)
        m[start: start + width_] = True
        return m

    vertical = np.broadcast_to(band(width)[None, :], (height, width)).copy()
    horizontal = np.broadcast_to(band(height)[:, None], (height, width)).copy()
    return vertical, horizontal


def quality(d_map: np.ndarray, gamma: float = 1.0, fraction: float = 0.2) -> QResult:
    """Q of a discriminator map (H, W) with 1 = real: tileable when both band minima reach tau.

    >>> d = np.ones((10, 10)); d[5, :] = 0.1   # a dark horizontal seam
    >>> quality(d).passed
    False
    >>> quality(np.array([[0.2], [0.9], [0.4]])).passed   # no texel outside the bands: nothing to judge against
    True
    """
    d = np.asarray(d_map, dtype=np.float64)
    assert d.ndim == 2 and np.isfinite(d).all(), f"expected a finite (H, W) discriminator map, got {d.shape}"
    vertical, horizontal = band_masks(*d.shape, fraction)
    outside = ~(vertical | horizontal)
    # a map too small to have pixels outside its bands (a one-texel-wide map of a small preset's crop): the whole
    # map is the reference, so Q tells the candidates apart by nothing (it guides the crop search only)
    tau = gamma * float(d[outside if outside.any() else np.ones_like(outside)].min())
    v_min, h_min = float(d[vertical].min()), float(d[horizontal].min())
    return QResult(passed=v_min >= tau and h_min >= tau, tau=tau, band_min_vertical=v_min,
                   band_min_horizontal=h_min, d_map=d.astype(np.float32), band_vertical=vertical,
                   band_horizontal=horizontal)
