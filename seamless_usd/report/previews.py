"""Display pictures of one stack for the HTML report: source and tile per map, the discriminator map.

Built on the worker from network-domain pixels (``[-1, 1]``), so the client only embeds them.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from seamless_usd.report.model import Previews

__all__ = ["PREVIEW_MAX", "stack_previews"]

PREVIEW_MAX = 384  # longest side of a 2x2 preview in the HTML report, px


def _shrink(img: np.ndarray) -> np.ndarray:
    step = max(1, int(np.ceil(max(img.shape[:2]) / PREVIEW_MAX)))
    return np.ascontiguousarray(img[::step, ::step])


def stack_previews(maps: Sequence, sources: Sequence[np.ndarray], tiles: Sequence[np.ndarray],
                   uv_scale: tuple[float, float], discriminator: np.ndarray | None = None) -> Previews:
    """Previews of a stack.

    Parameters
    ----------
    maps : the stack's ``TextureMap``s (roles, colour space, ``is_normal``, node path).
    sources, tiles : per map, the source and the written tile, ``(H, W, C)`` network domain.
    uv_scale : the UV scale authored for the tile (one tile spans ``1/uv_scale`` of the UV square).
    discriminator : uint8 RGB picture of the discriminator map, or None.
    """
    from seamless_usd import metrics

    out = Previews(discriminator=None if discriminator is None else np.asarray(discriminator, np.uint8))
    for m, source, tile in zip(maps, sources, tiles):
        out.source_2x2[m.node] = _shrink(metrics.preview_uint8(metrics.tile_2x2(source), is_normal=m.is_normal))
        out.tile_2x2[m.node] = _shrink(metrics.preview_uint8(metrics.tile_2x2(tile), is_normal=m.is_normal))
    return out
