"""From texture uses found in a material to maps, or to skip findings with a reason.

Traversal (``usd.py``, ``mtlx.py``) reports one :class:`TextureUse` per (material, texture node,
surface input). Here the uses of one node are merged into one :class:`TextureMap` (a packed ORM
node becomes one map with three roles), its file is checked and its header read, and its colour
space resolved.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from seamless_usd.discover.colorspace import Label, mismatch_finding, resolve_color_space
from seamless_usd.discover.images import ImageReadError, is_package_path, read_image_info, udim_tiles
from seamless_usd.discover.tokens import MIN_IMAGE_SIZE, Codes, ShaderIds, tile_token
from seamless_usd.textures import AuthoredAt, ImageInfo, Origin, RecordedSource, RoleUse, TextureMap, UVChain
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref

__all__ = ["TextureUse", "build_maps", "HeaderCache"]


@dataclass
class TextureUse:
    """One surface input reading one texture node of one material."""

    material: str
    node: str
    node_type: str
    origin: Origin
    asset: str  # as authored; "" when no file is authored
    resolved: str  # resolved path ("" when it does not resolve)
    udim_pattern: str  # absolute path with <UDIM> left in (for listing tiles), else ""
    file_at: AuthoredAt | None
    role: RoleUse
    expected: str = ""  # where the file was looked for (for messages)
    labels: list[Label] = field(default_factory=list)  # colour-space labels, precedence order
    scale: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    bias: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    wrap_s: str = "useMetadata"
    wrap_t: str = "useMetadata"
    uv: UVChain | None = None  # None: the node has no texture-coordinate input (swatch)
    document: str | None = None
    normal_y_flip: bool = False
    selection: tuple = ()  # variant selection it was found under (VariantChoice; () : the stage's own)
    recorded_passed: bool | None = None  # a tile this tool wrote: whether it passed when written (else None)
    recorded_source: RecordedSource | None = None  # a tile this tool wrote: the source it records
    animated: int = 0  # time samples of its file input (a texture swapped over time), 0 when none
    #: its file value comes from inside a variant under every selection it was found in (each variant's edits of the
    #: node then go inside that variant: two look variants naming the same file do not share one edit)
    file_in_variant: bool = False

    def key(self) -> tuple:
        """What makes two uses found under two variant selections the same use."""
        return (self.material, self.node, self.asset, self.resolved, self.role, self.uv.key if self.uv else None,
                self.wrap_s, self.wrap_t, self.scale, self.bias, self.document)


class HeaderCache(dict):
    """Resolved path -> ImageInfo or the error text, so each file's header is read once."""

    def get_info(self, resolved: str) -> ImageInfo | str:
        if resolved not in self:
            try:
                self[resolved] = read_image_info(resolved)
            except (OSError, ImageReadError) as exc:
                self[resolved] = str(exc) or type(exc).__name__
        return self[resolved]


def build_maps(uses: list[TextureUse], cache: HeaderCache | None = None) -> tuple[list[TextureMap], list[Finding]]:
    """Merge uses per (material, node), check files, read headers, resolve colour spaces."""
    cache = HeaderCache() if cache is None else cache
    grouped: dict[tuple, list[TextureUse]] = {}
    for use in uses:
        grouped.setdefault((use.material, use.node, use.selection), []).append(use)
    maps: list[TextureMap] = []
    findings: list[Finding] = []
    for group in grouped.values():
        made, found = _one_map(group, cache)
        findings.extend(found)
        if made is not None:
            maps.append(made)
    return maps, findings


def _where(use: TextureUse) -> str:
    node = prim_ref(use.node)
    return f"{node} {asset_ref(use.asset)}" if use.asset else node


def _skip(use: TextureUse, code: str, message: str) -> Finding:
    doc = f" in {asset_ref(use.document)}" if use.document else ""
    return Finding(
        Severity.SKIPPED, code, _where(use), f"{message} (material {use.material}{doc})", material=use.material
    )


def _one_map(group: list[TextureUse], cache: HeaderCache) -> tuple[TextureMap | None, list[Finding]]:
    first = group[0]
    roles: list[RoleUse] = []
    for use in group:
        if use.role not in roles:
            roles.append(use.role)
    if first.animated:
        return None, [_skip(first, Codes.ANIMATED_FILE, f"its file input is animated ({first.animated} time "
                                                        "sample(s)): a texture swapped over time is not made tileable")]
    if not first.asset or first.file_at is None:
        return None, [_skip(first, Codes.NO_FILE, "texture node has no file")]
    if first.uv is None:
        return None, [_skip(first, Codes.NO_UV, "texture has no texture-coordinate input (a swatch texture)")]
    if tile_token(first.asset):
        tiles = udim_tiles(first.udim_pattern) if first.udim_pattern else []
        listed = ", ".join(tiles) if tiles else "none found"
        return None, [_skip(first, Codes.UDIM, f"texture tile sets ({tile_token(first.asset)}) are not made "
                                                f"tileable (UDIM); tiles: {listed}. A tile set spreads one texture "
                                                "over several UV squares; a texture meant to repeat is one file: "
                                                "point the material at it to make it tileable")]
    recorded = first.recorded_source
    tile_missing = not first.resolved and bool(recorded and recorded.resolved)
    findings: list[Finding] = []
    if tile_missing:  # a tile this tool wrote, deleted since: made again from the source it records
        findings.append(Finding(Severity.WARNING, Codes.TILE_MISSING, _where(first),
                                f"this tile is not there; its recorded source {asset_ref(recorded.asset)} is, and "
                                "process makes the tile again from it", material=first.material))
        first = replace(first, resolved=recorded.resolved)
    elif not first.resolved:
        looked = f" at {first.expected}" if first.expected and first.expected != first.asset else ""
        searched = (first.origin is Origin.USD and not first.asset.startswith(("./", "../"))
                    and not Path(first.asset).is_absolute())  # USD's search-path form; MaterialX's names are paths
        how = ("; a name that is not a path (no ./, ../ or /) is also looked for on the asset resolver's search "
               "path: add its folder to PXR_AR_DEFAULT_SEARCH_PATH, or write the path from the layer"
               if searched else "; restore the file or fix the asset path")
        return None, [_skip(first, Codes.MISSING_FILE, f"texture file not found{looked}{how}")]
    info = cache.get_info(first.resolved)
    if isinstance(info, str):
        return None, [_skip(first, Codes.UNREADABLE_FILE, f"cannot read the image header: {info}")]
    if min(info.width, info.height) < MIN_IMAGE_SIZE:
        return None, [
            _skip(first, Codes.TOO_SMALL, f"image is {info.width}x{info.height} px, below the {MIN_IMAGE_SIZE} px of the smallest tile")
        ]
    cs, reason, unknown = resolve_color_space(first.labels, info)
    for name in unknown:
        findings.append(
            Finding(Severity.WARNING, Codes.UNKNOWN_COLORSPACE, _where(first),
                    f"colour space {name!r} is not understood; passed over (now {cs.value}, {reason})")
        )
    mismatch = mismatch_finding(tuple(roles), cs, reason, _where(first))
    if mismatch is not None:
        findings.append(mismatch)
    tmap = TextureMap(
        material=first.material,
        node=first.node,
        node_type=first.node_type,
        origin=first.origin,
        asset=first.asset,
        resolved=first.resolved,
        file_at=first.file_at,
        file_in_variant=first.file_in_variant,
        roles=tuple(roles),
        color_space=cs,
        color_space_reason=reason,
        scale=first.scale,
        bias=first.bias,
        wrap_s=first.wrap_s,
        wrap_t=first.wrap_t,
        uv=first.uv,
        image=info,
        document=first.document,
        in_package=is_package_path(first.resolved),
        normal_y_flip=first.normal_y_flip,
        selection=first.selection,
        recorded_passed=first.recorded_passed,
        recorded_source=first.recorded_source,
        tile_missing=tile_missing,
    )
    if (
        tmap.is_normal
        and tmap.node_type == ShaderIds.UV_TEXTURE
        and info.dtype in ("uint8", "uint16")
        and tmap.scale[:3] == (1.0, 1.0, 1.0)
        and tmap.bias[:3] == (0.0, 0.0, 0.0)
    ):
        findings.append(
            Finding(Severity.WARNING, Codes.NORMAL_SCALE_BIAS, _where(first),
                    "integer normal map read with scale 1 and bias 0: UsdPreviewSurface expects "
                    "scale (2, 2, 2, 1) and bias (-1, -1, -1, 0)")
        )
    return tmap, findings
