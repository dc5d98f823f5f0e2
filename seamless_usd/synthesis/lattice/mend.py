"""Keep the photo, mend its joins: the source rolled by half, with a band over the seams re-laid from itself.

What an artist does by hand (and GIMP's Resynthesizer does for them): offset the photo by half its size,
so that its own wrap is seamless and its edges meet in a cross in the middle, then paint over that cross
from the rest of the photo. Everything else stays where the photographer put it: every pepper, stone and
plank end whole, at the source's scale, in the source's light.

1. The tile is the source rolled by (H // 2, W // 2): its wraps are the source's interior, seamless; the
   source's edges meet along one row and one column of the tile, the seams.
2. A band of ``2 * core`` texels over each seam is cleared, and re-laid with blocks of the source (image
   quilting, Efros and Freeman 2001, constrained to a band): along the vertical seam, blocks as wide as the
   band plus an ``overlap`` on each side, ``segment`` texels tall, each the source window that agrees best
   with what lies already in its overlaps (the kept photo left and right, the block above; the last one
   also the first, across the wrap). Then the same along the horizontal seam, crossing the blocks just laid.
3. Each overlap is resolved by the cheapest path of texels through the two sides' difference (the quilt's
   cut, :func:`.quilt._cut`): the mend ends where the photo and the block agree, along a joint between
   stones or the edge of a fruit, not along a straight line.

Every texel is a source texel, copied through one field for every map, so the maps stay aligned and keep
their values, and the verdict can find the copies and judge the joins. The figures are the quilt's: each
join's cost and difference (over two unrelated texels' difference), their mean and worst, so
:func:`..candidates.joins_hide` applies as to a quilt.
"""
from __future__ import annotations

import numpy as np

from .cut import CUT_MARGIN, _closed_path, _sample
from .quilt import _Canvas, _bounds, _cut, _place, search_levels

__all__ = ["MEND_OVERLAP", "MEND_CORE", "MEND_SEGMENT", "mend_field", "best_mend"]

#: The overlap (share of the source's shorter side) on each side of a seam where the mend's joins may run.
MEND_OVERLAP = 0.06
#: Texels cleared on each side of a seam (share of the overlap): what no join may keep.
MEND_CORE = 0.25
#: Length of each block along its seam, in overlaps.
MEND_SEGMENT = 3.0
_EDGE = 4.0  # what a texel on an overlap's first or last line costs the cut, over two unrelated texels' difference


def _seams(H: int, W: int) -> tuple[int, int]:
    """Tile row and column where the rolled source's edges meet (its last texel before, its first after)."""
    return H - H // 2, W - W // 2


def _strip_index(along_y: bool, first: int, length: int, width: int, hw: tuple[int, int]
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Tile (rows, cols), each (length, width), of a band ``width`` texels across, from ``first`` across the seam,
    and ``length`` along it: the band's own coordinates are (along, across)."""
    t, k = np.arange(length)[:, None], (first + np.arange(width))[None, :]
    if along_y:
        return np.broadcast_to(t % hw[0], (length, width)), np.broadcast_to(k % hw[1], (length, width))
    return np.broadcast_to(k % hw[0], (length, width)), np.broadcast_to(t % hw[1], (length, width))


class _Mend:
    """What every band of one mend shares: the source and its search levels, the tile's canvas, the blocks used."""

    def __init__(self, maps: list[np.ndarray], o: int, b: int, seg: int, seed: int, margin: int, prepared: tuple):
        self.maps, self.o, self.b, self.seg, self.margin = maps, o, b, seg, margin
        H, W = maps[0].shape[:2]
        self.spreads, self.levels, self.unrelated = prepared
        self.rng = np.random.default_rng(seed)
        self.canvas = _Canvas((H, W))
        self.used: list[tuple[int, int]] = []
        self.blocks: list[list[int]] = []
        self.joins: list[dict] = []

    def features(self, field: np.ndarray) -> np.ndarray:
        return _sample(self.maps, self.spreads, field[..., 0], field[..., 1])

    def edged(self, diff: np.ndarray) -> np.ndarray:
        """A band's cost (rows along the join) with its first and last columns made dear: a join there would run
        straight along a block's or the band's edge."""
        d = diff.copy()
        d[:, [0, -1]] += _EDGE * self.unrelated
        return d

    def cut(self, diff: np.ndarray) -> tuple[np.ndarray, float, float]:
        """:func:`.quilt._cut` on a band (rows along the join, its first column the side kept), never along its
        edges (:meth:`edged`)."""
        return _cut(self.edged(diff), None, None, self.unrelated, 0)

    def band(self, along_y: bool, seam: int) -> None:
        """Clear and re-lay the band over one seam (along y: the seam is tile column ``seam``): blocks along it,
        each cut against the one before; then one closed cut on each side between the band and what lies there."""
        canvas, o, b = self.canvas, self.o, self.b
        H, W = canvas.hw
        length, width, first = (H if along_y else W), 2 * (b + o), seam - b - o
        ty, tx = _strip_index(along_y, first, length, width, (H, W))
        strip, have = np.zeros((length, width, 2), dtype=np.int64), np.zeros((length, width), dtype=bool)
        n = max(2, round(length / self.seg))
        bounds = _bounds(length, n)
        view = _Canvas((H, W))  # what the search sees: the tile with the band's blocks laid so far over it
        view.field, view.laid = canvas.field.copy(), canvas.laid.copy()
        for i in range(n):
            size_along = bounds[i + 1] - bounds[i] + o
            rows = (bounds[i] + np.arange(size_along)) % length  # the block's rows of the strip
            top, left = (bounds[i], first) if along_y else (first, bounds[i])
            size = (size_along, width) if along_y else (width, size_along)
            py, px = _place(view, top, left, size, self.levels, self.maps, self.spreads, self.used, self.rng,
                            self.margin)
            self.used.append((py, px))
            self.blocks.append([int(py), int(px)])
            dt, dk = np.mgrid[0:size_along, 0:width]
            block = np.stack([py + dt, px + dk] if along_y else [py + dk, px + dt], -1)
            laid = have[rows]
            diff = ((self.features(block) - self.features(strip[rows])) ** 2).sum(-1) * laid
            keep = np.ones((size_along, width), dtype=bool)
            if i > 0:  # the block before, along the first overlap
                near, cost, difference = self.cut(diff[:o].T)
                keep[:o] &= ~near.T
                self.joins.append({"seam": "x" if along_y else "y", "block": i, "side": "before",
                                   "cost": round(cost, 4), "difference": round(difference, 4)})
            if i == n - 1:  # the first block, across the band's own wrap
                near, cost, difference = self.cut(diff[-o:].T[:, ::-1])
                keep[-o:] &= ~near[:, ::-1].T
                self.joins.append({"seam": "x" if along_y else "y", "block": i, "side": "after",
                                   "cost": round(cost, 4), "difference": round(difference, 4)})
            keep |= ~laid
            strip[rows[:, None], dk[:1]] = np.where(keep[..., None], block, strip[rows])
            have[rows] |= keep
            vy, vx = ty[rows][keep], tx[rows][keep]
            view.field[vy, vx], view.laid[vy, vx] = strip[rows][keep], True
        # the band against what lies on each side of it: one closed path along the whole seam
        had = canvas.field[ty, tx]
        diff = ((self.features(strip) - self.features(had)) ** 2).sum(-1) * canvas.laid[ty, tx]
        use = np.zeros((length, width), dtype=bool)
        use[:, o: width - o] = True
        laid_here = canvas.laid[ty, tx]
        for side in ("before", "after"):
            near = (lambda a: a[:, :o]) if side == "before" else (lambda a: a[:, -o:][:, ::-1])  # side's texels first
            path = _closed_path(self.edged(near(diff)) + 1e-3 * self.unrelated)
            mine = np.arange(o)[None, :] >= path[:, None]  # the band from the path on, the side's texels before it
            if side == "before":
                use[:, :o] |= mine
            else:
                use[:, -o:] |= mine[:, ::-1]
            rows = np.arange(length)
            at = near(diff)[rows, path][near(laid_here)[rows, path]]
            difference = float(at.mean()) / self.unrelated if at.size else 0.0
            self.joins.append({"seam": "x" if along_y else "y", "block": None, "side": f"across {side}",
                               "cost": round(difference, 4), "difference": round(difference, 4)})
        canvas.field[ty[use], tx[use]] = strip[use]
        canvas.laid[ty[use], tx[use]] = True


def mend_field(maps: list[np.ndarray], overlap: float = MEND_OVERLAP, core: float = MEND_CORE,
               segment: float = MEND_SEGMENT, seed: int = 0, margin: int = CUT_MARGIN, prepared: tuple | None = None
               ) -> tuple[np.ndarray, dict] | None:
    """The (H, W, 2) int64 source (y, x) of every texel of the source rolled by half with its seams mended (see
    the module notes), and figures: ``joins`` (each join with its cost and difference), their mean and worst,
    the worst difference, the blocks' source places, the band (core, overlap); None when the source is too
    small for a block. ``prepared``: the maps' :func:`.quilt.search_levels`, when several mends share them.

    >>> rng = np.random.default_rng(0)
    >>> noise = rng.normal(size=(128, 128, 1)).astype(np.float32)
    >>> field, figures = mend_field([noise])
    >>> field.shape, figures["band"]
    ((128, 128, 2), [2, 8])
    """
    maps = [np.asarray(m) for m in maps]
    H, W = maps[0].shape[:2]
    o = max(4, round(min(H, W) * overlap))
    b = max(2, round(o * core))
    seg = max(2 * o, round(o * segment))
    if 2 * (b + o) + seg > min(H, W) - 2 * margin:
        return None
    mend = _Mend(maps, o, b, seg, seed, margin, prepared or search_levels(maps))
    canvas = mend.canvas
    cy, cx = _seams(H, W)
    canvas.field[..., 0] = ((np.arange(H) + H // 2) % H)[:, None]
    canvas.field[..., 1] = ((np.arange(W) + W // 2) % W)[None, :]
    canvas.laid[:] = True
    canvas.laid[cy - b: cy + b, :] = False
    canvas.laid[:, cx - b: cx + b] = False
    mend.band(True, cx)  # the vertical seam's band, then the horizontal one's, across it
    mend.band(False, cy)
    costs, differences = [j["cost"] for j in mend.joins], [j["difference"] for j in mend.joins]
    figures = {"band": [b, o], "segment": seg, "blocks": mend.blocks, "joins": mend.joins,
               "join_mean": round(float(np.mean(costs)), 4), "join_worst": round(float(np.max(costs)), 4),
               "difference_worst": round(float(np.max(differences)), 4)}
    return canvas.field, figures


def best_mend(maps: list[np.ndarray], tries: int, seed: int = 0) -> tuple[np.ndarray, dict] | None:
    """Of ``tries`` mends (seeds ``seed``, ``seed + 1``, ...), the one whose worst join costs least, then whose
    mean join does; None when the source is too small for one."""
    prepared = search_levels([np.asarray(m) for m in maps])  # the same for every seed
    made = [m for m in (mend_field(maps, seed=seed + k, prepared=prepared) for k in range(tries)) if m is not None]
    if not made:
        return None
    return min(made, key=lambda m: (m[1]["join_worst"], m[1]["join_mean"]))
