"""Stacks with long structure and no lattice: a tile quilted on a torus from a few large source blocks.

The refinement's tile is a mosaic of hundreds of copied blocks, each 10-30 px, and its joins cut stones
and plank gaps wherever they fall (``benchmarks/experiments/results/levers.md``). The window cut makes two joins but
only hides them where the texture continues itself at some lag (:mod:`.window`). This candidate is the
step between: image quilting (Efros and Freeman 2001) with a handful of blocks, each large enough to hold
several stones or a run of plank, laid on a torus:

1. the tile is split into ``ny`` x ``nx`` cells; each cell's block is one window of the source, larger
   than its cell by an overlap band that reaches into the next cell (and across the wrap, into the first);
2. blocks are placed in raster order. Each is the source window that agrees best with the texels already
   laid in its overlap bands (left and top; the last column and row also right and bottom, across the
   wrap, which closes the torus), searched over every source position at a coarse grid (FFT) and then
   refined down to the texel (:func:`_place`); a random one among those within a tenth of the best, and
   not a window half or more of which an earlier block took while another is as good (:func:`_pick`);
3. each overlap band is resolved by the cheapest 8-connected path of texels through the two blocks'
   difference (Dijkstra on the band: a graph cut's dual, free to turn, so it can run along a joint or a
   plank gap of any direction, where a one-column-per-row path as the lattice cut's cannot).

Every texel is a source texel, copied through one field for all maps, so the maps stay aligned and keep
their values (bit depth, unit normals); the tile wraps by construction, its wraps being joins like the
others. ``figures`` records every join's cost and difference (over the difference between unrelated
texels): where the two blocks differ along a cut, the cut cannot hide the join, and the verdict misses
some such joins (``benchmarks/experiments/results/quilt_gate.md``); ``..tile`` weighs the quilt against the refined
tile and never writes one whose joins do not hide as a tile that passes.

A lever measured and not kept (``lines=True``): cuts that run almost free along the texture's long lines
(:func:`line_mask`), each block keeping its own line texels near the cut, so a join hides behind a joint.
Stones stay whole, but the joints thicken, fork and leave slivers, and every figure reads worse
(``benchmarks/experiments/results/levers_quilt.md``, ``levers_quilt_fullres.md``). Another (``deform``): each new block's
texels near its joins shifted to line up with the laid ones (:mod:`.deform`); its rounded shifts step
lines, and it cannot add the stripe or head joint that one block lacks (``levers_quilt_deform.md``).
"""
from __future__ import annotations

import math

import numpy as np

from ..refinement.refine import spread
from ..scale import box_downsample
from .cut import CUT_MARGIN, _sample
from .lines import long_share, principal_tone

__all__ = ["QUILT_OVERLAP", "LINE_SHARE", "LINE_LONG", "line_sigma", "line_mask", "quilt_field", "best_quilt",
           "quilt_order"]

#: The overlap band between neighbouring blocks, as a share of the cell: where the cut may run.
QUILT_OVERLAP = 0.25
_ANALYSIS = 192  # longest side (px) of the coarse search over every source position
#: Share of the source's texels (its darkest or brightest) taken as its lines, along which a cut runs almost free.
LINE_SHARE = 0.2
#: A lines' pieces must hold this share of its texels for the source to have lines (see :func:`line_mask`).
LINE_LONG = 0.5
#: What a texel on a line costs the cut at most, over the difference of two unrelated texels.
_ON_LINE = 0.02
_TOLERANCE = 0.1  # blocks within this share of the best overlap error are equally good (Efros and Freeman)


def _bounds(n: int, cells: int) -> list[int]:
    return [round(i * n / cells) for i in range(cells + 1)]


def _levels(maps: list[np.ndarray], spreads: list[float], coarsest: int) -> list[tuple[np.ndarray, int]]:
    """Joint features (each map over its spread) box-halved to factors 2, 4, ... up to ``coarsest``,
    finest first; each map is halved on its own, so the full-resolution joint features are never held."""
    per_map, out, factor = [np.asarray(m, dtype=np.float32) / s for m, s in zip(maps, spreads)], [], 1
    while factor < coarsest:
        per_map = [box_downsample(p, max(p.shape[:2]) - 1)[0] for p in per_map]
        factor *= 2
        out.append((np.concatenate(per_map, axis=-1), factor))
    return out


def search_levels(maps: list[np.ndarray]) -> tuple[list[float], list[tuple[np.ndarray, int]], float]:
    """What a block search over ``maps`` needs, the same for every block and every seed: each map's spread, the
    joint features halved down to the coarse search's size (:func:`_levels`; the full resolution itself for a
    source already that small), and the squared difference of two unrelated texels (the unit of every join's
    cost)."""
    H, W = maps[0].shape[:2]
    spreads = [spread(m) for m in maps]
    coarsest = 1
    while max(H, W) / coarsest > _ANALYSIS:
        coarsest *= 2
    levels = _levels(maps, spreads, coarsest) or [(_sample(maps, spreads, *np.mgrid[0:H, 0:W]), 1)]
    flat = levels[-1][0].reshape(-1, levels[-1][0].shape[-1])
    return spreads, levels, 2.0 * float(flat.var(axis=0).sum()) + 1e-12


def line_sigma(overlap: tuple[int, int]) -> float:
    """The high-pass scale (px) of :func:`line_mask` for a quilt whose overlap bands are ``overlap`` px."""
    return max(2.0, min(overlap) / 8)


def line_mask(maps: list[np.ndarray], sigma: float) -> np.ndarray | None:
    """Bool (H, W): the source's long lines, or None when it has none.

    Lines are the darkest or the brightest :data:`LINE_SHARE` of the maps' first principal channel (jointly,
    each over its spread) after a high-pass at ``sigma`` px, opened and closed to drop grain and speckle:
    joints between stones, plank gaps, mortar. The polarity kept is the one whose texels lie mostly (at least :data:`LINE_LONG`) in
    pieces that span a quarter of the map; short strokes of grain or pores do not make lines."""
    from scipy import ndimage

    u = principal_tone(maps)
    u = ndimage.gaussian_filter(u, sigma / 8, mode="reflect")  # the lines' edges smooth, not the grain's noise
    hp = u - ndimage.gaussian_filter(u, sigma, mode="reflect")
    sample = hp[:: max(1, hp.shape[0] // 512), :: max(1, hp.shape[1] // 512)]
    r = max(1, round(sigma / 8))
    best, best_share = None, LINE_LONG
    for mask in (hp < np.quantile(sample, LINE_SHARE), hp > np.quantile(sample, 1 - LINE_SHARE)):
        mask = ndimage.binary_closing(ndimage.binary_opening(mask, iterations=r), iterations=r)
        share = long_share(mask)
        if share >= best_share:
            best, best_share = mask, share
    # with the lines' soft edges, so a block that keeps its line keeps all of it
    return None if best is None else ndimage.binary_dilation(best, iterations=r)


class _Canvas:
    """The tile's field (source y, x of every texel) and which texels are laid, on a torus."""

    def __init__(self, hw: tuple[int, int]):
        self.hw = hw
        self.field = np.zeros((*hw, 2), dtype=np.int64)
        self.laid = np.zeros(hw, dtype=bool)

    def rows_cols(self, top: int, left: int, size: tuple[int, int], step: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Tile rows and columns of a block at (top, left) of ``size``, every ``step``-th texel (its centre)."""
        off = step // 2
        return ((top + off + np.arange(0, size[0] - off, step)) % self.hw[0],
                (left + off + np.arange(0, size[1] - off, step)) % self.hw[1])


def _cost_at(level: np.ndarray | None, maps: list[np.ndarray], spreads: list[float],
             template: np.ndarray, mask: np.ndarray, places: list[tuple[int, int]]) -> np.ndarray:
    """The overlap error of a block at each of ``places`` (level px), for the laid texels ``mask`` whose
    features are ``template``."""
    ay, ax = np.nonzero(mask)
    want = template[ay, ax]
    out = np.empty(len(places))
    for k, (py, px) in enumerate(places):
        got = level[py + ay, px + ax] if level is not None else _sample(maps, spreads, py + ay, px + ax)
        out[k] = float(((got - want) ** 2).sum())
    return out


def _coarse_costs(level: np.ndarray, template: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The overlap error of a block at every place of ``level`` (FFT correlation): (h - bh + 1, w - bw + 1)."""
    from scipy.signal import fftconvolve  # here, not at import: scipy.signal alone takes 0.8 s to import

    m = mask.astype(np.float32)
    flip = (slice(None, None, -1), slice(None, None, -1))
    total = float((m[..., None] * template ** 2).sum())
    cost = fftconvolve((level ** 2).sum(-1), m[flip], mode="valid") + total
    for c in range(level.shape[-1]):
        cost -= 2 * fftconvolve(level[..., c], (m * template[..., c])[flip], mode="valid")
    return cost


def _pick(cost: np.ndarray, lo: tuple[int, int], g: int, size: tuple[int, int], used: list[tuple[int, int]],
          rng: np.random.Generator) -> tuple[int, int]:
    """A coarse place (level px, from ``lo``) at random among those within the tolerance of the cheapest whose
    window does not repeat an earlier block's (``used``, source px: at least half a block away along an axis);
    when every such place does, the cheapest one that does not, if any."""
    def fresh(k: tuple[int, int]) -> bool:
        return all(abs((k[0] + lo[0]) * g - uy) >= size[0] / 2 or abs((k[1] + lo[1]) * g - ux) >= size[1] / 2
                   for uy, ux in used)

    ys, xs = np.nonzero(cost <= cost.min() + _TOLERANCE * max(abs(float(cost.min())), 1e-6))
    good = [k for k in zip(ys.tolist(), xs.tolist()) if fresh(k)]
    if not good:
        order = [divmod(int(k), cost.shape[1]) for k in np.argsort(cost, axis=None)[:4096]]
        good = [next((k for k in order if fresh(k)), order[0])]
    y, x = good[int(rng.integers(len(good)))]
    return y + lo[0], x + lo[1]


def _place(canvas: _Canvas, top: int, left: int, size: tuple[int, int],
           levels: list[tuple[np.ndarray, int]], maps: list[np.ndarray], spreads: list[float],
           used: list[tuple[int, int]], rng: np.random.Generator, margin: int) -> tuple[int, int]:
    """Source (y, x) of the block at tile (top, left): the coarse place among those within the
    tolerance of the best (not overlapping an earlier block's window when another is as good), then
    refined level by level to the texel."""
    H, W = maps[0].shape[:2]
    fy, fx = canvas.field[..., 0], canvas.field[..., 1]
    place = None
    stages = [*reversed(levels)] + ([(None, 1)] if levels[0][1] > 1 else [])
    for level, g in stages:
        rows, cols = canvas.rows_cols(top, left, size, g)
        mask = canvas.laid[np.ix_(rows, cols)]
        bh, bw = mask.shape
        n_y, n_x = (H, W) if level is None else level.shape[:2]
        lo = (math.ceil(margin / g),) * 2
        hi = (min((H - margin - size[0]) // g, n_y - bh), min((W - margin - size[1]) // g, n_x - bw))
        if level is None:
            template = _sample(maps, spreads, fy[np.ix_(rows, cols)], fx[np.ix_(rows, cols)])
        else:
            template = level[np.minimum(fy[np.ix_(rows, cols)] // g, level.shape[0] - 1),
                             np.minimum(fx[np.ix_(rows, cols)] // g, level.shape[1] - 1)]
        if place is None:  # the coarsest level: every place
            if not mask.any():
                cost = rng.random((hi[0] - lo[0] + 1, hi[1] - lo[1] + 1))
            else:
                cost = _coarse_costs(level, template, mask)[lo[0]: hi[0] + 1, lo[1]: hi[1] + 1]
            place = _pick(cost, lo, g, size, used, rng)
            coarse = g
            continue
        # one level finer: the places that fall in the coarser place's texel, and one more on each side
        step = coarse // g
        around = [(min(max(place[0] * step + dy, lo[0]), hi[0]), min(max(place[1] * step + dx, lo[1]), hi[1]))
                  for dy in range(-1, step + 1) for dx in range(-1, step + 1)]
        around = sorted(set(around))
        cost = _cost_at(level, maps, spreads, template, mask, around) if mask.any() else np.zeros(len(around))
        place, coarse = around[int(np.argmin(cost))], g
    return place


def _cut(diff: np.ndarray, near_lines: np.ndarray | None, far_lines: np.ndarray | None, unrelated: float,
         reach: int) -> tuple[np.ndarray, float, float]:
    """(near, cost, difference) for a band (rows along the join, the band across it, its first column on the
    side of the block called near): True where the near block is kept, the join's cost (the mean along the
    cut of what it minimised) and its difference (the mean of the blocks' difference along the cut), each
    over the difference of two unrelated texels.

    The cut is the cheapest 8-connected path of texels from the band's first row to its last (Dijkstra on
    the band's texels, a graph cut's dual): free to run along the band or turn back, so it follows a joint
    of any direction. A texel costs the two blocks' difference there; with lines (:func:`line_mask`), almost
    nothing where either block has one, since a join along a joint or a plank gap hides behind it. Each
    block then keeps its own line texels within ``reach`` of the path, so the line shows whole."""
    from scipy import ndimage

    cost = diff
    if near_lines is not None:
        cost = np.where(near_lines | far_lines, np.minimum(diff, _ON_LINE * unrelated), diff)
    path = _free_path(cost + 1e-3 * unrelated)  # a little for every texel: the shorter of equal paths
    labels, _ = ndimage.label(~path)
    near = np.isin(labels, np.unique(labels[:, 0][labels[:, 0] > 0]))
    if near_lines is not None:
        close = ndimage.binary_dilation(path, iterations=reach)
        near = (near | (close & near_lines)) & ~(close & far_lines & ~near_lines)
    return near, float(cost[path].mean()) / unrelated, float(diff[path].mean()) / unrelated


def _free_path(cost: np.ndarray) -> np.ndarray:
    """Bool (n, b): the cheapest 8-connected path of texels from row 0 to row n - 1 through ``cost`` (n, b)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    n, b = cost.shape
    idx = np.arange(n * b).reshape(n, b)
    src, dst = [], []
    for dy, dx in ((0, 1), (1, -1), (1, 0), (1, 1)):
        a = idx[0: n - dy, max(0, -dx): b - max(0, dx)].ravel()
        o = idx[dy: n, max(0, dx): b - max(0, -dx)].ravel()
        src += [a, o]
        dst += [o, a]
    start = n * b  # joined to every texel of the first row
    src.append(np.full(b, start))
    dst.append(idx[0])
    s, d = np.concatenate(src), np.concatenate(dst)
    graph = coo_matrix((cost.astype(np.float64).ravel()[d], (s, d)), shape=(n * b + 1, n * b + 1)).tocsr()
    dist, pred = dijkstra(graph, indices=start, return_predecessors=True)
    end = int(idx[-1][np.argmin(dist[idx[-1]])])
    path = np.zeros(n * b, dtype=bool)
    while end != start and end >= 0:
        path[end] = True
        end = int(pred[end])
    return path.reshape(n, b)


def quilt_field(maps: list[np.ndarray], tile_hw: tuple[int, int], cells: tuple[int, int],
                overlap: float = QUILT_OVERLAP, seed: int = 0, margin: int = CUT_MARGIN, lines: bool = False,
                deform: float = 0.0) -> tuple[np.ndarray, dict] | None:
    """The (h, w, 2) int64 source (y, x) of every texel of a ``tile_hw`` tile quilted from ``cells`` =
    (ny, nx) blocks (see the module notes), with figures: ``joins``, each overlap's cut with its cost (the
    mean along it of what it minimised, over the squared difference of two unrelated texels) and its
    difference (the mean of the two blocks' squared difference along it, in the same units: where the cut
    follows lines, the cost is low by design and the difference says what the lines hide); the costs'
    mean and worst, the worst difference, and the blocks' source places; None when a block does not fit
    in the source. ``lines=True``: where the source has long lines (:func:`line_mask`), the cuts run along
    them (a lever measured, not the product's: ``benchmarks/experiments/results/levers_quilt.md``). ``deform`` > 0: each
    new block's texels near its joins shift, by at most that share of the band, to line up with the laid
    ones (:mod:`.deform`; a lever, not the product's: ``levers_quilt_deform.md``).

    >>> rng = np.random.default_rng(0)
    >>> noise = rng.normal(size=(96, 96, 1)).astype(np.float32)
    >>> field, figures = quilt_field([noise], (96, 96), (2, 2))
    >>> field.shape, len(figures["blocks"])
    ((96, 96, 2), 4)
    """
    maps = [np.asarray(m) for m in maps]
    H, W = maps[0].shape[:2]
    th, tw = tile_hw
    ys, xs = _bounds(th, cells[0]), _bounds(tw, cells[1])
    oy = max(2, round(th / cells[0] * overlap))
    ox = max(2, round(tw / cells[1] * overlap))
    big = (max(ys[i + 1] - ys[i] for i in range(cells[0])) + oy, max(xs[j + 1] - xs[j] for j in range(cells[1])) + ox)
    if big[0] > H - 2 * margin or big[1] > W - 2 * margin:
        return None
    spreads, levels, unrelated = search_levels(maps)
    lines = line_mask(maps, line_sigma((oy, ox))) if lines else None
    reach = max(2, min(oy, ox) // 10)
    rng = np.random.default_rng(seed)
    canvas = _Canvas((th, tw))
    used: list[tuple[int, int]] = []
    joins, blocks = [], []
    for i in range(cells[0]):
        for j in range(cells[1]):
            size = (ys[i + 1] - ys[i] + oy, xs[j + 1] - xs[j] + ox)
            rows, cols = canvas.rows_cols(ys[i], xs[j], size)
            laid = canvas.laid[np.ix_(rows, cols)]
            py, px = _place(canvas, ys[i], xs[j], size, levels, maps, spreads, used, rng, margin)
            used.append((py, px))
            blocks.append([int(py), int(px)])
            by, bx = np.mgrid[0:size[0], 0:size[1]]
            had = canvas.field[np.ix_(rows, cols)]
            laid_features = _sample(maps, spreads, had[..., 0], had[..., 1])
            # each side the block shares with one laid before: (name, band, whether the join runs across the
            # tile's rows, so that the band is turned to have its rows along the join, whether it is there)
            sides = [("left", np.s_[:, :ox], False, j > 0), ("top", np.s_[:oy, :], True, i > 0),
                     ("right", np.s_[:, -ox:], False, j == cells[1] - 1 and cells[1] > 1),
                     ("bottom", np.s_[-oy:, :], True, i == cells[0] - 1 and cells[0] > 1)]
            sy, sx = py + by, px + bx
            if deform > 0:  # a lever (deform.py): the block's texels near each join line up with the laid ones
                from .deform import join_shifts

                bands = [(name, oy if across else ox) for name, _, across, present in sides if present]
                dy, dx = join_shifts(laid_features, laid, (py, px), bands,
                                     lambda y, x: _sample(maps, spreads, y, x), (H, W),
                                     max(1, round(deform * min(oy, ox))), unrelated)
                sy, sx = np.clip(sy + dy, 0, H - 1), np.clip(sx + dx, 0, W - 1)
            diff = ((_sample(maps, spreads, sy, sx) - laid_features) ** 2
                    ).sum(-1) * laid  # texels not laid yet cost nothing to cover
            new_lines = old_lines = None
            if lines is not None:
                new_lines, old_lines = lines[sy, sx], lines[had[..., 0], had[..., 1]] & laid
            keep = np.ones(size, dtype=bool)
            for name, band, across, present in sides:
                if not present:
                    continue
                turn = (lambda a: a.T) if across else (lambda a: a)  # rows along the join
                flip = (lambda a: a[:, ::-1]) if name in ("right", "bottom") else (lambda a: a)  # laid block near
                view = lambda a: flip(turn(a[band]))  # noqa: E731
                near, cost, difference = _cut(view(diff), None if lines is None else view(old_lines),
                                              None if lines is None else view(new_lines), unrelated, reach)
                keep[band] &= turn(flip(~near))
                joins.append({"block": [i, j], "side": name, "cost": round(cost, 4), "difference": round(difference, 4)})
            keep |= ~laid  # what no block covers yet is this block's
            tr, tc = np.meshgrid(rows, cols, indexing="ij")
            canvas.field[tr[keep], tc[keep]] = np.stack([sy[keep], sx[keep]], -1)
            canvas.laid[tr[keep], tc[keep]] = True
    costs, differences = [j["cost"] for j in joins], [j["difference"] for j in joins]
    figures = {"cells": list(cells), "overlap": [oy, ox], "blocks": blocks, "joins": joins, "lines": lines is not None,
               "join_mean": round(float(np.mean(costs)), 4) if costs else 0.0,
               "join_worst": round(float(np.max(costs)), 4) if costs else 0.0,
               "difference_worst": round(float(np.max(differences)), 4) if differences else 0.0}
    return canvas.field, figures


def best_quilt(maps: list[np.ndarray], tile_hw: tuple[int, int], cells: tuple[int, int], tries: int, seed: int = 0,
               lines: bool = False, deform: float = 0.0) -> tuple[np.ndarray, dict] | None:
    """Of ``tries`` quilts (seeds ``seed``, ``seed + 1``, ...), the one whose worst join costs least, then
    whose mean join does (:func:`quilt_field`, ``lines`` as there); None when a block does not fit."""
    made = [q for q in (quilt_field(maps, tile_hw, cells, seed=seed + k, lines=lines, deform=deform)
                        for k in range(tries))
            if q is not None]
    if not made:
        return None
    return min(made, key=lambda q: quilt_order(q[1]))


def quilt_order(figures: dict) -> tuple[float, float]:
    """How quilts rank (the lowest is kept), from their figures: the worst join's cost, then the mean's."""
    return figures["join_worst"], figures["join_mean"]
