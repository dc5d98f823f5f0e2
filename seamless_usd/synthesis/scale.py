"""Feature scale of a stack and the working resolution the GAN trains at.

SeamlessGAN learns to expand a k x k crop into a 2k x 2k one. When the texture's structure (a
plank, a few bricks) is larger than the 2k crop, the generator never sees it whole and falls back
to its initial behaviour, a 2x upsampler: features come out magnified. So the GAN trains at a
working resolution where the structure fits the crop; the refinement brings the tile back to the
source's resolution with the source's own texels.
"""
from __future__ import annotations

import numpy as np

__all__ = ["structure_size", "working_factor", "autocorrelation", "box_downsample", "STRUCTURE_CORRELATION",
           "CROP_PER_STRUCTURE"]

#: The structure size is the radius where the radially averaged autocorrelation first falls below
#: this value (fine grain decorrelates within a few pixels; the larger arrangement much later).
STRUCTURE_CORRELATION = 0.2

#: How many structure sizes a 2k training crop should span. Chosen from the measurements on a
#: 512 px wood-planks window (structure 54 px): trained at 256 px (k = 64) its planks keep their
#: width (scale 0.89-1.10), trained natively they come out 2x too wide (0.71).
CROP_PER_STRUCTURE = 4.7

_MAX_ANALYSIS = 1024  # larger maps are box-downsampled for the autocorrelation (lengths scaled back)


def autocorrelation(u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normalised autocorrelation of ``u`` (H, W, C), summed over channels, with zero padding (the
    image is not treated as periodic) and each lag divided by its overlap: ``(acf (2H, 2W), lag_y
    (2H,), lag_x (2W,))``, ``acf[0, 0] == 1``. A constant map gives all zeros."""
    u = u.astype(np.float64)
    u = u - u.mean(axis=(0, 1))
    h, w = u.shape[:2]
    spec = np.fft.rfft2(u, s=(2 * h, 2 * w), axes=(0, 1))
    acf = np.fft.irfft2((np.abs(spec) ** 2).sum(axis=-1), s=(2 * h, 2 * w))
    ly = np.fft.fftfreq(2 * h) * 2 * h
    lx = np.fft.fftfreq(2 * w) * 2 * w
    overlap = np.maximum(np.outer(h - np.abs(ly), w - np.abs(lx)), 1.0)
    acf = acf / overlap
    if acf[0, 0] <= 0:
        return np.zeros_like(acf), ly, lx
    return acf / acf[0, 0], ly, lx


def box_downsample(u: np.ndarray, max_side: int) -> tuple[np.ndarray, int]:
    """``u`` (H, W, C) halved by 2x2 box means until its longest side is at most ``max_side``; with the factor."""
    factor = 1
    while max(u.shape[:2]) > max_side:
        h, w = u.shape[0] // 2 * 2, u.shape[1] // 2 * 2
        u = u[:h, :w].reshape(h // 2, 2, w // 2, 2, -1).mean(axis=(1, 3))
        factor *= 2
    return u, factor


def _correlation_length(u: np.ndarray, threshold: float) -> float:
    """Radius (px) where the radial mean of the normalised autocorrelation of ``u`` (H, W, C) drops below
    ``threshold``."""
    acf, ly, lx = autocorrelation(u)
    if acf[0, 0] <= 0:
        return 0.0  # a constant map has no structure
    h, w = u.shape[:2]
    radius = np.rint(np.sqrt(ly[:, None] ** 2 + lx[None, :] ** 2)).astype(np.int64)
    limit = min(h, w) // 2
    keep = radius < limit
    sums = np.bincount(radius[keep], weights=acf[keep], minlength=limit)
    counts = np.bincount(radius[keep], minlength=limit)
    ring = sums / np.maximum(counts, 1)
    below = np.nonzero(ring[1:] < threshold)[0]
    return float(below[0] + 1) if below.size else float(limit)


def structure_size(maps: list[np.ndarray], threshold: float = STRUCTURE_CORRELATION) -> float:
    """The largest correlation length (px at the given resolution) over the maps of a stack.

    >>> rng = np.random.default_rng(0)
    >>> structure_size([rng.normal(size=(64, 64, 1))]) <= 2
    True
    """
    sizes = []
    for m in maps:
        u = np.asarray(m, dtype=np.float32)
        u = u[..., None] if u.ndim == 2 else u
        u, factor = box_downsample(u, _MAX_ANALYSIS)
        sizes.append(_correlation_length(u, threshold) * factor)
    return max(sizes) if sizes else 0.0


def working_factor(height: int, width: int, k: int, structure: float,
                   crop_per_structure: float = CROP_PER_STRUCTURE) -> float:
    """Scale (<= 1) of the GAN's working resolution: the 2k crop spans ``crop_per_structure``
    structure sizes, and the short side stays at least 3k (room for varied training crops).

    >>> working_factor(512, 512, 64, 54.0)
    0.504
    >>> working_factor(256, 256, 64, 11.0)
    1.0
    """
    if structure <= 0:
        return 1.0
    f = min(1.0, 2 * k / (crop_per_structure * structure))
    floor = min(1.0, 3 * k / min(height, width))
    f = max(f, floor)
    return float(round(f, 3))
