"""The dominant orientation of a texture's structure: how far its lines (planks, courses, stripes, a grid)
are turned from the picture's axes.

Each map is brought to grey (its channels averaged, at most ``SIDE`` px by box means) and light broader
than ``_LIGHT`` px is taken away. The picture is then turned back by each whole degree from -44 to 45 (at
half that size) and the variance of its row means and column means is read on the centre that holds
picture texels at every angle (the square inside the inscribed circle): a Radon-style projection, in which lines that run along an axis pile into
a sharp profile and lines at a slant average out. A grid's two directions and a plank's long edge and its
end joints peak at the same angle modulo 90 degrees. Around the best degree the search goes on in steps
of a quarter and a twentieth of a degree, at full size.

``strength`` is the best figure over the median of the whole degrees (1.5 for white noise, 1.3-2.4 for
stochastic photos, 10-60 for turned planks and bricks, up to 660 for a tiled floor). Only lines at least ``MIN_STRENGTH`` are worth
straightening. The map whose lines stand out most decides: a roughness map's grain can hide the planks
its colour map shows.

>>> import numpy as np
>>> y, x = np.mgrid[0:256, 0:256].astype(np.float32)
>>> a = np.radians(10.0)
>>> stripes = np.sin(2 * np.pi * (x * np.cos(a) - y * np.sin(a)) / 16.0)[..., None]
>>> found = dominant_orientation([stripes])
>>> round(found.degrees), found.strength > MIN_STRENGTH
(10, True)
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["Orientation", "dominant_orientation", "MIN_STRENGTH", "MIN_DEGREES", "SIDE"]

#: The grey picture is read at most this many px on its longer side.
SIDE = 384
#: A best projection this many times the median one is structure worth straightening. Set on the 33 photos of
#: ``benchmarks/photos`` (none shot turned): the stochastic ones read 1.3-2.4, lines along the axes 4-660 at
#: 0 degrees, and the flagstones 5.4 at -0.85 degrees, from a few straight joints (benchmarks/straighten.py).
MIN_STRENGTH = 6.0
#: Turns smaller than this (degrees) are left alone: the resampling would cost more detail than it mends.
MIN_DEGREES = 0.5
_LIGHT = 6.0  # px (gaussian sigma, on the grey picture): broader changes are light, taken away first


@dataclass(frozen=True)
class Orientation:
    """``degrees``: how far the structure is turned counter-clockwise (as the picture is seen) from the
    picture's axes, in (-45, 45]; turning the picture clockwise by ``degrees`` straightens it. ``strength``: the
    sharpest projection over the median one."""

    degrees: float
    strength: float

    @property
    def straightens(self) -> bool:
        """Whether the structure is strong and turned enough to be straightened."""
        return self.strength >= MIN_STRENGTH and abs(self.degrees) >= MIN_DEGREES

    def as_dict(self) -> dict:
        return {"degrees": round(self.degrees, 2), "strength": round(self.strength, 2)}


def _grey(values: np.ndarray) -> np.ndarray:
    """A map's channels averaged, at most SIDE px (box means), light (broader than _LIGHT) taken away."""
    from scipy import ndimage

    h, w = values.shape[:2]
    step = max(1, int(np.ceil(max(h, w) / SIDE)))
    hh, ww = h // step * step, w // step * step
    g = np.asarray(values, dtype=np.float64).reshape(h, w, -1)[:hh, :ww].mean(axis=2)
    g = g.reshape(hh // step, step, ww // step, step).mean(axis=(1, 3))
    return g - ndimage.gaussian_filter(g, _LIGHT)


def _sharpness(grey: np.ndarray, degrees: float) -> float:
    """Variance of the row and column means of ``grey`` turned back by ``degrees``, on the centre square that
    holds picture texels at every angle (inside the inscribed circle): every angle is read on as many texels,
    so a mean over fewer of them, noisier, cannot win."""
    from scipy import ndimage

    turned = ndimage.rotate(grey, -degrees, reshape=False, order=1, mode="nearest")
    h, w = turned.shape
    side = int(min(h, w) / np.sqrt(2.0)) - 2
    y0, x0 = (h - side) // 2, (w - side) // 2
    centre = turned[y0:y0 + side, x0:x0 + side]
    if side < 2:
        return 0.0
    return float(centre.mean(axis=0).var() + centre.mean(axis=1).var())


def _one_map(grey: np.ndarray) -> Orientation:
    h, w = grey.shape[0] // 2 * 2, grey.shape[1] // 2 * 2
    half = grey[:h, :w].reshape(h // 2, 2, w // 2, 2).mean(axis=(1, 3))  # whole degrees read at half size
    coarse = np.arange(-44.0, 46.0, 1.0)
    figures = np.array([_sharpness(half, float(d)) for d in coarse])
    if not np.any(figures > 0):
        return Orientation(0.0, 1.0)
    best = float(coarse[int(np.argmax(figures))])
    strength = float(figures.max() / max(np.median(figures), 1e-20))
    for step in (0.25, 0.05):
        candidates = np.arange(best - 4 * step, best + 4.5 * step, step)
        best = float(max(candidates, key=lambda d: _sharpness(grey, float(d))))
    degrees = best - 90.0 if best > 45.0 else best + 90.0 if best <= -45.0 else best
    return Orientation(round(degrees, 2), strength)


def dominant_orientation(values: Sequence[np.ndarray]) -> Orientation:
    """The dominant orientation of the maps ``values`` (``(H, W, C)`` or ``(H, W)``, one texel grid): that of
    the map whose lines stand out most (a roughness map's grain can hide the planks its colour map shows)."""
    found = [_one_map(_grey(v)) for v in values if min(np.shape(v)[:2]) >= 8 * _LIGHT]
    return max(found, key=lambda o: o.strength, default=Orientation(0.0, 1.0))
