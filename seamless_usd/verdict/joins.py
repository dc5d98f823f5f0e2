"""Every join inside a tile made of source texels: how many copied blocks meet badly, and how long.

The verdict (:mod:`.judge`) names the strongest seams of a tile, over runs of 32 texels. A refined tile
is a mosaic of copied blocks, often 10-30 texels across; where two blocks meet badly the join is shorter
than the verdict's run and a long coherent stretch on the same line can average it away. This module
counts them all: along every line of the tile (the wrap lines are lines like any other on a torus), a
*bad join* is a stretch where the continuation error (:func:`.copies.continuation`) averages more than the
verdict's threshold over :data:`SHORT_RUN` texels. Per map and for the maps together it reports the
number of such stretches, their total length (texels), and the field's *coherence*: the share of
neighbouring texel pairs copied together from neighbouring source texels.
"""
from __future__ import annotations

import numpy as np

from seamless_usd.metrics.structure import structure_figures

from .copies import COPY_THRESHOLD, MAP_THRESHOLD, continuation, step_unit
from .features import moving_mean
from .reference import Reading, Reference

__all__ = ["JOIN_SHARE", "SHORT_RUN", "JoinStats", "join_stats", "bad_join_mask", "inside_figures"]

#: Share of texels that must be found in the source for the joins to be counted. Lower than the verdict's
#: :data:`.copies.COPY_SHARE`: a finely cut tile (small blocks, slivers) leaves more texels beside its joins
#: unplaced, and those are the ones to count, not a reason to give up; ``copied`` says how many were placed.
JOIN_SHARE = 0.5
#: Texels a bad join must span: short enough for the 10-30 px blocks of a refined field, long enough that
#: one odd texel pair is not a join.
SHORT_RUN = 8


def _flagged(err: np.ndarray, threshold: float, run: int) -> np.ndarray:
    """(along, lines) bool: texels covered by a run of ``run`` whose mean error exceeds ``threshold``."""
    n = err.shape[0]
    k = min(run, n)
    start = moving_mean(err, k, periodic=True) > threshold  # run starting at each texel
    # a texel is covered when one of the k runs through it is flagged
    covered = moving_mean(np.roll(start, k - 1, axis=0).astype(np.float64), k, periodic=True) > 0
    return covered


def bad_join_mask(tile: np.ndarray, source: np.ndarray, origin: np.ndarray, threshold: float,
                  run: int = SHORT_RUN, units: dict[int, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Bool masks (H, W) of bad joins on the vertical lines (before each texel along x) and horizontal ones.
    ``units``: the source's :func:`.copies.step_unit` by axis when they are already measured."""
    units = units or {axis: step_unit(source, axis) for axis in (0, 1)}
    vx = _flagged(continuation(tile, source, origin, 1, units[1]), threshold, run)  # runs along y
    vy = _flagged(continuation(tile, source, origin, 0, units[0]).T, threshold, run).T  # along x
    return vx, vy


def _segments(mask: np.ndarray, axis: int) -> int:
    """Stretches of consecutive flagged texels along ``axis`` (periodic): a line flagged all the way round
    is one stretch."""
    starts = int((mask & ~np.roll(mask, 1, axis=axis)).sum())
    return starts + int(mask.all(axis=axis).sum())


class JoinStats(dict):
    """``{"copied": share, "coherence": share, "maps": {name: {"count": n, "length": texels, "per_mpx": n}}}``;
    ``maps`` is None when the tile is not made of source texels (fewer than :data:`JOIN_SHARE` found)."""


def join_stats(tiles: list[np.ndarray], sources: list[np.ndarray], normals: list[bool], names: list[str],
               run: int = SHORT_RUN, origin: np.ndarray | None = None, reading: Reading | None = None) -> JoinStats:
    """Bad joins of a tile made of source texels, per map and for the maps together (``"stack"``).

    ``sources`` must be at the tile's texel scale (see :func:`seamless_usd.verdict.judge`). ``origin``: the
    source position of every tile texel when it is known (the refinement's field); by default each is looked
    up. A tile whose texels near the joins were blended (no longer copies) is judged on its field: the
    continuation error then reads the blended values against what the source continues with. ``reading``: the
    tile already prepared against its source (:class:`.reference.Reading`; ``tiles`` and ``sources`` are then
    not read again), whose copies are looked up once for the verdict and these figures.
    """
    if reading is None:
        reading = Reading(tiles, normals, names, Reference(sources, normals, names, keep_index=False))
    ref = reading.reference
    tj, t, sj, s = reading.joint, reading.maps, ref.joint, ref.maps
    if origin is None:
        origin, share = reading.origins
    else:
        origin, share = np.asarray(origin, dtype=np.int64), 1.0
    out = JoinStats(copied=round(share, 4), coherence=None, maps=None)
    if share < JOIN_SHARE:
        return out
    known = origin[..., 0] >= 0
    together = []
    for axis in (0, 1):
        step = np.array([1, 0]) if axis == 0 else np.array([0, 1])
        prev = np.roll(origin, 1, axis=axis)
        pair = known & (prev[..., 0] >= 0)
        together.append((np.all(origin == prev + step, axis=-1) & pair).sum() / max(1, pair.sum()))
    out["coherence"] = round(float(np.mean(together)), 4)
    mpx = tj.shape[0] * tj.shape[1] / 1e6
    maps = {}
    parts = [("stack", tj, sj, COPY_THRESHOLD, ref.units())] + (
        [(n, a, b, MAP_THRESHOLD, ref.units(k)) for k, (n, a, b) in enumerate(zip(reading.names, t, s))]
        if len(t) > 1 else [])
    for name, tile, source, threshold, units in parts:  # one map's own copy at a time: gathers from it are faster
        vx, vy = bad_join_mask(np.ascontiguousarray(tile), np.ascontiguousarray(source), origin, threshold, run, units)
        count = _segments(vx, 0) + _segments(vy, 1)
        maps[name] = {"count": count, "length": int(vx.sum() + vy.sum()), "per_mpx": round(count / mpx, 1)}
    out["maps"] = maps
    return out


def inside_figures(tiles: list[np.ndarray], sources: list[np.ndarray], normals: list[bool], names: list[str],
                   joins: JoinStats | None = None) -> list[dict]:
    """Per map, what lies inside a tile (figures without a tolerance): its bad joins (count, total length in
    texels) and the copies' coherence (None when the tile is not made of source texels), and the structure
    figure against the source (:mod:`seamless_usd.metrics.structure`). ``sources`` at the tile's texel scale;
    ``joins``: the tile's :func:`join_stats` when they are already counted (from the reading its verdict used)."""
    joins = join_stats(tiles, sources, normals, names) if joins is None else joins
    out = []
    for name, tile, source in zip(names, tiles, sources):
        mine = (joins["maps"] or {}).get(name if len(names) > 1 else "stack")
        out.append({"bad_joins": None if mine is None else float(mine["count"]),
                    "join_length": None if mine is None else float(mine["length"]),
                    "coherence": joins["coherence"],
                    "structure": structure_figures(tile, source)["structure"]})
    return out
