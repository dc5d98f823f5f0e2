"""Atlas evidence in the pixels of a map that no geometry binds.

A baked UV atlas leaves the space between its islands flat: a background colour (often black)
beyond a few texels of padding, so the islands are many disconnected regions on one exact
colour. A texture meant to tile is a photo or a pattern: no large flat area of one colour,
let alone one cutting it into islands. Figures, on the map's used channels reduced to at most
``SIZE`` px:

- ``background``: the share of texels within ``TOLERANCE`` of the most common colour (binned
  at ``1 / BINS``), counting only flat texels (their 3x3 neighbourhood varies by at most
  ``TOLERANCE``);
- ``islands``: connected regions of the rest (8-connected) covering at least ``MIN_ISLAND``
  of the image each.

Thresholds come from ``benchmarks/atlas.py`` (figures in ``tests/test_intent_atlas.py``): 25
atlases with a background between their islands (the bundled ones and others baked the same way,
3x3 to 8x8 islands, four background colours, 0-2 texels of padding) measure 9-64 islands on a
background of 0.150-0.332; 66 windows (256-2048 px) of the MaterialX example photos, which do
not tile, measure at most 5 islands (background 0.000-0.759: a brick mask is mostly flat), and
the 9 tiling textures 1 island (background 0.008-0.529). The island count separates them; the
background share keeps a few specks on a flat photo from counting. Not seen: an atlas whose
padding fills the whole sheet (no background left: 16 such bakes measure 1 island), which stays
*tiling* unless geometry binds it.
"""
from __future__ import annotations

import numpy as np

from seamless_usd.textures import TextureMap, TextureStack

__all__ = ["AtlasFigures", "atlas_figures", "atlas_evidence", "BACKGROUND_MIN", "ISLANDS_MIN"]

SIZE = 256  # longest side the pixels are reduced to
BINS = 64  # colour bins for the background's colour
TOLERANCE = 0.02  # a texel within this of the background colour (each channel) is background
MIN_ISLAND = 0.001  # islands smaller than this share of the image are noise
BACKGROUND_MIN = 0.10  # at least this share of flat background ... (atlases 0.150-0.332)
ISLANDS_MIN = 8  # ... cutting the rest into at least this many islands (atlases 9-64, photos <= 5)
MAX_PIXELS = 1 << 26  # larger files are not decoded here


class AtlasFigures(tuple):
    """``(background share, islands)`` of one map."""

    __slots__ = ()

    @property
    def background(self) -> float:
        return self[0]

    @property
    def islands(self) -> int:
        return self[1]

    @property
    def is_atlas(self) -> bool:
        return self.background >= BACKGROUND_MIN and self.islands >= ISLANDS_MIN


def _reduce(pixels: np.ndarray, size: int) -> np.ndarray:
    """Block means by the integer factor bringing the longest side to at most ``size``."""
    step = max(1, int(np.ceil(max(pixels.shape[:2]) / size)))
    if step == 1:
        return pixels
    h, w = (pixels.shape[0] // step) * step, (pixels.shape[1] // step) * step
    c = pixels.shape[2]
    return pixels[:h, :w].reshape(h // step, step, w // step, step, c).mean(axis=(1, 3))


def atlas_figures(pixels: np.ndarray) -> AtlasFigures:
    """Background share and island count of ``(H, W, C)`` pixels in [0, 1] (see the module notes).

    >>> img = np.zeros((64, 64, 3)); img[4:12, 4:12] = 0.5; img[20:30, 40:60] = 0.8
    >>> atlas_figures(img).islands
    2
    """
    from scipy import ndimage

    a = _reduce(np.asarray(pixels, dtype=np.float64), SIZE)
    binned = np.clip(np.floor(a * BINS), 0, BINS - 1).astype(np.int64)
    codes = np.zeros(a.shape[:2], dtype=np.int64)
    for ch in range(a.shape[2]):
        codes = codes * BINS + binned[..., ch]
    values, counts = np.unique(codes, return_counts=True)
    mode = values[np.argmax(counts)]
    colour = np.median(a[codes == mode], axis=0)
    near = np.all(np.abs(a - colour) <= TOLERANCE, axis=2)
    spread = np.max(ndimage.maximum_filter(a, size=(3, 3, 1)) - ndimage.minimum_filter(a, size=(3, 3, 1)), axis=2)
    background = near & (spread <= TOLERANCE)
    labels, n = ndimage.label(~background, structure=np.ones((3, 3)))
    sizes = np.bincount(labels.ravel())[1:] if n else np.zeros(0)
    islands = int(np.sum(sizes >= MIN_ISLAND * labels.size))
    return AtlasFigures((float(background.mean()), islands))


def _map_figures(m: TextureMap) -> AtlasFigures | None:
    if not m.resolved or m.in_package or m.image is None or m.image.width * m.image.height > MAX_PIXELS:
        return None
    from seamless_usd.errors import InputError
    from seamless_usd.imaging.io import read_image

    try:
        pixels, _ = read_image(m.resolved)
    except (InputError, OSError, ValueError, RuntimeError):
        return None
    if not np.isfinite(pixels).all():
        return None
    channels = [i for i, c in enumerate("rgba") if c in m.channels_used and i < pixels.shape[2]]
    return atlas_figures(np.clip(pixels[..., channels or [0]], 0.0, 1.0))


def atlas_evidence(stack: TextureStack, cache: dict) -> str | None:
    """The reason a stack no geometry binds is flagged as an atlas (its most atlas-like map's
    figures), or None when no map shows an atlas's layout. ``cache`` keeps figures per file."""
    found = []
    for m in stack.maps:
        key = ("atlas", m.resolved, m.channels_used)
        if key not in cache:
            cache[key] = _map_figures(m)
        if cache[key] is not None and cache[key].is_atlas:
            found.append((cache[key], m))
    if not found:
        return None
    figures, m = max(found, key=lambda f: f[0].islands)
    return (f"pixels of @{m.asset}@: {figures.islands} island{'' if figures.islands == 1 else 's'} on a flat "
            f"background covering {figures.background:.0%} (an atlas has at least {ISLANDS_MIN} on {BACKGROUND_MIN:.0%}; photos "
            f"and tiling textures measure at most 5 islands)")
