"""A stack's report pictures as named arrays (kept beside its cache entry, :mod:`seamless_usd.pipeline.rerun`), and
read back from such a file: all of them for the stack's page, or one (the index's thumbnail), while the report is
drawn, so that a run over a library keeps none of them in memory."""
from __future__ import annotations

from typing import Any

import numpy as np
from safetensors import safe_open
from safetensors.numpy import load_file

from seamless_usd.report.model import Previews

__all__ = ["previews_to_arrays", "previews_from_arrays", "previews_from_file", "picture_from_file", "stored_previews",
           "loaded", "thumbnail_picture"]


def previews_to_arrays(p: Previews) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The pictures as named arrays, and what is not a picture as JSON."""
    arrays = {f"source_view/{k}": v for k, v in p.source_view.items()}
    arrays |= {f"tile_view/{k}": v for k, v in p.tile_view.items()}
    arrays |= {name: v for name in ("lit_source", "lit_tile", "thumbnail", "discriminator", "asset_source", "asset_tile")
               if (v := getattr(p, name)) is not None}
    arrays |= {f"level/{i}": pic for i, (_, pic) in enumerate(p.levels)}
    return ({k: np.ascontiguousarray(v) for k, v in arrays.items()},
            {"lit_note": p.lit_note, "view": p.view, "levels": [caption for caption, _ in p.levels],
             "source_view": list(p.source_view), "tile_view": list(p.tile_view)})


def previews_from_arrays(arrays: dict[str, np.ndarray], info: dict[str, Any]) -> Previews:
    return Previews(
        source_view={k: arrays[f"source_view/{k}"] for k in info["source_view"]},
        tile_view={k: arrays[f"tile_view/{k}"] for k in info["tile_view"]},
        lit_source=arrays.get("lit_source"), lit_tile=arrays.get("lit_tile"), lit_note=info["lit_note"],
        view=info["view"], thumbnail=arrays.get("thumbnail"), discriminator=arrays.get("discriminator"),
        levels=[(caption, arrays[f"level/{i}"]) for i, caption in enumerate(info["levels"])],
        asset_source=arrays.get("asset_source"), asset_tile=arrays.get("asset_tile"),
    )


def previews_from_file(path: str, info: dict[str, Any]) -> Previews:
    """The pictures kept in the safetensors file ``path`` (``info``: what is not a picture)."""
    return previews_from_arrays(load_file(path), info)


def picture_from_file(path: str, name: str) -> np.ndarray | None:
    """The one picture ``name`` kept in ``path`` (None when it holds none), the others left unread."""
    with safe_open(path, framework="numpy") as f:
        return f.get_tensor(name) if name in f.keys() else None


def stored_previews(path: str, info: dict[str, Any]) -> Previews:
    """Pictures kept in ``path``, read when the report draws them (:meth:`.model.Previews.loaded`)."""
    return Previews(lit_note=info["lit_note"], view=info["view"], stored=path, stored_info=info)


def loaded(previews: Previews) -> Previews:
    """``previews`` with their pictures, read from their file where they are kept in one."""
    return previews_from_file(previews.stored, previews.stored_info) if previews.stored else previews


def thumbnail_picture(previews: Previews) -> np.ndarray | None:
    """The thumbnail alone (read alone from the file where the pictures are kept in one)."""
    return picture_from_file(previews.stored, "thumbnail") if previews.stored else previews.thumbnail
