"""Seams of a tile made of the source's own texels (refined, cut, or a window used as a tile).

Every texel of such a tile is a copy of a source texel, so where it came from can be looked up exactly
(3 x 3 neighbourhoods, hashed, quantised to 8 bits so that a tile written to a file and read back still
matches). Across a line between two texels copied from places that are not neighbours in the source,
the join is judged by what the source itself would have put there: the *continuation error* is the
difference between the texel the tile has beside the line and the texel the source has beside the other
one's origin, in units of the source's own neighbour difference. A cut placed where two copies agree
(the lattice cut along a mortar joint) reads near 0; a join of unrelated places reads like unrelated
texels, far above 1. A seam is a run of a line whose mean continuation error exceeds
:data:`COPY_THRESHOLD`.
"""
from __future__ import annotations

import numpy as np

from .features import moving_mean
from .lines import Seam

__all__ = ["COPY_SHARE", "COPY_THRESHOLD", "MAP_THRESHOLD", "continuation", "copy_origins", "copy_seams"]

#: Share of a tile's texels that must be found in the source for the tile to be judged as copies.
COPY_SHARE = 0.9
#: Mean continuation error over a run (source neighbour-difference units) above which a run is a seam: the
#: lattice cuts of the tuning textures read at most 0.77, the blocky refinements 1.03 and more.
COPY_THRESHOLD = 0.9
#: The same for one map alone: its own neighbour difference is a noisier unit than the maps' together, and
#: the lattice cuts of the six quality-benchmark stacks read up to 1.01 on one map (0.77 together).
MAP_THRESHOLD = 1.2


def _keys(img: np.ndarray, periodic: bool) -> np.ndarray:
    """One 64-bit key per texel for its 3 x 3 neighbourhood, 8-bit quantised ((H, W) or (H-2, W-2))."""
    q = _quantised(img).astype(np.int64)  # network domain -> 0..255
    rng = np.random.default_rng(12345)
    weights = rng.integers(1, 1 << 61, size=(9, q.shape[-1]), dtype=np.int64) | 1
    if periodic:
        pad = np.pad(q, ((1, 1), (1, 1), (0, 0)), mode="wrap")
    else:
        pad = q
    h, w = pad.shape[0] - 2, pad.shape[1] - 2
    key = np.zeros((h, w), dtype=np.int64)
    k = 0
    with np.errstate(over="ignore"):
        for dy in range(3):
            for dx in range(3):
                key = key * np.int64(1_000_003) + (pad[dy:dy + h, dx:dx + w] * weights[k]).sum(-1)
                k += 1
    return key


def copy_origins(tile: np.ndarray, source: np.ndarray) -> tuple[np.ndarray, float]:
    """Source position ``(y, x)`` of every tile texel (-1 where none matches exactly), and the share found."""
    tk = _keys(tile, periodic=True)
    sk = _keys(source, periodic=False)  # centre texel (y + 1, x + 1) of the source
    flat = sk.ravel()
    order = np.argsort(flat, kind="stable")
    sorted_keys = flat[order]
    idx = np.searchsorted(sorted_keys, tk.ravel())
    idx = np.clip(idx, 0, len(sorted_keys) - 1)
    hit = sorted_keys[idx] == tk.ravel()
    pos = order[idx]
    ys, xs = pos // sk.shape[1] + 1, pos % sk.shape[1] + 1
    origin = np.stack([np.where(hit, ys, -1), np.where(hit, xs, -1)], -1).reshape(tk.shape + (2,))
    # a texel beside a join has a neighbourhood the source lacks: it takes its neighbour's origin, moved
    # by one, when the source has exactly its value there
    tq, sq = _quantised(tile), _quantised(source)
    hs, ws = source.shape[:2]
    for _ in range(2):
        for axis, shift in ((0, 1), (0, -1), (1, 1), (1, -1)):
            step = np.array([shift, 0]) if axis == 0 else np.array([0, shift])
            cand = np.roll(origin, shift, axis=axis) + step
            ok = (origin[..., 0] < 0) & (np.roll(origin, shift, axis=axis)[..., 0] >= 0)
            ok &= (cand[..., 0] >= 0) & (cand[..., 0] < hs) & (cand[..., 1] >= 0) & (cand[..., 1] < ws)
            cy, cx = np.clip(cand[..., 0], 0, hs - 1), np.clip(cand[..., 1], 0, ws - 1)
            ok &= np.all(sq[cy, cx] == tq, axis=-1)
            origin = np.where(ok[..., None], cand, origin)
    return origin, float((origin[..., 0] >= 0).mean())


def _quantised(img: np.ndarray) -> np.ndarray:
    return np.clip(np.round((img + 1.0) * 127.5), 0, 255).astype(np.int16)


def continuation(tile: np.ndarray, source: np.ndarray, origin: np.ndarray, axis: int, unit: float) -> np.ndarray:
    """(H, W) continuation error (in ``unit``) across the line before each texel along ``axis`` (1: vertical
    lines). At a join whose continuation lies outside the source on both sides (a window used as its own
    tile joins its last column to its first), the plain step across the line stands in, less one unit (the
    texture's own mean step)."""
    h, w = tile.shape[:2]
    step = np.array([0, 1]) if axis == 1 else np.array([1, 0])
    prev = np.roll(origin, 1, axis=axis)  # origin of the texel before the line
    prev_tile = np.roll(tile, 1, axis=axis)
    known = (origin[..., 0] >= 0) & (prev[..., 0] >= 0)
    follows = known & np.all(origin == prev + step, axis=-1)  # copied together: no join here
    hs, ws = source.shape[:2]
    nxt = prev + step  # where the source continues the texel before the line
    inside_a = known & (nxt[..., 0] < hs) & (nxt[..., 1] < ws)
    back = origin - step  # where the source precedes the texel after the line
    inside_b = known & (back[..., 0] >= 0) & (back[..., 1] >= 0)
    err = np.full((h, w), np.inf)
    ya, xa = np.clip(nxt[..., 0], 0, hs - 1), np.clip(nxt[..., 1], 0, ws - 1)
    yb, xb = np.clip(back[..., 0], 0, hs - 1), np.clip(back[..., 1], 0, ws - 1)
    ea = np.linalg.norm(tile - source[ya, xa], axis=-1)
    eb = np.linalg.norm(prev_tile - source[yb, xb], axis=-1)
    err = np.where(inside_a, ea, err)
    err = np.minimum(err, np.where(inside_b, eb, np.inf))
    step_size = np.linalg.norm(tile - prev_tile, axis=-1)
    err = np.where(np.isfinite(err), err / unit, np.maximum(0.0, step_size / unit - 1.0))
    return np.where(follows | ~known, 0.0, err)


def copy_seams(tile: np.ndarray, source: np.ndarray, origin: np.ndarray, name: str, run: int,
               threshold: float = COPY_THRESHOLD, limit: int = 6) -> tuple[list[Seam], float]:
    """Seams of a copied tile (see the module notes) over runs of ``run`` texels, and its strongest run."""
    unit = float(np.mean(np.linalg.norm(np.diff(source, axis=1), axis=-1))) + 1e-6
    found: list[Seam] = []
    strongest = 0.0
    for axis, label in ((1, "x"), (0, "y")):
        err = continuation(tile, source, origin, axis, unit)
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
