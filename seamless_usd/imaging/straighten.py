"""Straightening a stack whose structure is turned: every map turned back by the same angle and cut to the
largest axis-aligned rectangle that holds source texels only.

The turn is resampled with OpenImageIO's ``rotate`` and a Lanczos-3 filter, at the source's texel size
(a rotation keeps it), so the straightened maps keep the source's feature scale. Values are clipped to
each channel's range in the source (the filter's lobes overshoot at hard edges), and normal maps, decoded
to vectors, turn with the picture and are renormalised. The rectangle is cut ``MARGIN`` texels inside the
turned picture's border, where the filter reaches no texel outside the source.

>>> inscribed_size(512, 512, 0.0)
(512, 512)
>>> inscribed_size(1000, 1000, 45.0)
(707, 707)
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import OpenImageIO as oiio

from seamless_usd.imaging.normals import renormalise

__all__ = ["inscribed_size", "straighten_maps", "MARGIN"]

#: Texels kept clear of the turned picture's border: the Lanczos-3 filter's reach.
MARGIN = 3


def inscribed_size(width: int, height: int, degrees: float) -> tuple[int, int]:
    """(width, height) of the largest axis-aligned rectangle, centred, inside a ``width`` x ``height`` picture
    turned by ``degrees`` about its centre."""
    a = math.radians(abs(degrees) % 180.0)
    if a > math.pi / 2:
        a = math.pi - a
    sin_a, cos_a = math.sin(a), math.cos(a)
    if sin_a < 1e-12:
        return width, height
    long_side, short_side = max(width, height), min(width, height)
    if short_side <= 2.0 * sin_a * cos_a * long_side or abs(sin_a - cos_a) < 1e-12:
        # two corners touch the long sides: the rectangle is bound by the short side alone
        half = 0.5 * short_side
        along, across = half / sin_a, half / cos_a
        w, h = (along, across) if width >= height else (across, along)
    else:  # all four corners touch the turned picture's sides
        cos_2a = cos_a * cos_a - sin_a * sin_a
        w = (width * cos_a - height * sin_a) / cos_2a
        h = (height * cos_a - width * sin_a) / cos_2a
    return int(math.floor(w + 1e-6)), int(math.floor(h + 1e-6))


def _turned(values: np.ndarray, degrees: float) -> np.ndarray:
    """``values`` (H, W, C) turned clockwise, as the picture is seen, by ``degrees`` about its centre, same canvas."""
    src = oiio.ImageBuf(np.ascontiguousarray(values, dtype=np.float32))
    out = oiio.ImageBufAlgo.rotate(src, math.radians(degrees), filtername="lanczos3", recompute_roi=False)
    if out.has_error:
        raise RuntimeError(f"turning the map failed: {out.geterror()}")
    return np.asarray(out.get_pixels(oiio.FLOAT), dtype=np.float32).reshape(values.shape)


def straighten_maps(values: Sequence[np.ndarray], normals: Sequence[bool], degrees: float,
                    turn_vectors: bool = True) -> list[np.ndarray]:
    """Every map of ``values`` (decoded, (H, W, C), one texel grid) turned clockwise by ``degrees`` (an
    :class:`.orientation.Orientation`'s angle straightens it) and cut to the largest rectangle of source
    texels; ``normals``: which maps hold unit vectors (x right, y up), turned with the picture unless
    ``turn_vectors`` is false: a tile the asset's UVs turn back (``process --straighten``) is seen in the asset's
    own tangent frame, so its vectors keep the source's."""
    h, w = values[0].shape[:2]
    iw, ih = inscribed_size(w, h, degrees)
    iw, ih = iw - 2 * MARGIN, ih - 2 * MARGIN
    if iw < 8 or ih < 8:
        raise ValueError(f"a {w} x {h} picture turned by {degrees:g} degrees keeps no rectangle to tile")
    x0, y0 = (w - iw) // 2, (h - ih) // 2
    out = []
    for v, is_normal in zip(values, normals):
        v = np.asarray(v, dtype=np.float32)
        flat = v.reshape(h, w, -1)
        turned = _turned(flat, degrees)[y0:y0 + ih, x0:x0 + iw]
        if is_normal and flat.shape[2] >= 3 and not turn_vectors:
            turned = np.concatenate([renormalise(turned[..., :3]), turned[..., 3:]], axis=2)
        elif is_normal and flat.shape[2] >= 3:
            a = math.radians(degrees)  # the vectors turn clockwise with the picture
            x, y = turned[..., 0].copy(), turned[..., 1].copy()
            turned[..., 0] = x * math.cos(a) + y * math.sin(a)
            turned[..., 1] = -x * math.sin(a) + y * math.cos(a)
            turned = np.concatenate([renormalise(turned[..., :3]), turned[..., 3:]], axis=2)
        else:
            lo = flat.reshape(-1, flat.shape[2]).min(axis=0)
            hi = flat.reshape(-1, flat.shape[2]).max(axis=0)
            turned = np.clip(turned, lo, hi)
        out.append(np.ascontiguousarray(turned.reshape((ih, iw) + v.shape[2:]), dtype=np.float32))
    return out
