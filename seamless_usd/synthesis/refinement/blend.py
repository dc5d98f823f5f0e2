"""Gradient-domain blending of a narrow band around the joins of a copied tile.

A refined tile is a mosaic of blocks, each copied coherently from one place of the source (see
:mod:`.refine`). Where two blocks meet, the tone on either side may differ: a light patch ends on a
straight edge. This pass hides such a step the way Poisson image editing (Perez et al. 2003) hides the
border of a pasted region: inside a band of ``width`` texels around every join, the tile's values are
solved for so that each neighbour difference is the one the source has there (the mean of what the two
blocks' own sources continue with), with every texel outside the band held as it is. A step in tone is
spread over the band; a structure that does not continue (a plank gap that jumps) becomes a short
smudge instead of a hard step: blending hides colour, it does not mend structure.

Texels outside the band stay exact copies of source texels; the band's texels are new values, which
the result names (``band``). Every map is solved with the same band and the same field, so the maps stay
aligned; normal maps are blended as vectors and renormalised. The band, the joins and the solve all live
on the tile's torus, so the tile still wraps. The system (a 4-neighbour Laplacian over the band texels,
Dirichlet values from the texels around it) is built and solved on the band texels alone, by conjugate
gradients from the copied values; a band a few texels wide converges in tens of iterations.
"""
from __future__ import annotations

import numpy as np

__all__ = ["join_edges", "band_mask", "blend_band"]

_AXES = ((0, np.array([1, 0])), (1, np.array([0, 1])))


def join_edges(field: np.ndarray) -> list[np.ndarray]:
    """Per axis (0: rows, 1: columns), (h, w) bool: the line before each texel along that axis is a join
    (the texel and the one before it were not copied from neighbouring source texels)."""
    out = []
    for axis, step in _AXES:
        prev = np.roll(field, 1, axis=axis)
        out.append(~np.all(field == prev + step, axis=-1))
    return out


def band_mask(edges: list[np.ndarray], width: int) -> np.ndarray:
    """(h, w) bool: texels within ``width`` texels (city-block, on the torus) of a join line, on both sides."""
    if width <= 0:
        return np.zeros_like(edges[0])
    touched = np.zeros_like(edges[0])
    for axis, edge in enumerate(edges):
        touched |= edge | np.roll(edge, -1, axis=axis)  # both texels of the joined pair
    band = touched.copy()
    for _ in range(width - 1):
        grown = band.copy()
        for axis in (0, 1):
            grown |= np.roll(band, 1, axis=axis) | np.roll(band, -1, axis=axis)
        band = grown
    return band


def _pair_guidance(source: np.ndarray, field: np.ndarray, a: np.ndarray, b: np.ndarray, step: np.ndarray) -> np.ndarray:
    """(n, C) the difference ``x(b) - x(a)`` the source asks for across each pair of neighbouring tile texels
    (flat indices ``a`` and ``b = a + step``): the mean of the step ``a``'s source continues with and the
    one ``b``'s source comes from (one of them where the other falls outside the source; 0 where both do)."""
    hs, ws = source.shape[:2]
    flat = field.reshape(-1, 2)
    total = np.zeros((len(a), source.shape[2]), dtype=np.float64)
    count = np.zeros(len(a), dtype=np.float64)
    for base, sign in ((flat[a], 1), (flat[b], -1)):
        other = base + sign * step
        ok = (other[:, 0] >= 0) & (other[:, 0] < hs) & (other[:, 1] >= 0) & (other[:, 1] < ws)
        oy, ox = np.clip(other[:, 0], 0, hs - 1), np.clip(other[:, 1], 0, ws - 1)
        diff = (source[oy, ox].astype(np.float64) - source[base[:, 0], base[:, 1]]) * sign
        total += np.where(ok[:, None], diff, 0.0)
        count += ok
    return total / np.maximum(count, 1)[:, None]


def _neighbours(band: np.ndarray) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray, np.ndarray]]]:
    """Flat indices of the band texels, and per axis (their texel before, their texel after, the axis step),
    as flat indices on the torus."""
    h, w = band.shape
    ys, xs = np.nonzero(band)
    here = ys * w + xs
    out = []
    for axis, step in _AXES:
        if axis == 0:
            before, after = ((ys - 1) % h) * w + xs, ((ys + 1) % h) * w + xs
        else:
            before, after = ys * w + (xs - 1) % w, ys * w + (xs + 1) % w
        out.append((before, after, step))
    return here, out


def _solve(tile: np.ndarray, source: np.ndarray, field: np.ndarray, here: np.ndarray,
           axes: list[tuple[np.ndarray, np.ndarray, np.ndarray]], iterations: int, tol: float) -> np.ndarray:
    """Least squares over the band: every pair with a band texel should differ by its guidance. The normal
    equations (a 4-neighbour Laplacian over the band texels, Dirichlet values from the texels around it)
    are solved by conjugate gradients from the copied values, all channels at once, on the band alone."""
    h, w, c = tile.shape
    n = len(here)
    flat_tile = tile.reshape(-1, c).astype(np.float64)
    order = np.full(h * w, n, dtype=np.int64)  # band texel -> its row; others -> n (a zero row)
    order[here] = np.arange(n)
    rhs = np.zeros((n, c), dtype=np.float64)
    links = []
    for before, after, step in axes:
        # pairs (before, here) and (here, after): x_here - x_before = g1, x_after - x_here = g2
        rhs += _pair_guidance(source, field, before, here, step) - _pair_guidance(source, field, here, after, step)
        for nb in (before, after):
            inside = order[nb]
            rhs += np.where((inside == n)[:, None], flat_tile[nb], 0.0)  # held neighbours move to the right side
            links.append(inside)

    def apply(v: np.ndarray) -> np.ndarray:  # A v on the band: 4 v - the band neighbours' values
        padded = np.vstack([v, np.zeros((1, c))])
        out = 4.0 * v
        for inside in links:
            out -= padded[inside]
        return out

    x = flat_tile[here].copy()
    r = rhs - apply(x)
    p = r.copy()
    rr = (r * r).sum(axis=0)
    stop = tol ** 2 * np.maximum((rhs * rhs).sum(axis=0), 1e-30)
    for _ in range(iterations):
        if np.all(rr <= stop):
            break
        ap = apply(p)
        alpha = rr / np.maximum((p * ap).sum(axis=0), 1e-30)
        x += alpha * p
        r -= alpha * ap
        new = (r * r).sum(axis=0)
        p = r + (new / np.maximum(rr, 1e-30)) * p
        rr = new
    out = flat_tile.copy()
    out[here] = x
    return out.reshape(h, w, c)


def blend_band(sources: list[np.ndarray], field: np.ndarray, width: int, normals: list[bool] | None = None,
               iterations: int = 200, tol: float = 1e-4) -> tuple[list[np.ndarray], np.ndarray]:
    """The maps copied through ``field`` with a band of ``width`` texels around every join blended.

    Returns ``(maps, band)``: per map (h, w, C_i) float32, and the (h, w) bool mask of blended texels (all
    others are exact copies). ``normals[i]`` marks a normal map: its first three channels are renormalised.
    """
    field = np.asarray(field, dtype=np.int64)
    band = band_mask(join_edges(field), width)
    here, axes = _neighbours(band)  # the same system for every map
    out = []
    for i, src in enumerate(sources):
        src = np.asarray(src, dtype=np.float32)
        tile = src[field[..., 0], field[..., 1]]
        if not band.any():
            out.append(np.ascontiguousarray(tile))
            continue
        solved = _solve(tile, src, field, here, axes, iterations, tol)
        if normals is not None and normals[i] and solved.shape[2] >= 3:
            xyz = solved[..., :3]
            solved[..., :3] = xyz / np.maximum(np.linalg.norm(xyz, axis=-1, keepdims=True), 1e-8)
        solved = np.clip(solved, -1.0, 1.0) if src.min() >= -1.0 and src.max() <= 1.0 else solved
        out.append(np.ascontiguousarray(np.where(band[..., None], solved, tile), dtype=np.float32))
    return out, band
