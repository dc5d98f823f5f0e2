"""Test helper: authoring inputs for every stack found in a scene, each map's tile a copy of its source (authoring
only places the tiles)."""
from __future__ import annotations

import shutil
from pathlib import Path

from seamless_usd.authoring import MapResult, Provenance, StackResult
from seamless_usd.discover import scan_paths


def stand_ins(path: Path, scale: tuple[float, float] = (2.0, 2.0), provenance=None) -> list[StackResult]:
    """A passed :class:`StackResult` at UV ``scale`` for each stack of ``path``; tiles in ``tileable/`` beside it
    (``provenance(stack)``: what is recorded, else a tile cut with no network)."""
    results = []
    for stack in scan_paths([path]).stacks:
        maps = []
        for tex in stack.maps:
            out = path.parent / "tileable" / f"{Path(tex.resolved).stem}_tile.png"
            out.parent.mkdir(exist_ok=True)
            shutil.copyfile(tex.resolved, out)
            maps.append(MapResult(tex, out))
        prov = provenance(stack) if provenance else Provenance(stack.maps[0].asset, (64, 64), scale, None, 0.0,
                                                                (0.0, 0.0), "", "0.1.0", passed=True)
        results.append(StackResult(stack, maps, scale, prov))
    return results
