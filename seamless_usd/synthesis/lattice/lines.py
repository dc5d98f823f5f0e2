"""A source's long lines: joints between stones and slabs, plank gaps, mortar, however thin.

:func:`.quilt.line_mask` finds lines as broad as a quilt's overlap sees them: it opens its mask to drop grain,
and so erases joints one or two texels wide (a marble floor's slab joints at 512 px). :func:`thin_line_share`
finds those: the source halved until its longest side is at most :data:`THIN_SIDE` texels (so a 4-texel joint of a 2K map
is as thin as a 512 px map's), high-passed at :data:`THIN_SIGMA` texels, its darkest or brightest
:data:`THIN_SHARE` kept, then opened by straight segments :data:`THIN_LENGTH` texels long in eight
directions: what survives lies on a straight run, however thin, while speckle, pores and the rims of round
things do not. The share of what survives that lies in pieces spanning a quarter of the map is the figure
(:func:`long_share`). On the 33 photos of ``benchmarks/photos.py`` at 512 px it reads 1.0 for the marble
slabs and at most 0.15 for every photo without joints (fruit, grass, bark, soil, gravel, stones, sand).
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ..refinement.refine import spread
from ..scale import box_downsample

__all__ = ["THIN_SIDE", "THIN_SIGMA", "THIN_SHARE", "THIN_LENGTH", "THIN_LONG", "principal_tone", "long_share",
           "thin_line_share", "has_thin_lines"]

#: Longest side (texels) the source is brought to before its thin lines are looked for.
THIN_SIDE = 512
#: The high-pass scale (texels at THIN_SIDE): a joint is narrower than this.
THIN_SIGMA = 2.0
#: Share of the texels (the darkest or the brightest after the high-pass) that may be lines.
THIN_SHARE = 0.1
#: The straight segments (texels) a line's texels must lie on.
THIN_LENGTH = 15
#: The source has thin lines when at least this share of the surviving texels lies in long pieces.
THIN_LONG = 0.5


def principal_tone(maps: list[np.ndarray]) -> np.ndarray:
    """(H, W) float32: the maps' first principal channel, jointly, each map over its spread."""
    parts = [(np.asarray(m, dtype=np.float32) / spread(m)).reshape(*m.shape[:2], -1) for m in maps]
    H, W = parts[0].shape[:2]
    step = max(1, round(math.sqrt(H * W / 65536)))
    flat = np.concatenate([p[::step, ::step].reshape(-1, p.shape[-1]) for p in parts], -1)
    axis = np.ones(1, dtype=np.float32)
    if flat.shape[-1] > 1:  # the polarity of the axis does not matter: callers try both
        axis = np.linalg.eigh(np.cov(flat - flat.mean(0), rowvar=False))[1][:, -1].astype(np.float32)
    u, at = np.zeros((H, W), dtype=np.float32), 0
    for p in parts:  # one map at a time: a 4K stack never holds its joint features
        u += p @ axis[at: at + p.shape[-1]]
        at += p.shape[-1]
    return u


def long_share(mask: np.ndarray) -> float:
    """Share of ``mask``'s texels that lie in 8-connected pieces spanning at least a quarter of its longer side."""
    from scipy import ndimage

    labels, count = ndimage.label(mask, structure=np.ones((3, 3)))
    if count == 0:
        return 0.0
    spans = np.array([max(sl[0].stop - sl[0].start, sl[1].stop - sl[1].start) for sl in ndimage.find_objects(labels)])
    sizes = np.bincount(labels.ravel())[1:]
    return float(sizes[spans >= max(mask.shape) / 4].sum()) / max(1, int(mask.sum()))


@lru_cache(maxsize=4)
def _segments(length: int) -> tuple[np.ndarray, ...]:
    """Straight segments ``length`` texels long, in eight directions, as structuring elements."""
    c, out = length // 2, []
    for k in range(8):
        a = math.pi * k / 8
        se = np.zeros((length, length), dtype=bool)
        t = np.linspace(-c, c, 4 * length)
        se[np.round(c + t * math.sin(a)).astype(int), np.round(c + t * math.cos(a)).astype(int)] = True
        out.append(se)
    return tuple(out)


def thin_line_share(maps: list[np.ndarray]) -> float:
    """The share of the source's line texels, however thin, that lie in long pieces (see the module notes); the
    larger of its dark and its bright lines."""
    from scipy import ndimage

    u = principal_tone([np.asarray(m) for m in maps])
    u = box_downsample(u[..., None], THIN_SIDE)[0][..., 0]
    hp = u - ndimage.gaussian_filter(u, THIN_SIGMA, mode="reflect")
    best = 0.0
    for mask in (hp < np.quantile(hp, THIN_SHARE), hp > np.quantile(hp, 1 - THIN_SHARE)):
        kept = np.zeros_like(mask)
        for se in _segments(THIN_LENGTH):
            kept |= ndimage.binary_opening(mask, structure=se)
        best = max(best, long_share(kept))
    return best


def has_thin_lines(maps: list[np.ndarray]) -> bool:
    """Whether the source has long lines, however thin (:func:`thin_line_share` at least THIN_LONG)."""
    return thin_line_share(maps) >= THIN_LONG
