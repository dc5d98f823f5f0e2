"""Discovery: USD + MaterialX traversal to texture maps and stacks (no pixels; see DESIGN.md).

>>> from seamless_usd.discover import scan_paths
>>> result = scan_paths(["sample_assets/brick/scene.usda"])  # doctest: +SKIP
>>> [s.id for s in result.stacks]  # doctest: +SKIP
"""
from __future__ import annotations

from seamless_usd.discover.scan import open_stage, scan_mtlx, scan_paths, scan_stage
from seamless_usd.textures import (
    AuthoredAt,
    ColorSpace,
    ImageInfo,
    Origin,
    RoleUse,
    ScanResult,
    TextureMap,
    TextureStack,
    UVChain,
    UVTransform,
)

__all__ = [
    "scan_paths",
    "scan_stage",
    "scan_mtlx",
    "open_stage",
    "AuthoredAt",
    "ColorSpace",
    "ImageInfo",
    "Origin",
    "RoleUse",
    "ScanResult",
    "TextureMap",
    "TextureStack",
    "UVChain",
    "UVTransform",
]
