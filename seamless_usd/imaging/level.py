"""Levelling a photo's light: each map divided by a broad blur of itself, so a wall lit brighter on one side, or
a slab darker towards a corner, has the same tone everywhere before its copies are joined.

Copies of a photo joined side by side meet where its light differs, and no cut hides a step in tone that
runs the whole length of a join. The light of a photo changes slowly; the texture does not. So each map's
light is read as a Gaussian blur of its tone (sigma :data:`LEVEL_SIGMA` of its shorter side; for a colour
map, of the mean of its colour channels), and every texel is scaled by the map's mean tone over the blur
there (a gain, as light multiplies). Texels keep their places: the maps stay aligned, and a cut made of the
levelled maps is still made of their copies, so the verdict finds the copies and judges the joins against
the levelled source. The gain is held to :data:`GAIN_RANGE` and values to the map's own range in the source.
Normal maps are left as they are (a light gradient is not in a normal map).

The result is a function of the source alone: ``check`` levels the recorded source the same way.

>>> rng = np.random.default_rng(0)
>>> flat = rng.uniform(-0.5, 0.5, (64, 64, 3)).astype(np.float32)
>>> lit = ((flat + 1) * np.linspace(0.7, 1.1, 64)[None, :, None] - 1).astype(np.float32)
>>> levelled, facts = level_maps([lit], [False])
>>> facts["moved"] > 0.1, float(np.abs(levelled[0].mean(axis=(0, 2))[:8].mean() - levelled[0].mean(axis=(0, 2))[-8:].mean())) < 0.05
(True, True)
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .resample import grown_linear

__all__ = ["LEVEL_SIGMA", "LEVEL_MIN", "GAIN_RANGE", "light_gain", "level_maps"]

#: The light's blur, as a share of the map's shorter side (the scale of what a lit photo's tone varies over).
LEVEL_SIGMA = 0.15
#: Light that varies by less than this share (the largest gain's distance from 1) is not levelled.
LEVEL_MIN = 0.02
#: The least and most a texel is scaled by.
GAIN_RANGE = (0.5, 2.0)
_LIGHT_SIDE = 256  # the light is read on the map box-shrunk to at most this many texels a side


def _shrunk(a: np.ndarray, step: int) -> np.ndarray:
    """``a`` (H, W) averaged over ``step`` x ``step`` boxes (the last partial ones dropped)."""
    H, W = (a.shape[0] // step) * step, (a.shape[1] // step) * step
    return a[:H, :W].reshape(H // step, step, W // step, step).mean(axis=(1, 3))


def _lit_channels(channels: int) -> int:
    """How many of a map's first channels carry light: grey (1), grey and alpha (2: the grey), colour (3) and
    colour with alpha (4: the colour)."""
    return 1 if channels <= 2 else 3


def light_gain(tone: np.ndarray) -> np.ndarray:
    """(H, W) float32: what each texel of ``tone`` (H, W, in [0, 1]) is scaled by for its light to be even: the
    mean tone over its light: the plane that fits the tone best, plus a Gaussian blur (sigma LEVEL_SIGMA of the
    shorter side, reflected at the borders) of what the plane leaves; held to GAIN_RANGE."""
    from scipy import ndimage

    H, W = tone.shape
    step = max(1, -(-max(H, W) // _LIGHT_SIDE))
    small = _shrunk(tone.astype(np.float64), step) if step > 1 else tone.astype(np.float64)
    # a plane through the tone first, the rest blurred reflected at the borders: light that ramps towards a border
    # keeps its slope there (a reflected ramp would flatten it)
    ys, xs = np.mgrid[0: small.shape[0], 0: small.shape[1]]
    basis = np.stack([np.ones(small.size), ys.ravel(), xs.ravel()], 1)
    plane = (basis @ np.linalg.lstsq(basis, small.ravel(), rcond=None)[0]).reshape(small.shape)
    light = plane + ndimage.gaussian_filter(small - plane, LEVEL_SIGMA * min(small.shape), mode="reflect")
    gain = float(small.mean()) / np.maximum(light, 1e-4)
    gain = np.clip(gain, *GAIN_RANGE)
    return grown_linear(gain, (H, W)) if step > 1 else gain.astype(np.float32)


def level_maps(values: Sequence[np.ndarray], normals: Sequence[bool]) -> tuple[list[np.ndarray], dict]:
    """(maps, facts): ``values`` (network domain, [-1, 1]) with each map's light levelled (see the module notes),
    and what was done: ``moved``, the largest share a texel was scaled by (``|gain - 1|``), ``moved_mean``, its
    mean, and ``sigma``. Maps are returned as given when no map's light varies by LEVEL_MIN or more."""
    out, moved, means = [], 0.0, []
    for m, normal in zip(values, normals):
        m = np.asarray(m, dtype=np.float32)
        if normal:
            out.append(m)
            continue
        unit = (m + 1.0) / 2.0
        colour = unit[..., : _lit_channels(unit.shape[-1])]  # an alpha channel is not lit
        gain = light_gain(colour.mean(-1))
        lo, hi = colour.min(axis=(0, 1)), colour.max(axis=(0, 1))
        levelled = unit.copy()
        levelled[..., : colour.shape[-1]] = np.clip(colour * gain[..., None], lo, hi)
        out.append(levelled * 2.0 - 1.0)
        moved = max(moved, float(np.abs(gain - 1).max()))
        means.append(float(np.abs(gain - 1).mean()))
    facts = {"moved": round(moved, 4), "moved_mean": round(float(np.mean(means)) if means else 0.0, 4),
             "sigma": LEVEL_SIGMA}
    if moved < LEVEL_MIN:
        return [np.asarray(m, dtype=np.float32) for m in values], {**facts, "moved": 0.0}
    return out, facts
