"""Ghosted bands: where a tile's fine detail fades against its source's, along a whole line.

A crossfade (what quick "make seamless" scripts and tools such as img2texture do: the photo's opposite
borders laid over each other with a ramp of opacity) leaves no line that breaks. Inside its band every
texel is a mix of two unrelated places, so the copy lookup (:mod:`.copies`) finds nothing there and the
classifier (:mod:`.classifier`) sees only soft stretches. What the eye sees at 1x is two pictures showing
through each other: stones and berries doubled, their edges faint. Mixing two unrelated patches at half
weight each keeps about half their detail's energy, wherever the band runs.

So each tile patch's fine detail (the working-resolution maps less a Gaussian blur of
:data:`SIGMA` px) is compared with the source patch it looks most like (the highest normalised
correlation among the source's patches): the log of their detail's norms is about 0 for a copy at any
phase, for a patch across a clean join and for a texture's own flat stretches (which find flat source
patches), and falls to about -0.35 (log 0.7) in the middle of a crossfade. The median of that figure
along every line of the tile, against the median over all lines, dips where a band runs the tile's
whole length. A dip of more than :data:`GHOST_DIP` is a ghosted band: a seam, located at the band's
centre, over the whole line.

Only tiles judged against a source are read this way: a texture on its own has no detail to compare
with, and a tile of copies (:mod:`.copies`) has its blended texels judged by their steps.
"""
from __future__ import annotations

import numpy as np

from .lines import Seam

# scipy.ndimage is imported where a tile is read against a source, not with the verdict: it takes a quarter of a
# second, a quarter of ``check`` on a 1K picture, which judges a texture on its own and never reads ghosts.

__all__ = ["GHOST_DIP", "PATCH", "SIGMA", "ghost_bands", "detail_ratios"]

#: Side (working px) of the patches compared.
PATCH = 7
#: Blur (working px) removed from the maps: what remains is the detail a crossfade fades.
SIGMA = 2.0
#: Step (working px) between the tile's patches, and between the source's.
TILE_STRIDE = 4
SOURCE_STRIDE = 2
#: A patch whose detail's norm is under this share of the source's median is flat: its match is arbitrary.
FLAT = 0.25
#: A line whose median detail figure (smoothed over three lines of patches) lies this far (natural log)
#: below the tile's median line is a ghosted band.
GHOST_DIP = 0.3
#: Patches compared at a time (memory: this many rows of the correlation matrix).
CHUNK = 1024


def _detail(img: np.ndarray, periodic: bool) -> np.ndarray:
    """One channel of fine detail: the sum over channels of each less its blur."""
    from scipy.ndimage import gaussian_filter

    g = np.asarray(img, dtype=np.float32)
    g = g.sum(-1) if g.ndim == 3 else g
    return g - gaussian_filter(g, SIGMA, mode="wrap" if periodic else "reflect")


def _patches(d: np.ndarray, stride: int, periodic: bool) -> tuple[np.ndarray, tuple[int, int]]:
    """Zero-mean patches of ``d`` (rows of PATCH * PATCH), every ``stride`` px, and the grid's shape;
    periodic: a patch at every position of the torus (the tile as it repeats)."""
    if periodic:
        d = np.pad(d, ((0, PATCH - 1), (0, PATCH - 1)), mode="wrap")
    view = np.lib.stride_tricks.sliding_window_view(d, (PATCH, PATCH))[::stride, ::stride]
    grid = view.shape[:2]
    v = view.reshape(-1, PATCH * PATCH).astype(np.float32)
    return v - v.mean(1, keepdims=True), grid


def detail_ratios(tile: np.ndarray, source: np.ndarray) -> np.ndarray | None:
    """Per tile patch (a grid every TILE_STRIDE working px), the log of its detail's norm over that of the
    source patch it correlates best with; NaN where the tile's patch is flat. ``tile`` and ``source`` are
    working-resolution arrays (H, W, C) in the verdict's joint form. None: the source is too small or flat."""
    s, _ = _patches(_detail(source, False), SOURCE_STRIDE, False)
    t, grid = _patches(_detail(tile, True), TILE_STRIDE, True)
    if s.shape[0] == 0 or t.shape[0] == 0:
        return None
    sn, tn = np.linalg.norm(s, axis=1), np.linalg.norm(t, axis=1)
    floor = FLAT * float(np.median(sn))
    if floor <= 0:
        return None
    s, sn = s[sn >= floor], sn[sn >= floor]
    s /= sn[:, None]
    unit = t / np.maximum(tn, 1e-12)[:, None]
    out = np.empty(len(t), dtype=np.float32)
    for i in range(0, len(t), CHUNK):
        best = (unit[i:i + CHUNK] @ s.T).argmax(1)
        out[i:i + CHUNK] = np.log(np.maximum(tn[i:i + CHUNK], 1e-12) / sn[best])
    out[tn < floor] = np.nan
    return out.reshape(grid)


def ghost_bands(tile: np.ndarray, source: np.ndarray, factor: float, size: tuple[int, int], margin: float,
                map_name: str = "stack") -> tuple[list[Seam], float]:
    """Ghosted bands of a tile (working-resolution joint arrays, ``factor`` the working scale, ``size`` the tile's
    (h, w) at full resolution): a seam per axis where a line's dip exceeds GHOST_DIP, with its figure on the
    verdict's scale (the dip over GHOST_DIP, times the verdict's ``margin``: above the margin is a seam), and
    the strongest such figure.

    >>> rng = np.random.default_rng(0)
    >>> src = rng.normal(size=(192, 192, 1)).astype(np.float32)
    >>> a, b = src[8:136, 8:136], src[56:184, 56:184]
    >>> ramp = np.clip((np.arange(128) - 48) / 32, 0, 1)[:, None, None]  # a crossfade over rows 48-80
    >>> seams, _ = ghost_bands((1 - ramp) * a + ramp * b, src, 1.0, (128, 128), 0.5)
    >>> [(s.axis, s.kind, 56 <= s.position <= 72) for s in seams]
    [('y', 'ghost', True)]
    >>> ghost_bands(np.roll(src, 5, 0), src, 1.0, (192, 192), 0.5)[0]
    []
    """
    from scipy.ndimage import uniform_filter1d

    ratios = detail_ratios(tile, source)
    if ratios is None:
        return [], 0.0
    seams, strongest = [], 0.0
    h, w = size
    for axis, grid in (("y", ratios), ("x", ratios.T)):
        with np.errstate(all="ignore"):
            lines = np.nanmedian(grid, axis=1)
        if np.all(np.isnan(lines)):
            continue
        lines = np.where(np.isnan(lines), np.nanmedian(lines), lines)
        smooth = uniform_filter1d(lines, 3, mode="wrap")
        dip = float(np.median(lines)) - smooth
        at = int(np.argmax(dip))
        figure = float(dip[at]) / GHOST_DIP * margin
        strongest = max(strongest, figure)
        if dip[at] > GHOST_DIP:
            across = h if axis == "y" else w
            position = int(round((at * TILE_STRIDE + PATCH // 2) / factor)) % across
            along = (w if axis == "y" else h) - 1
            seams.append(Seam(axis, position, 0, along, figure, map_name, "ghost"))
    return seams, strongest
