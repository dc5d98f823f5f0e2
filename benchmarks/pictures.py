"""Pictures the benchmarks write: a tile repeated beside its source at one texel scale, and zoomed crops of
the tile's wrap corner beside the source, shrunk to at most :data:`PICTURE_MAX` px."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from seamless_usd import metrics as M

__all__ = ["PICTURE_MAX", "PICTURE_QUALITY", "side_by_side", "crops", "write_picture"]


#: Longest side of a committed picture (px); JPEG quality.
PICTURE_MAX = 768
PICTURE_QUALITY = 85


def side_by_side(tile: np.ndarray, source: np.ndarray, is_normal: bool, gap: int = 8) -> np.ndarray:
    """uint8 picture at one texel scale: ``tile`` repeated over the area of the source's 2x2 tiling
    (left) beside the naive 2x2 tiling of ``source`` (right). ``tile`` must already have the
    source's texel size (see ``methods.to_source_grid``)."""
    area = (2 * source.shape[0], 2 * source.shape[1])
    left = M.preview_uint8(M.tile_to(tile, area), is_normal)
    right = M.preview_uint8(M.tile_2x2(source), is_normal)
    out = np.full((area[0], 2 * area[1] + gap, 3), 255, np.uint8)
    out[:, : area[1]] = left
    out[:, area[1] + gap:] = right
    return out


def crops(tile: np.ndarray, source: np.ndarray, is_normal: bool, zoom: int, gap: int = 8) -> np.ndarray:
    """uint8: a window of the tile repeated (across its wrap corner, where a seam would show) beside a window
    of the source, each about ``PICTURE_MAX / 2 / zoom`` texels across, every texel shown ``zoom`` x ``zoom``."""
    h, w = tile.shape[:2]
    sh, sw = source.shape[:2]
    side = min((PICTURE_MAX - gap) // 2 // zoom, h, w, sh, sw)  # the pair fits PICTURE_MAX: shown unshrunk
    rep = M.tile_2x2(tile)[h - side // 2: h + side - side // 2, w - side // 2: w + side - side // 2]
    win = source[sh // 2 - side // 2: sh // 2 + side - side // 2, sw // 2 - side // 2: sw // 2 + side - side // 2]
    parts = [np.repeat(np.repeat(M.preview_uint8(a, is_normal), zoom, 0), zoom, 1) for a in (rep, win)]
    out = np.full((parts[0].shape[0], 2 * parts[0].shape[1] + gap, 3), 255, np.uint8)
    out[:, : parts[0].shape[1]] = parts[0]
    out[:, parts[0].shape[1] + gap:] = parts[1]
    return out


def write_picture(path: Path, pixels: np.ndarray) -> None:
    """Write an ``(H, W, 3)`` uint8 picture (JPEG by the suffix), shrunk to at most ``PICTURE_MAX`` px."""
    path.parent.mkdir(parents=True, exist_ok=True)
    step = max(1, int(np.ceil(max(pixels.shape[:2]) / PICTURE_MAX)))
    pixels = np.ascontiguousarray(pixels[::step, ::step])
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, oiio.UINT8)
    spec.attribute("Compression", f"jpeg:{PICTURE_QUALITY}")
    out = oiio.ImageOutput.create(str(path))
    if out is None or not out.open(str(path), spec):
        raise RuntimeError(f"cannot write @{path}@: {oiio.geterror()}")
    out.write_image(pixels)
    out.close()
