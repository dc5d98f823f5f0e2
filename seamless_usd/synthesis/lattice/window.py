"""Stacks that do not repeat: a tile that is one window of the source, joined across its wraps.

A refined tile is a mosaic of copied blocks; where two blocks meet badly a plank gap jumps or a stone
is cut in half, and the refinement makes hundreds of such joins (``benchmarks/experiments/results/levers.md``). This
candidate makes two: the tile is a single window of the source, so every plank, stone and joint inside
it is whole, and only its two wraps are joins. Each wrap is closed the way :func:`.cut.lattice_cut`
closes a lattice tile's (image quilting with one block, Efros and Freeman 2001): a band past one side
of the window is compared with the texels one tile on, and a minimum-error boundary cut chooses
between them, so the wrap runs where the two agree (along a joint, between grains).

The window's sides are the lags at which the texture comes closest to continuing itself: for every
side between :data:`WINDOW_MIN` of the source and the longest that leaves room for the band, the least
mean difference, over all places of a band, between the texels that the wrap would join
(:func:`window_tile_size`). A texture with long regular lines (planks, courses drifting in perspective)
has lags where its lines fall on lines; a stochastic one has no such lag, and the cut hides the join.

Like the lattice cut, this is one more candidate beside the refined tile (see :mod:`..tile`): the
verdict (no seam, fidelity) and the fidelity score choose between them. It is offered only for a texture
that *continues itself* at the chosen lags (:func:`continues_itself`): where it does not, the cut cannot
hide the join. Looked at along both wraps (2x), every window cut of a texture that does not repeat
closely enough (rotated wood and brick photographs, stone cells, stripes, weave windows at other scales, a
brick with a tone ramp or a drifting scale) showed tone patches with stair-stepped edges, mortar lines
jogging or ending at the cut, threads cut in half, while the verdict passed many of them: the minimum-error
cut meanders, so a straight line of the tile crosses a broken stretch for a few texels only
(``benchmarks/experiments/window_gate.py``, ``benchmarks/experiments/results/window_gate.md``).
"""
from __future__ import annotations

import math

import numpy as np

from ..refinement.refine import spread
from ..advice import WINDOW_MAX_DIFFERENCE
from .cut import CUT_MARGIN, _joint_small, box_sums

__all__ = ["WINDOW_MIN", "WINDOW_BAND", "WINDOW_MAX_DIFFERENCE", "continues_itself", "window_tile_size"]

#: The shortest tile side, as a share of the source's: a window keeps the source's texel scale, and its
#: UV transform keeps the texel density, but a much smaller tile repeats its features more often.
WINDOW_MIN = 0.7
#: The band across each wrap, as a share of the side: where the minimum-error cut may run.
WINDOW_BAND = 0.1
_ANALYSIS = 256  # longest side (px) the lags are compared at


def _lag_costs(u: np.ndarray, axis: int, lags: np.ndarray, band: int, length: int) -> np.ndarray:
    """For each lag along ``axis``, the least mean squared difference between texels that lag apart over
    a ``band`` x ``length`` block (``band`` along ``axis``), wherever the block sits."""
    v = u if axis == 1 else u.transpose(1, 0, 2)
    h, w = v.shape[:2]
    out = np.full(len(lags), np.inf)
    for k, lag in enumerate(lags):
        d = ((v[:, lag:] - v[:, :-lag]) ** 2).sum(-1)  # (h, w - lag)
        if h < length or d.shape[1] < band:
            continue
        out[k] = float(box_sums(d, length, band).min()) / (band * length)
    return out


def window_tile_size(maps: list[np.ndarray], margin: int = CUT_MARGIN
                     ) -> tuple[tuple[int, int], tuple[int, int], dict] | None:
    """((tile_h, tile_w), (band_h, band_w), figures) of a window tile of ``maps`` (see the module notes),
    or None when the source is too small for one. ``figures``: per axis, the chosen lag's mean difference
    over the texture's mean difference between unrelated texels (0: the texture continues itself exactly
    at that lag; about 1: the wrap joins unrelated places, the cut alone has to hide it).

    >>> x = np.arange(200)
    >>> bars = np.sin(2 * np.pi * x / 37)[None, :, None].repeat(160, 0).astype(np.float32)
    >>> (th, tw), band, figures = window_tile_size([bars])
    >>> tw % 37 == 0 and figures["x"] < 0.01
    True
    """
    H, W = np.asarray(maps[0]).shape[:2]
    u, factor = _joint_small(maps, [spread(m) for m in maps], _ANALYSIS)
    h, w = u.shape[:2]
    flat = u.reshape(-1, u.shape[-1])
    unrelated = 2.0 * float(flat.var(axis=0).sum()) + 1e-12  # mean squared difference of two random texels
    sides, bands, figures = [], [], {}
    for axis, (n, small, across) in enumerate(((H, h, W), (W, w, H))):
        band = max(4, round(n * WINDOW_BAND))
        longest = n - band - 2 * margin
        shortest = math.ceil(n * WINDOW_MIN)
        if longest < shortest or small < 16:
            return None
        lags = np.arange(max(1, math.ceil(shortest / factor)), max(1, longest // factor) + 1)
        if len(lags) == 0:
            return None
        small_band = max(1, round(band / factor))
        length = max(1, math.ceil(across * WINDOW_MIN / factor))  # the band runs along the tile's other side
        costs = _lag_costs(u, axis, lags, small_band, length)
        best = int(np.argmin(costs))
        sides.append(int(min(longest, lags[best] * factor)))
        bands.append(band)
        figures["yx"[axis]] = round(float(costs[best]) / unrelated, 4)
    return (sides[0], sides[1]), (bands[0], bands[1]), figures


def continues_itself(figures: dict) -> bool:
    """Whether a texture continues itself at a window's lags closely enough for its cut to hide the joins:
    ``figures`` (from :func:`window_tile_size`) at most :data:`WINDOW_MAX_DIFFERENCE` on both axes.

    >>> continues_itself({"y": 0.003, "x": 0.0006}), continues_itself({"y": 0.003, "x": 0.34})
    (True, False)
    """
    return max(figures.values()) <= WINDOW_MAX_DIFFERENCE
