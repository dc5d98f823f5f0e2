"""Synthetic structured stacks with known structure: cells with dark joints, and long curved stripes.

Both are non-periodic crops of an unbounded pattern (no lattice, no wrap), in the network domain
[-1, 1], with a colour map and a height map that share the structure:

``cells(side, cell)``
    A Voronoi pattern of jittered seeds about ``cell`` px apart: rounded stones of varied tone, each
    domed in the height map, separated by dark joints about ``cell / 12`` px wide. A connected joint
    network; a stone cut in half is not in it.
``stripes(side, period)``
    Dark lines about ``period`` px apart running across the whole crop, slightly curved and of varied
    width, over a grainy ground: long lines that a tile must keep unbroken.
"""
from __future__ import annotations

import numpy as np

__all__ = ["cells", "stripes"]


def _noise(rng: np.random.Generator, side: int, scale: float) -> np.ndarray:
    """Smooth value noise in [-1, 1] with features about ``scale`` px."""
    from scipy import ndimage

    n = rng.normal(size=(side, side))
    n = ndimage.gaussian_filter(n, scale / 2.0, mode="reflect")
    return n / (np.abs(n).max() + 1e-9)


def cells(side: int, cell: float = 64.0, seed: int = 0) -> dict[str, tuple[np.ndarray, bool]]:
    """``{"color": (side, side, 3), "height": (side, side, 1)}`` of a stone-cell pattern (see the module notes)."""
    from scipy.spatial import cKDTree

    rng = np.random.default_rng(seed)
    n = int(np.ceil(side / cell)) + 2
    gy, gx = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    pts = (np.stack([gy, gx], -1).reshape(-1, 2) - 0.5 + rng.uniform(-0.4, 0.4, (n * n, 2))) * cell
    tree = cKDTree(pts)
    yy, xx = np.meshgrid(np.arange(side) + 0.5, np.arange(side) + 0.5, indexing="ij")
    warp = 0.08 * cell
    qy = yy + warp * _noise(rng, side, cell / 2)
    qx = xx + warp * _noise(rng, side, cell / 2)
    d, idx = tree.query(np.stack([qy.ravel(), qx.ravel()], -1), k=2)
    d1, d2 = d[:, 0].reshape(side, side), d[:, 1].reshape(side, side)
    nearest = idx[:, 0].reshape(side, side)
    edge = (d2 - d1) / 2.0  # distance to the cell's border
    joint = cell / 24.0
    inside = np.clip((edge - joint) / (cell / 6.0), 0.0, 1.0)  # 0 in the joint, 1 well inside
    tone = rng.uniform(0.35, 0.75, len(pts))[nearest]
    hue = rng.uniform(-0.06, 0.06, (len(pts), 3))[nearest]
    grain = 0.05 * rng.normal(size=(side, side))
    base = (tone * (0.6 + 0.4 * inside) + grain)[..., None] + hue
    mortar = 0.12 + 0.04 * rng.normal(size=(side, side))
    color = np.where((edge < joint)[..., None], mortar[..., None] * np.ones(3), base)
    height = np.where(edge < joint, -0.8, -0.2 + 0.8 * np.sqrt(inside)) + 0.03 * rng.normal(size=(side, side))
    return {"color": (np.clip(color, 0, 1).astype(np.float32) * 2 - 1, False),
            "height": (np.clip(height, -1, 1).astype(np.float32)[..., None], False)}


def stripes(side: int, period: float = 48.0, seed: int = 0) -> dict[str, tuple[np.ndarray, bool]]:
    """``{"color": (side, side, 3), "height": (side, side, 1)}`` of long curved dark lines (see the module notes)."""
    rng = np.random.default_rng(seed)
    yy, xx = np.meshgrid(np.arange(side, dtype=np.float64), np.arange(side, dtype=np.float64), indexing="ij")
    bend = 0.35 * period * np.sin(2 * np.pi * xx / (side * 0.73) + 0.6 * np.sin(2 * np.pi * yy / (side * 1.3)))
    v = (yy + 0.18 * xx + bend) / period + 0.15 * _noise(rng, side, period)
    phase = v - np.floor(v)
    line = np.floor(v).astype(np.int64)
    widths = rng.uniform(0.06, 0.12, line.max() - line.min() + 1)[line - line.min()]
    dark = np.abs(phase - 0.5) < widths / 2
    grain = 0.06 * _noise(rng, side, 3.0) + 0.04 * rng.normal(size=(side, side))
    tone = 0.55 + 0.08 * _noise(rng, side, period * 2)
    g = np.where(dark, 0.12, tone + grain)
    color = np.stack([g * 1.05, g * 0.9, g * 0.7], -1)
    height = np.where(dark, -0.7, 0.2 + 0.3 * grain)
    return {"color": (np.clip(color, 0, 1).astype(np.float32) * 2 - 1, False),
            "height": (np.clip(height, -1, 1).astype(np.float32)[..., None], False)}
