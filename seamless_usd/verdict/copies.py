"""Seams of a tile made of the source's own texels (refined, cut, or a window used as a tile).

Every texel of such a tile is a copy of a source texel, so where it came from can be looked up exactly
(3 x 3 neighbourhoods, hashed, quantised to 8 bits so that a tile written to a file and read back still
matches). Across a line between two texels copied from places that are not neighbours in the source,
the join is judged by what the source itself would have put there: the *continuation error* is the
difference between the texel the tile has beside the line and the texel the source has beside the other
one's origin, in units of the source's own neighbour difference across lines of that direction (a
texture of horizontal streaks changes more from row to row than along a row). A cut placed where two copies agree
(the lattice cut along a mortar joint) reads near 0; a join of unrelated places reads like unrelated
texels, far above 1. A seam is a run of a line whose mean continuation error exceeds
:data:`COPY_THRESHOLD`.

A tile whose texels near its joins were blended (the refinement's gradient-domain band) is a tile of
copies with a few new values. A texel not found in the source within :data:`INFER` texels of found ones
takes its found neighbour's origin, moved by one (*inferred*). Across a line with a texel that is not an
exact copy of its origin, the error is read on the *step* instead: the difference between the tile's
step across the line and the step the source takes there (from either side's origin). For exact copies
this is the same figure as the value error; for a blended band it is what the blend could not make
look like the source: a tone step spread evenly over the band reads a fraction of its size on each
line, a structure that does not continue reads as before.
"""
from __future__ import annotations

import numpy as np

from .features import moving_mean
from .lines import Seam

__all__ = ["COPY_SHARE", "COPY_THRESHOLD", "EXACT_SHARE", "INFER", "MAP_THRESHOLD", "SourceIndex", "continuation",
           "copy_origins", "copy_seams", "sampled_share", "step_unit"]

#: Share of a tile's texels that must be placed in the source (found or inferred) for the tile to be judged
#: as copies.
COPY_SHARE = 0.9
#: Share that must be found exactly: the rest may be inferred (a blended band).
EXACT_SHARE = 0.5
#: Texels (each side of a join) over which an origin is inferred: more than a blend band's width.
INFER = 8
#: A texel within this of its origin's value in every channel (one 8-bit code, network domain) is an exact copy.
EXACT_TOL = 1.0 / 127.5
#: How far (in the source's mean steps) an inferred texel's value may lie from its origin's: a blend moves a
#: texel by at most half the step it spreads, so a join up to twice this is placed across its whole band; a
#: candidate further off is another place (a flat area's arbitrary origin next to a joint).
INFER_UNITS = 4.0
#: A 3 x 3 neighbourhood spanning fewer 8-bit codes than this is flat: where it was found is not certain.
FLAT_CODES = 4
#: Mean continuation error over a run (source neighbour-difference units) above which a run is a seam: the
#: lattice cuts of the tuning textures read at most 0.59 (0.64 with their joins blended), their blocky
#: refinements 1.19 and more, blended or not (``benchmarks/results/verdict.md``).
COPY_THRESHOLD = 0.9
#: The same for one map alone: its own neighbour difference is a noisier unit than the maps' together, and
#: the lattice cuts of the six quality-benchmark stacks read up to 1.01 on one map (0.77 together).
MAP_THRESHOLD = 1.2


def _keys(img: np.ndarray, periodic: bool) -> np.ndarray:
    """One 64-bit key per texel for its 3 x 3 neighbourhood, 8-bit quantised ((H, W) or (H-2, W-2)).

    Built one channel at a time from 8-bit codes (the sums wrap the same in any order), so a 4K stack of
    seven channels never holds a 64-bit copy of all of them."""
    q = _quantised(img).astype(np.uint8)  # network domain -> 0..255
    rng = np.random.default_rng(12345)
    weights = rng.integers(1, 1 << 61, size=(9, q.shape[-1]), dtype=np.int64) | 1
    if periodic:
        q = np.pad(q, ((1, 1), (1, 1), (0, 0)), mode="wrap")
    h, w = q.shape[0] - 2, q.shape[1] - 2
    key = np.zeros((h, w), dtype=np.int64)
    part = np.empty((h, w), dtype=np.int64)
    k = 0
    with np.errstate(over="ignore"):
        for dy in range(3):
            for dx in range(3):
                key *= np.int64(1_000_003)
                for c in range(q.shape[-1]):
                    np.multiply(q[dy:dy + h, dx:dx + w, c], weights[k, c], out=part, dtype=np.int64)
                    key += part
                k += 1
    return key


class SourceIndex:
    """A source's 3 x 3 neighbourhood keys, sorted for lookup: made once per source and reused by every tile
    whose copies are looked up in it (the candidates of one stack, the verdict and the join figures)."""

    def __init__(self, source: np.ndarray):
        sk = _keys(source, periodic=False)  # centre texel (y + 1, x + 1) of the source
        self.shape = sk.shape
        self.order = np.argsort(sk.ravel(), kind="stable")
        self.sorted_keys = sk.ravel()[self.order]

    def lookup(self, wanted: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For each key of ``wanted``: whether the source has it, the first place (flat index into the source's
        keys) and how many places have it."""
        # looked up in key order: a sorted search over sorted queries walks the table once (at 4K this lookup
        # took 55 s with the queries unsorted, 22 s sorted)
        by_key = np.argsort(wanted)
        idx, right = np.empty_like(by_key), np.empty_like(by_key)
        in_order = wanted[by_key]
        idx[by_key] = np.searchsorted(self.sorted_keys, in_order)
        right[by_key] = np.searchsorted(self.sorted_keys, in_order, side="right")
        idx = np.clip(idx, 0, len(self.sorted_keys) - 1)
        return self.sorted_keys[idx] == wanted, self.order[idx], right - idx


def sampled_share(tile: np.ndarray, index: SourceIndex, bands: int = 16, rows: int = 8) -> float:
    """The share of ``tile``'s texels found exactly in ``index``'s source, read on ``bands`` bands of ``rows`` rows
    spread over it (each texel's 3 x 3 neighbourhood inside its band)."""
    h = tile.shape[0]
    if h <= bands * rows:
        keys = _keys(tile, periodic=True).ravel()
    else:
        keys = np.concatenate([_keys(tile[y: y + rows], periodic=False).ravel()
                               for y in np.linspace(0, h - rows, bands).astype(int)])
    return float(index.lookup(keys)[0].mean())


def copy_origins(tile: np.ndarray, source: np.ndarray, infer: int = 0, index: SourceIndex | None = None
                 ) -> tuple[np.ndarray, float]:
    """Source position ``(y, x)`` of every tile texel (-1 where none is placed), and the share found exactly.

    ``infer``: texels not found within this many texels of found ones take a found neighbour's origin,
    moved by one (see the module notes); 0: only exact matches are placed. ``index``: the source's
    :class:`SourceIndex` when it is already made."""
    index = SourceIndex(source) if index is None else index
    tk = _keys(tile, periodic=True)
    hit, pos, count = index.lookup(tk.ravel())
    ys, xs = pos // index.shape[1] + 1, pos % index.shape[1] + 1
    origin = np.stack([np.where(hit, ys, -1), np.where(hit, xs, -1)], -1).reshape(tk.shape + (2,))
    tq, sq = _quantised(tile), _quantised(source)
    # a neighbourhood found in one place only, or one with texture in it, places its texel for certain; a
    # flat one is found all over a flat area, and its continuation there may be anything
    single = hit & (count == 1)
    certain = single.reshape(tk.shape) | (hit.reshape(tk.shape) & (_local_range(tq) >= FLAT_CODES))
    # a texel beside a join has a neighbourhood the source lacks: it takes its neighbour's origin, moved
    # by one, when the source has exactly its value there
    for _ in range(2 + infer):
        origin, certain, placed = _spread(origin, certain, tile, source, (tq, sq))
        if not placed:
            break
    share = float((origin[..., 0] >= 0).mean())
    reach = INFER_UNITS * 0.5 * (step_unit(source, 0) + step_unit(source, 1)) if infer else 0.0
    for _ in range(infer):  # then the rest, from certain neighbours: the origin whose value is nearest the texel's
        origin, certain, placed = _spread(origin, certain, tile, source, None, reach)
        if not placed:
            break
    return origin, share


def _spread(origin: np.ndarray, certain: np.ndarray, tile: np.ndarray, source: np.ndarray,
            exact: tuple[np.ndarray, np.ndarray] | None, reach: float = 0.0) -> tuple[np.ndarray, np.ndarray, int]:
    """One step of placing unplaced texels from their placed neighbours (origin moved by one): with ``exact``
    (the tile and source quantised) only where the source has exactly the texel's value there (a certain
    neighbour makes a certain texel); else from certain neighbours only, the candidate whose source value is
    nearest the texel's, if within ``reach`` of it (:data:`INFER_UNITS` source steps). Returns the origins, which are
    certain, and how many were placed. Works on the unplaced texels alone (a few per cent of a tile)."""
    h, w = origin.shape[:2]
    hs, ws = source.shape[:2]
    flat, sure_flat = origin.reshape(-1, 2), certain.ravel()
    todo = np.flatnonzero(flat[:, 0] < 0)
    if len(todo) == 0:
        return origin, certain, 0
    ty, tx = todo // w, todo % w
    here = (exact[0].reshape(-1, exact[0].shape[-1]) if exact is not None else tile.reshape(-1, tile.shape[-1]))[todo]
    best = np.full(len(todo), np.inf)
    placed = np.full((len(todo), 2), -1, dtype=origin.dtype)
    placed_sure = np.zeros(len(todo), dtype=bool)
    for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):  # the neighbour at (y + dy, x + dx)
        nb = ((ty + dy) % h) * w + (tx + dx) % w
        cand = flat[nb] - np.array([dy, dx])
        from_certain = sure_flat[nb]
        ok = (flat[nb, 0] >= 0) & (cand[:, 0] >= 0) & (cand[:, 0] < hs) & (cand[:, 1] >= 0) & (cand[:, 1] < ws)
        cy, cx = np.clip(cand[:, 0], 0, hs - 1), np.clip(cand[:, 1], 0, ws - 1)
        if exact is not None:
            ok &= np.all(exact[1][cy, cx] == here, axis=-1)
            dist = np.where(from_certain, 0.0, 1.0)  # a certain neighbour first
        else:
            dist = np.linalg.norm(source[cy, cx] - here, axis=-1)
            ok &= from_certain & (dist <= reach)
        ok &= dist < best
        best = np.where(ok, dist, best)
        placed = np.where(ok[:, None], cand, placed)
        placed_sure = np.where(ok, from_certain, placed_sure)
    out, sure = flat.copy(), sure_flat.copy()
    hit = np.isfinite(best)
    out[todo[hit]] = placed[hit]
    sure[todo[hit]] = placed_sure[hit]
    return out.reshape(origin.shape), sure.reshape(certain.shape), int(hit.sum())


def _local_range(q: np.ndarray) -> np.ndarray:
    """(H, W) the largest spread (8-bit codes) of any channel over each texel's 3 x 3 neighbourhood (torus)."""
    lo, hi = q.copy(), q.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            moved = np.roll(q, (dy, dx), (0, 1))
            lo, hi = np.minimum(lo, moved), np.maximum(hi, moved)
    return (hi - lo).max(axis=-1)


def _quantised(img: np.ndarray, rows: int = 256) -> np.ndarray:
    """8-bit codes (int16) of network-domain values, a band of ``rows`` rows at a time (a 4K float64 stack's
    temporaries would otherwise be as large as the stack)."""
    out = np.empty(img.shape, dtype=np.int16)
    for r in range(0, img.shape[0], rows):
        out[r: r + rows] = np.clip(np.round((img[r: r + rows] + 1.0) * 127.5), 0, 255)
    return out


#: Lines (rows for vertical lines, columns for horizontal ones) worked on at a time: a 4K tile's per-texel
#: temporaries of every channel in float64 would otherwise be gigabytes each.
_BAND = 256


def step_unit(source: np.ndarray, axis: int) -> float:
    """The source's mean neighbour difference along ``axis`` (1: across vertical lines): the unit of the
    continuation error across lines of that direction (summed a band of rows or columns at a time)."""
    other = 1 - axis
    n = source.shape[other]
    total = sum(float(np.linalg.norm(np.diff(np.take(source, range(a, min(n, a + _BAND)), axis=other), axis=axis),
                                     axis=-1).sum()) for a in range(0, n, _BAND))
    count = (source.shape[axis] - 1) * n
    return total / max(count, 1) + 1e-6


def continuation(tile: np.ndarray, source: np.ndarray, origin: np.ndarray, axis: int, unit: float) -> np.ndarray:
    """(H, W) continuation error (in ``unit``) across the line before each texel along ``axis`` (1: vertical
    lines). Where both texels are exact copies of their origins, a line between texels copied together reads
    0, and a join the value error (see the module notes); where either is not (blended), every line reads its
    step error. At a join whose continuation lies outside the source on both sides (a window used as its own
    tile joins its last column to its first), the plain step across the line stands in, less one unit (the
    texture's own mean step). Worked out :data:`_BAND` rows (or columns) at a time: each is independent."""
    other = 1 - axis
    n = tile.shape[other]
    out = np.empty(tile.shape[:2], dtype=np.float64)
    for a in range(0, n, _BAND):
        band = np.s_[a: a + _BAND] if other == 0 else np.s_[:, a: a + _BAND]
        out[band] = _continuation(tile[band], source, origin[band], axis, unit)
    return out


def _continuation(tile: np.ndarray, source: np.ndarray, origin: np.ndarray, axis: int, unit: float) -> np.ndarray:
    """:func:`continuation` of a band of whole lines along ``axis``."""
    h, w = tile.shape[:2]
    hs, ws = source.shape[:2]
    step = np.array([0, 1]) if axis == 1 else np.array([1, 0])
    prev = np.roll(origin, 1, axis=axis)  # origin of the texel before the line
    prev_tile = np.roll(tile, 1, axis=axis)
    known = (origin[..., 0] >= 0) & (prev[..., 0] >= 0)
    oy, ox = np.clip(origin[..., 0], 0, hs - 1), np.clip(origin[..., 1], 0, ws - 1)
    py, px = np.clip(prev[..., 0], 0, hs - 1), np.clip(prev[..., 1], 0, ws - 1)
    at_origin, at_prev = source[oy, ox], source[py, px]
    exact = np.all(np.abs(tile - at_origin) <= EXACT_TOL, axis=-1)
    exact &= np.roll(exact, 1, axis=axis)  # both texels of the pair
    follows = known & np.all(origin == prev + step, axis=-1)  # copied together: no join here
    nxt = prev + step  # where the source continues the texel before the line
    inside_a = known & (nxt[..., 0] < hs) & (nxt[..., 1] < ws)
    back = origin - step  # where the source precedes the texel after the line
    inside_b = known & (back[..., 0] >= 0) & (back[..., 1] >= 0)
    ya, xa = np.clip(nxt[..., 0], 0, hs - 1), np.clip(nxt[..., 1], 0, ws - 1)
    yb, xb = np.clip(back[..., 0], 0, hs - 1), np.clip(back[..., 1], 0, ws - 1)
    tile_step = tile - prev_tile
    ea = np.linalg.norm(tile_step - (source[ya, xa] - at_prev), axis=-1)  # = |tile - source[nxt]| for copies
    eb = np.linalg.norm(tile_step - (at_origin - source[yb, xb]), axis=-1)  # = |prev_tile - source[back]|
    err = np.where(inside_a, ea, np.inf)
    err = np.minimum(err, np.where(inside_b, eb, np.inf))
    step_size = np.linalg.norm(tile_step, axis=-1)
    err = np.where(np.isfinite(err), err / unit, np.maximum(0.0, step_size / unit - 1.0))
    return np.where((follows & exact) | ~known, 0.0, err)


def copy_seams(tile: np.ndarray, source: np.ndarray, origin: np.ndarray, name: str, run: int,
               threshold: float = COPY_THRESHOLD, limit: int = 6, units: dict[int, float] | None = None
               ) -> tuple[list[Seam], float]:
    """Seams of a copied tile (see the module notes) over runs of ``run`` texels, and its strongest run.
    ``units``: the source's :func:`step_unit` by axis when they are already measured."""
    found: list[Seam] = []
    strongest = 0.0
    for axis, label in ((1, "x"), (0, "y")):
        err = continuation(tile, source, origin, axis, units[axis] if units else step_unit(source, axis))
        along = err if axis == 1 else err.T  # rows run along the line; columns are lines
        n = along.shape[0]
        k = min(run, n)
        means = moving_mean(along, k, periodic=True)  # (n, lines): the run starting at each texel
        peak = means.max(axis=0)
        strongest = max(strongest, float(peak.max()))
        taken: list[int] = []
        for line in np.argsort(-peak):
            if peak[line] <= threshold or len(taken) >= limit:
                break
            if any(min(abs(line - t), len(peak) - abs(line - t)) <= 2 for t in taken):
                continue
            taken.append(int(line))
            above = np.nonzero(means[:, line] > threshold)[0]
            start = int(above.min())
            end = int(min(n - 1, above.max() + k - 1))
            found.append(Seam(label, int(line), start, end, float(peak[line] - threshold), name))
    found.sort(key=lambda s: -s.figure)
    return found, strongest
