"""Display pictures of one stack for the HTML report, built on the worker from network-domain pixels.

For every map, the source and the tile are repeated over one UV window
(:mod:`seamless_usd.report.repeat`: the tile's repeat scaled by its UV scale), so both are at the
same texel scale. The material is lit from a grazing angle over the same window
(:mod:`seamless_usd.report.lit`), once with the source maps and once with the tiles. The client
only encodes and embeds the pictures.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from seamless_usd.report.lit import exposure_for, shade, shading_inputs, to_display
from seamless_usd.report.model import Previews
from seamless_usd.report.repeat import REPEATS, VIEW_MAX, ViewGeometry, repeat_view, through_uv, view_geometry

__all__ = ["THUMBNAIL_MAX", "stack_previews", "map_picture", "lit_pictures"]

THUMBNAIL_MAX = 192  # longest side of the library index thumbnail, px


def map_picture(values: np.ndarray, is_normal: bool) -> np.ndarray:
    """A map's values as they are, uint8 RGB (sRGB maps are already display-encoded)."""
    from seamless_usd.metrics import preview_uint8

    return preview_uint8(values, is_normal=is_normal)


def lit_pictures(maps: Sequence, source_views: Sequence[np.ndarray],
                 tile_views: Sequence[np.ndarray]) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The stack lit from a grazing angle, source and tile, uint8 RGB at one exposure.

    ``(None, None)`` when the stack has no albedo, normal, roughness, metallic or occlusion map.
    """
    source, tile = shading_inputs(maps, source_views), shading_inputs(maps, tile_views)
    if source is None or tile is None:
        return None, None
    lit_source, lit_tile = shade(source), shade(tile)
    exposure = exposure_for(lit_source)
    return to_display(lit_source, exposure), to_display(lit_tile, exposure)


def _thumbnail(img: np.ndarray) -> np.ndarray:
    step = max(1, int(np.ceil(max(img.shape[:2]) / THUMBNAIL_MAX)))
    h, w = (img.shape[0] // step) * step, (img.shape[1] // step) * step
    blocks = img[:h, :w].reshape(h // step, step, w // step, step, -1).astype(np.float64)
    return (blocks.mean(axis=(1, 3)) + 0.5).astype(np.uint8)


def _lit_note(maps: Sequence, has_lit: bool) -> str:
    if not has_lit:
        return "no albedo, normal, roughness, metallic or occlusion map: the maps are shown as they are"
    roles = sorted({r.role for m in maps for r in m.roles})
    return (f"one light from the top left, 20° above the surface, seen from 50° opposite it (GGX); "
            f"from {', '.join(roles)}")


def stack_previews(maps: Sequence, sources: Sequence[np.ndarray], tiles: Sequence[np.ndarray],
                   uv_scale: tuple[float, float] | None, discriminator: np.ndarray | None = None, *,
                   repeats: int = REPEATS, max_px: int = VIEW_MAX,
                   levels: Sequence[tuple[str, np.ndarray]] = (), turn: tuple | None = None) -> Previews:
    """Previews of a stack.

    Parameters
    ----------
    maps : the stack's ``TextureMap``s (roles, colour space, ``is_normal``, node path).
    sources, tiles : per map, the source and the written tile, ``(H, W, C)`` network domain
        (sources share one grid, tiles share one grid; the two grids may differ).
    uv_scale : the UV scale authored for the tile (one tile spans ``1/uv_scale`` of the UV square).
    discriminator : uint8 RGB picture of the discriminator map, or None.
    repeats : repeats of the larger of source and tile across the shared window.
    max_px : longest side of the same-scale pictures.
    levels : (caption, first map in the network domain) per synthesis stage, shown as they are.
    turn : for a tile the asset's UVs turn back (``process --straighten``): (the first map's source as authored,
        degrees, its height over width, the UV scale against it): the source and the tile as the asset shows
        them, over one window of the source's UVs.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> m = NS(node="/M/Rough", roles=(NS(role="roughness", channels="r"),), channels_used="r",
    ...        color_space="raw", is_normal=False)
    >>> p = stack_previews([m], [np.zeros((64, 64, 1))], [np.zeros((32, 32, 1))], (2.0, 2.0), max_px=96)
    >>> p.source_view["/M/Rough"].shape, p.view["window"], p.lit_tile.shape
    ((96, 96, 3), [3.0, 3.0], (96, 96, 3))
    """
    out = Previews(discriminator=None if discriminator is None else np.asarray(discriminator, np.uint8))
    if maps:
        out.levels = [(c, map_picture(np.asarray(px, np.float32), maps[0].is_normal)) for c, px in levels]
    if not maps:
        return out
    source_hw = np.asarray(sources[0]).shape[:2]
    geometry: ViewGeometry = view_geometry((source_hw[1], source_hw[0]), uv_scale, repeats, max_px)
    out.view = geometry.to_dict()
    source_views, tile_views = [], []
    for m, source, tile in zip(maps, sources, tiles):
        sv = repeat_view(source, (1.0, 1.0), geometry)
        tv = repeat_view(tile, geometry.tile_extent, geometry)
        source_views.append(sv)
        tile_views.append(tv)
        out.source_view[m.node] = map_picture(sv, m.is_normal)
        out.tile_view[m.node] = map_picture(tv, m.is_normal)
    if turn is not None:
        from seamless_usd.authoring.uvmath import turned_scale

        original, degrees, aspect, uv = turn
        seen = view_geometry((original.shape[1], original.shape[0]), uv, repeats, max_px)
        affine = turned_scale(tuple(uv), degrees, aspect)
        out.asset_source = map_picture(repeat_view(original, (1.0, 1.0), seen), maps[0].is_normal)
        out.asset_tile = map_picture(through_uv(tiles[0], affine, seen), maps[0].is_normal)
    out.lit_source, out.lit_tile = lit_pictures(maps, source_views, tile_views)
    out.lit_note = _lit_note(maps, out.lit_tile is not None)
    first = out.lit_tile if out.lit_tile is not None else out.tile_view[maps[0].node]
    out.thumbnail = _thumbnail(first)
    return out
