"""Maps moved between pixel grids: a stack brought to a working size, a periodic tile read on another grid."""
from __future__ import annotations

import dataclasses

import numpy as np
import torch
import torch.nn.functional as F

from .refinement.refine import resize_periodic
from .types import MapInput

__all__ = ["downsample_maps", "resized", "on_grid"]


def downsample_maps(maps: list[MapInput], size: tuple[int, int]) -> list[MapInput]:
    """Maps resized to ``size = (h, w)`` (bilinear, antialiased when shrinking; normals renormalised)."""
    return [m if m.pixels.shape[:2] == tuple(size) else
            dataclasses.replace(m, pixels=resized(m.pixels, size, m.is_normal)) for m in maps]


def resized(pixels: np.ndarray, size: tuple[int, int], is_normal: bool, periodic: bool = False) -> np.ndarray:
    """(H, W, C) pixels resized to ``size``: bilinear with antialiasing, or, for a periodic tile, area
    averaging with wrap-around (:func:`.refine.resize_periodic`); normals renormalised, values clamped."""
    t = torch.from_numpy(np.ascontiguousarray(pixels.transpose(2, 0, 1)))
    if periodic:
        r = resize_periodic(t, size)
    else:
        r = F.interpolate(t[None], size=size, mode="bilinear", antialias=True, align_corners=False)[0]
    if is_normal and r.shape[0] >= 3:
        r = torch.cat([F.normalize(r[:3], dim=0, eps=1e-6), r[3:]], 0)
    return np.ascontiguousarray(r.clamp(-1, 1).permute(1, 2, 0).numpy())


def on_grid(tiles: dict[str, np.ndarray], maps: list[MapInput], factor: tuple[float, float]) -> dict[str, np.ndarray]:
    """Periodic tiles resized by ``factor`` per axis (working / source size: onto the working grid)."""
    out = {}
    for m in maps:
        h, w = tiles[m.name].shape[:2]
        hw = (max(8, round(h * factor[0])), max(8, round(w * factor[1])))
        out[m.name] = resized(tiles[m.name], hw, m.is_normal, periodic=True)
    return out
