"""Names of the files a run writes, derived from the source asset and the stack."""
from __future__ import annotations

import re
from pathlib import Path

__all__ = ["tile_filename", "override_layer_path", "slug"]

_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def slug(text: str, limit: int = 48) -> str:
    """A file-name-safe form of ``text`` (prim paths, material names)."""
    cleaned = _UNSAFE.sub("_", text.strip("<>/")).strip("._") or "x"
    return cleaned[:limit]


def tile_filename(source_asset: str, stack_id: str, extension: str) -> str:
    """``brick_albedo.png`` of stack ``Looks_Brick-3f2a`` -> ``brick_albedo.Looks_Brick-3f2a.tile.png``.

    The stack id keeps two materials that share one source file from overwriting each other's
    tiles. The stem keeps non-ASCII letters and spaces out of nothing: only unsafe characters
    are replaced.
    """
    stem = Path(source_asset.replace("\\", "/")).stem
    return f"{slug(stem)}.{slug(stack_id, 64)}.tile{extension}"


def override_layer_path(stage_path: Path) -> Path:
    """``scene.usda`` -> ``scene.seamless.usda`` (``.usdc``/``.usd``/``.usdz`` -> ``.seamless.usda``)."""
    stage_path = Path(stage_path)
    return stage_path.with_name(f"{stage_path.stem}.seamless.usda")
