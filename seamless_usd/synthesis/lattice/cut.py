"""Repeating textures: their lattice periods, and a tile cut to whole periods.

Bricks, tiles and weaves repeat on a lattice. A torus holds such a texture without a broken bond
only when its sides are whole multiples of the lattice's periods along the axes; a source-sized
tile (256 px of a 107 px brick period) cannot. Neither SeamlessGAN at the CPU's training budget
nor a refinement from a random start rebuilds a bond: both break it (``benchmarks/results``).

So for a stack whose autocorrelation has strong peaks along an axis, this module

1. finds the period along each axis (:func:`find_lattice`);
2. sizes the tile to whole periods, leaving room for a band across each wrap, and snaps each side
   to the lag where the texture best matches itself (:func:`lattice_tile_size`);
3. cuts the crop whose bands match their one-tile-on copies best, and joins each band to its copy
   along a minimum-error boundary cut (:func:`lattice_cut`). Both sides of the cut sit at the same
   lattice phase, so bricks land on bricks and the cut runs through the mortar. Every texel is a
   source texel, copied through one field for all maps.

The result is one more candidate beside the refined GAN tile (see :mod:`seamless_usd.synthesis.tile`):
the verdict and the score (fidelity, structure, lattice ratio, strongest seam) choose between them;
the discriminator's Q is recorded, not used to choose.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..refinement.refine import joint_features, spread
from ..scale import autocorrelation, box_downsample

__all__ = ["Lattice", "find_lattice", "lattice_tile_size", "lattice_cut", "lattice_ratio", "PERIOD_STRENGTH",
           "PERIOD_DIP", "LATTICE_TARGET"]

#: An autocorrelation peak marks a period when it reaches this value ...
PERIOD_STRENGTH = 0.4
#: ... after the curve dipped at least this far below it (a smooth texture decays without a peak).
PERIOD_DIP = 0.15
#: Peaks whose value is within this of the strongest and whose lag divides its lag are the same lattice
#: (a grid's first peak, not its second); a running bond's half-period row peak is well below this.
_SAME_PEAK = 0.05
#: A tile keeps the source's repeat when its autocorrelation at each lattice period is at least this
#: share of the source's (:func:`lattice_ratio`). On the two 256 px brick windows of the quality
#: benchmark a cut of whole periods scores 0.95-0.99, the source repeated as it is 0.51-0.52, the
#: refined GAN tile with its broken bond 0.16-0.31 and a refinement from a random start about 0.
LATTICE_TARGET = 0.9
_MIN_LAG = 4  # px: shorter repeats are grain, not layout
_ANALYSIS = 1024  # longest side (px) the autocorrelation is computed at
_OFFSET_ANALYSIS = 512  # longest side (px) of the crop-placement search
#: px the cut keeps from the maps' borders where it fits
CUT_MARGIN = 5


@dataclass(frozen=True)
class Lattice:
    """Periods (px at the maps' resolution) along y and x; None where that axis does not repeat."""

    period: tuple[float | None, float | None]
    strength: tuple[float | None, float | None]  # the autocorrelation at each period
    #: the autocorrelation along each axis at every lag below the side (at the analysis resolution,
    #: ``factor`` times coarser), to snap a tile side to the best-matching multiple of the period
    curves: tuple[np.ndarray | None, np.ndarray | None] = field(default=(None, None), compare=False, repr=False)
    factor: int = 1

    @property
    def found(self) -> bool:
        return any(p is not None for p in self.period)

    def as_dict(self) -> dict:
        return {"period_px": [None if p is None else round(p, 2) for p in self.period],
                "strength": [None if s is None else round(s, 3) for s in self.strength]}


def _axis_period(curve: np.ndarray, strength: float, dip: float) -> tuple[float, float] | None:
    """(period, value) of the lattice along one axis from its autocorrelation ``curve[lag]``, or None."""
    n = len(curve)
    peaks = [i for i in range(_MIN_LAG, n - 1) if curve[i] >= curve[i - 1] and curve[i] > curve[i + 1]]
    strong = [i for i in peaks if curve[i] >= strength and curve[:i].min() <= curve[i] - dip]
    if not strong:
        return None
    best = max(strong, key=lambda i: curve[i])
    for i in strong:  # ascending: the fundamental of the strongest peak, when it is about as strong
        ratio = best / i
        if curve[i] >= curve[best] - _SAME_PEAK and abs(ratio - round(ratio)) < 0.1:
            best = i
            break
    period = _peak(curve, best)
    harmonic = int(round(2 * period))
    if harmonic < n - 1 and curve[max(0, harmonic - 1): harmonic + 2].max() < strength - 0.1:
        return None  # a lattice repeats: its second period must be a peak too, where it can be seen
    # a tile holds several periods, so the error of one multiplies: measure the farthest strong harmonic
    k = 2
    while round((k + 0.5) * period) < n - 1:
        near = int(round(k * period))
        lo, hi = max(1, near - 2), min(n - 2, near + 2)
        top = lo + int(np.argmax(curve[lo: hi + 1]))
        if curve[top] < strength - 0.1:
            break
        period = _peak(curve, top) / k
        k += 1
    return period, float(curve[best])


def _joint_small(maps: list[np.ndarray], spreads: list[float], max_side: int) -> tuple[np.ndarray, int]:
    """Joint features (each map over its spread, as :func:`.refine.joint_features`) box-downsampled
    to at most ``max_side`` px, with the factor; each map is shrunk before they are joined, so a 4K
    stack never holds its full-resolution joint features."""
    parts = [box_downsample(np.asarray(m, dtype=np.float32) / s, max_side) for m, s in zip(maps, spreads)]
    return np.concatenate([p for p, _ in parts], axis=-1), parts[0][1]


def _peak(curve: np.ndarray, i: int) -> float:
    """Sub-pixel lag of the local maximum at ``i``: the vertex of the parabola through its neighbours."""
    a, b, c = curve[i - 1], curve[i], curve[i + 1]
    den = a - 2 * b + c
    shift = 0.5 * (a - c) / den if den < 0 else 0.0
    return i + float(np.clip(shift, -0.5, 0.5))


def find_lattice(maps: list[np.ndarray], strength: float = PERIOD_STRENGTH, dip: float = PERIOD_DIP) -> Lattice:
    """The axis periods of a stack (all maps jointly, each at equal weight).

    >>> x = np.arange(96)
    >>> bars = np.sin(2 * np.pi * x / 16)[None, :, None].repeat(64, 0).astype(np.float32)
    >>> round(find_lattice([bars]).period[1])
    16
    """
    u, factor = _joint_small(maps, [spread(m) for m in maps], _ANALYSIS)
    acf, _, _ = autocorrelation(u)
    h, w = u.shape[:2]
    found = []
    curves = (acf[:h, 0], acf[0, :w])  # lags 0 .. side - 1
    for curve, n in zip(curves, (h, w)):
        hit = _axis_period(curve[: n // 2 + 1], strength, dip)
        found.append(None if hit is None else (hit[0] * factor, hit[1]))
    return Lattice(tuple(None if f is None else f[0] for f in found),
                   tuple(None if f is None else f[1] for f in found), curves, factor)


def _axis_size(n: int, period: float | None, curve: np.ndarray | None = None, factor: int = 1) -> tuple[int, int]:
    """(tile side, band across the wrap) along one axis of ``n`` px.

    The side is ``count`` periods; with the axis's autocorrelation ``curve``, it is snapped to the
    lag within 3 % where the curve peaks, the lag at which the texture best matches itself (one
    period's error grows ``count`` times, and a few px break a bond across the wrap)."""
    if period is None:  # no repeat: a band of an eighth of the side
        band = max(4, round(n / 8))
        return n - band, band
    min_band = max(4, math.ceil(period / 8))
    count = math.floor((n - min_band) / period)
    side = round(count * period)
    if count >= 2 and curve is not None:
        reach = max(2, math.ceil(0.03 * side / factor))
        lo, hi = max(1, round(side / factor) - reach), min(len(curve) - 2, round(side / factor) + reach)
        if lo < hi:
            top = lo + int(np.argmax(curve[lo: hi + 1]))
            side = min(round(_peak(curve, top) * factor), n - min_band)
    if count < 1 or side < n / 2:
        return 0, 0
    return side, min(n - side, max(min_band, round(period / 4)))


def lattice_tile_size(hw: tuple[int, int], lattice: Lattice) -> tuple[tuple[int, int], tuple[int, int]] | None:
    """((tile_h, tile_w), (band_h, band_w)): whole periods along each repeating axis with room for a
    band across each wrap, or None when the periods do not fit (fewer than half the side in whole periods)."""
    sizes = [_axis_size(n, p, c, lattice.factor) for n, p, c in zip(hw, lattice.period, lattice.curves)]
    if not lattice.found or any(side == 0 for side, _ in sizes):
        return None
    return (sizes[0][0], sizes[1][0]), (sizes[0][1], sizes[1][1])


def box_sums(d: np.ndarray, sy: int, sx: int) -> np.ndarray:
    """Sums of every ``sy`` x ``sx`` window of ``d`` (summed-area table): ``(H - sy + 1, W - sx + 1)``."""
    c = np.pad(d.cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    return c[sy:, sx:] - c[:-sy, sx:] - c[sy:, :-sx] + c[:-sy, :-sx]


def _best_offset(maps: list[np.ndarray], spreads: list[float], tile: tuple[int, int], band: tuple[int, int],
                 margin: int) -> tuple[int, int]:
    """(y, x) of the crop whose bands differ least from their one-tile-on copies (searched on the joint
    features of the maps, box-downsampled to at most _OFFSET_ANALYSIS px), the crop and its copies at
    least ``margin`` px inside the maps along each axis where they fit."""
    H, W = np.asarray(maps[0]).shape[:2]
    m = [margin if n - t - b >= 2 * margin else 0 for n, t, b in zip((H, W), tile, band)]
    u, factor = _joint_small([np.asarray(px)[m[0]: H - m[0], m[1]: W - m[1]] for px in maps], spreads, _OFFSET_ANALYSIS)
    h, w = u.shape[:2]
    th, tw = (max(1, round(t / factor)) for t in tile)
    bh, bw = (max(1, round(b / factor)) for b in band)
    ny, nx = h - th - bh + 1, w - tw - bw + 1
    if ny <= 0 or nx <= 0:
        return m[0], m[1]

    dx = ((u[:, tw:] - u[:, :-tw]) ** 2).sum(-1)  # column x against column x + tile width
    dy = ((u[th:] - u[:-th]) ** 2).sum(-1)
    cost = box_sums(dx, th + bh, bw) / bw + box_sums(dy, bh, tw + bw) / bh  # (ny, nx)
    y, x = np.unravel_index(int(np.argmin(cost)), cost.shape)
    return (m[0] + min(int(y) * factor, H - 2 * m[0] - tile[0] - band[0]),
            m[1] + min(int(x) * factor, W - 2 * m[1] - tile[1] - band[1]))


def _min_path(cost: np.ndarray, start: int | None = None) -> tuple[np.ndarray, float]:
    """For a cost (n, b), the column j(i) of each row on the cheapest path from the first row to the last
    that moves at most one column per row (dynamic programming, as in image quilting), and its cost.
    With ``start``, the path starts at that column and ends within one column of it."""
    n, b = cost.shape
    acc = cost[0].astype(np.float64)
    if start is not None:
        acc = np.where(np.arange(b) == start, acc, np.inf)
    back = np.zeros((n, b), dtype=np.int64)
    cols = np.arange(b)
    choices = np.full((3, b), np.inf)  # from j-1, j, j+1; one buffer (the DP runs row by row in Python)
    for i in range(1, n):
        choices[0, 1:] = acc[:-1]
        choices[1] = acc
        choices[2, :-1] = acc[1:]
        k = np.argmin(choices, axis=0)
        acc = choices[k, cols] + cost[i]
        back[i] = cols + k - 1
    if start is not None:
        acc = np.where(np.abs(cols - start) <= 1, acc, np.inf)
    path = np.empty(n, dtype=np.int64)
    path[-1] = int(np.argmin(acc))
    for i in range(n - 1, 0, -1):
        path[i - 1] = back[i, path[i]]
    return path, float(acc[path[-1]])


def _closed_path(cost: np.ndarray) -> np.ndarray:
    """:func:`_min_path` whose ends meet: the path of a cut that itself crosses a wrap (the y wrap's cut
    runs along the whole tile width, so its last column is the first's neighbour across the x wrap).
    When the free path's ends are more than a column apart, the cheapest of the paths closed at its
    first column, its last, or half-way between them."""
    path, _ = _min_path(cost)
    if abs(int(path[0]) - int(path[-1])) <= 1:
        return path
    starts = {int(path[0]), int(path[-1]), (int(path[0]) + int(path[-1])) // 2}
    return min((_min_path(cost, s) for s in sorted(starts)), key=lambda pc: pc[1])[0]


def _sample(maps: list[np.ndarray], spreads: list[float], y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Joint features (each map over its spread) of the source texels at (y, x)."""
    y, x = np.broadcast_arrays(y, x)
    width = maps[0].shape[1]  # a stack's maps share one grid: one flat index serves them all
    flat = None
    if y.size and min(y.min(), x.min()) >= 0 and x.max() < width:
        flat = (y * width + x).ravel()
    out = []
    for m, s in zip(maps, spreads):
        m = np.asarray(m, dtype=np.float32)
        if flat is not None and m.ndim == 3 and m.shape[1] == width and m.flags.c_contiguous:
            got = m.reshape(-1, m.shape[2]).take(flat, axis=0).reshape(y.shape + m.shape[2:])  # 4x faster
        else:
            got = m[y, x]
        out.append(got / s)
    return np.concatenate(out, axis=-1)


def _unrelated(maps: list[np.ndarray], spreads: list[float], step: int = 4) -> float:
    """The mean squared difference of two unrelated texels of the joint features (each map over its spread, as
    :func:`_sample` reads them): twice their variance, summed over channels, read on every ``step``-th texel."""
    total = 0.0
    for m, s in zip(maps, spreads):
        v = np.asarray(m, dtype=np.float64)[::step, ::step] / s
        total += float(v.reshape(-1, v.shape[-1] if v.ndim == 3 else 1).var(axis=0).sum())
    return 2.0 * total + 1e-12


def lattice_cut(maps: list[np.ndarray], tile: tuple[int, int], band: tuple[int, int], margin: int = CUT_MARGIN,
                differences: dict | None = None) -> tuple[np.ndarray, tuple[int, int]]:
    """The (h, w, 2) int64 source (y, x) of every texel of a tile cut to whole lattice periods, with the
    crop's (y, x) offset.

    The crop sits where its borders match their one-tile-on copies best, at least ``margin`` px inside
    the maps where it fits (their outermost texels are the least trustworthy: resampling filters and
    block compression are clamped there). Across each wrap, the first ``band`` px of the tile choose, along a
    minimum-error boundary cut (Efros and Freeman 2001), between the crop's own texels and those one
    tile on, which continue the opposite border: both sit at the same lattice phase, so the cut runs
    where they agree (mortar beside mortar) and the tile wraps without a seam. Every texel is a source
    texel, the same for every map.

    ``differences``, when given, receives each wrap's join: the mean of the two sides' difference along its cut
    over that of two unrelated texels (``"x"``: the x wrap's, ``"y"``: the y wrap's), as a quilt's joins are
    measured (:func:`.quilt._cut`). Across an axis that repeats it is near 0; across one that does not, it says
    whether the cut hides the join of two unrelated rows or columns.
    """
    (th, tw), (bh, bw) = tile, band
    spreads = [spread(m) for m in maps]
    y0, x0 = _best_offset(maps, spreads, tile, band, margin)
    rows = y0 + np.arange(th + bh)
    # across the x wrap: columns j < cut(y) copy from one tile on, the others are the crop's own
    ys, js = np.meshgrid(rows, np.arange(bw), indexing="ij")
    diff = _sample(maps, spreads, ys, x0 + tw + js) - _sample(maps, spreads, ys, x0 + js)
    cost = (diff ** 2).sum(-1)
    cut, _ = _min_path(cost)  # (th + bh,)
    if differences is not None:
        unrelated = _unrelated(maps, spreads)
        differences["x"] = round(float(cost[np.arange(len(cut)), cut].mean()) / unrelated, 4)
    cols = np.arange(tw)
    fx = x0 + cols[None, :] + tw * (cols[None, :] < cut[:, None])  # (th + bh, tw)
    fy = np.repeat(rows[:, None], tw, axis=1)
    # across the y wrap, on the columns just chosen: rows i < cut(x) copy from one tile down
    diff = _sample(maps, spreads, fy[th:], fx[th:]) - _sample(maps, spreads, fy[:bh], fx[:bh])
    cost = (diff ** 2).sum(-1).T
    cut = _closed_path(cost)  # (tw,): column tw - 1 meets column 0 across the x wrap
    if differences is not None:
        differences["y"] = round(float(cost[np.arange(tw), cut].mean()) / unrelated, 4)
    down = np.arange(th)[:, None] < cut[None, :]  # (th, tw)
    index = np.arange(th)[:, None] + th * down
    field = np.stack([np.take_along_axis(fy, index, 0), np.take_along_axis(fx, index, 0)], axis=-1)
    return field.astype(np.int64), (int(y0), int(x0))


def lattice_ratio(tiles: list[np.ndarray], sources: list[np.ndarray], lattice: Lattice) -> float | None:
    """How much of the source's repeat a periodic tile keeps: along each repeating axis, the tile's
    circular autocorrelation at the lattice period over the source's own at that lag (on the same
    grid, so pass tiles and sources at one resolution, with the periods in px there), the lower of
    the two axes; None when the stack does not repeat. About 1 when every period of the tile lines
    up with the next across the wrap, lower where a bond breaks (the tile's side not a whole number
    of periods, or a layout that lost the lattice).

    >>> x = np.arange(96)
    >>> bars = np.sin(2 * np.pi * x / 16)[None, :, None].repeat(64, 0).astype(np.float32)
    >>> lattice = find_lattice([bars])
    >>> round(lattice_ratio([bars], [bars], lattice), 2), round(lattice_ratio([bars[:, :88]], [bars], lattice), 2)
    (1.0, 0.63)
    """
    if not lattice.found:
        return None
    u, v = joint_features(tiles, like=sources), joint_features(sources)
    u, v = u - u.mean(axis=(0, 1)), v - v.mean(axis=(0, 1))
    tile_energy, source_energy = float((u * u).sum(-1).mean()), float((v * v).sum(-1).mean())
    ratios = []
    for axis, period in enumerate(lattice.period):
        if period is None:
            continue
        lag = int(round(period))
        tile_corr = float((u * np.roll(u, -lag, axis=axis)).sum(-1).mean()) / max(tile_energy, 1e-12)
        n = v.shape[axis]
        ahead = np.take(v, range(lag, n), axis=axis) * np.take(v, range(0, n - lag), axis=axis)
        source_corr = float(ahead.sum(-1).mean()) / max(source_energy, 1e-12)
        ratios.append(tile_corr / max(source_corr, 1e-6))
    return min(ratios)
