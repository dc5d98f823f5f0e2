"""Materials of a composed USD stage and the texture nodes their surfaces read.

The walk sees the stage as composed (payloads as loaded, references, selected variants) and goes
into instances through instance proxies. From each Material terminal (``outputs:surface``,
``outputs:mtlx:surface``, displacement) to its shader, then from every shader input upstream
through NodeGraphs, interface inputs, channel splitters and other nodes to texture nodes.
``.mtlx`` documents referenced from prims are listed for ``mtlx.py`` (usd-core cannot compose them).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pxr import Ar, Sdf, Usd, UsdShade

from seamless_usd.discover import usdgraph
from seamless_usd.discover.colorspace import Label
from seamless_usd.discover.maps import TextureUse
from seamless_usd.discover.mtlxgraph import channels_of
from seamless_usd.discover.tokens import (
    COLOUR_TYPES,
    MTLX_SUFFIX,
    mtlx_image_type,
    SEPARATE_OUTPUTS,
    tile_token,
    Inputs,
    MtlxInputs,
    Codes,
    Recorded,
    ShaderIds,
    Terminals,
    Wrap,
)
from seamless_usd.textures import NORMAL_ROLES, ColorSpace, Origin, RecordedSource, RoleUse
from seamless_usd.discover.uv import usd_uv_chain
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref

__all__ = ["MtlxReference", "walk_stage", "is_texture_id"]

_MAX_DEPTH = 64


@dataclass(frozen=True)
class MtlxReference:
    """A prim that references or payloads a ``.mtlx`` document."""

    prim: str  # referencing prim path
    document: str  # resolved document path ("" when it does not resolve)
    asset: str  # as authored
    target: str  # referenced prim path inside the document ("" for its default prim)
    layer: str  # layer holding the reference


def is_texture_id(sid: str) -> bool:
    return (
        sid == ShaderIds.UV_TEXTURE
        or sid.startswith((ShaderIds.ND_IMAGE, ShaderIds.ND_TILEDIMAGE))
        or (sid.startswith(ShaderIds.ND_GLTF) and "image" in sid)
    )


def _is_uv_id(sid: str) -> bool:
    return (
        sid in (ShaderIds.TRANSFORM_2D,)
        or sid.startswith(("UsdPrimvarReader", ShaderIds.ND_PLACE2D, ShaderIds.ND_TEXCOORD, ShaderIds.ND_GEOMPROPVALUE))
    )


def walk_stage(stage: Usd.Stage) -> tuple[list[str], list[TextureUse], list[MtlxReference], list[Finding]]:
    """Materials (``<path>``), texture uses, ``.mtlx`` references and errors of a composed stage.

    A material whose network cannot be followed is reported as an error finding; the rest go on.
    """
    materials: list[str] = []
    uses: list[TextureUse] = []
    refs: list[MtlxReference] = []
    errors: list[Finding] = []
    for prim in stage.Traverse(Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate)):
        refs.extend(_mtlx_references(prim))
        if prim.IsA(UsdShade.Material):
            materials.append(prim_ref(prim.GetPath()))
            try:
                found, custom = _material_uses(UsdShade.Material(prim))
                uses.extend(found)
                errors.extend(_file_node_finding(node, consumer, prim_ref(prim.GetPath())) for node, consumer in custom)
            except Exception as exc:  # noqa: BLE001 - one bad material must not stop the scan
                errors.append(Finding(Severity.ERROR, Codes.DISCOVERY_ERROR, prim_ref(prim.GetPath()),
                                      f"cannot follow the material network: {type(exc).__name__}: {exc}"))
    return materials, uses, refs, errors


def _mtlx_references(prim: Usd.Prim) -> list[MtlxReference]:
    found = []
    for spec in prim.GetPrimStack():
        items = list(spec.referenceList.GetAddedOrExplicitItems()) + list(spec.payloadList.GetAddedOrExplicitItems())
        for item in items:
            if not item.assetPath.lower().endswith(MTLX_SUFFIX):
                continue
            resolved = str(Ar.GetResolver().Resolve(usdgraph.anchored(spec.layer, item.assetPath)))
            found.append(
                MtlxReference(
                    prim=str(prim.GetPath()),
                    document=resolved,
                    asset=item.assetPath,
                    target=str(item.primPath) if item.primPath != Sdf.Path.emptyPath else "",
                    layer=spec.layer.realPath or spec.layer.identifier,
                )
            )
    return found


def _file_node_finding(node: Usd.Prim, consumer: str, material: str) -> Finding:
    """A skipped finding for a shader that takes a file but is no texture node this tool reads (an ``info:id`` it does
    not know, a misspelt ``UsdUVTextur`` among them): its material is left alone, saying so (it was dropped without
    a word, and the material's other maps were tiled on their own)."""
    sid = usdgraph.shader_id(node)
    files = [v.path for i in UsdShade.Shader(node).GetInputs()
             if isinstance(v := i.Get(), Sdf.AssetPath) and v.path]
    shown = f" {asset_ref(files[0])}" if files else ""
    import difflib

    what = f"a shader of id {sid!r}" if sid else "a shader with no info:id"
    hint = (f" (is the id {ShaderIds.UV_TEXTURE!r}?)" if not sid or difflib.get_close_matches(
        sid, [ShaderIds.UV_TEXTURE], cutoff=0.8) else "")
    return Finding(Severity.SKIPPED, Codes.FILE_NODE_NOT_READ, f"{prim_ref(node.GetPath())}{shown}",
                   f"{consumer} reads a file through {what}, which this tool does not make tileable{hint} "
                   f"(material {material})", material=material)


def _material_uses(material: UsdShade.Material) -> tuple[list[TextureUse], list[tuple[Usd.Prim, str]]]:
    """The material's texture uses, and the shaders with a file input its surface reads that are no texture node
    this tool knows, each with the input reading it."""
    mat_name = prim_ref(material.GetPath())
    shaders: dict[str, Usd.Prim] = {}
    for output in material.GetOutputs():
        if output.GetBaseName().split(":")[-1] not in Terminals.NAMES:
            continue
        for prim, _, _ in usdgraph.producing_outputs(output):
            shaders.setdefault(str(prim.GetPath()), prim)
    uses: list[TextureUse] = []
    custom: dict[str, tuple[Usd.Prim, str]] = {}
    for shader in shaders.values():
        for inp in UsdShade.Shader(shader).GetInputs():
            role = inp.GetBaseName()
            consumer = f"<{shader.GetPath()}.{inp.GetAttr().GetName()}>"
            for tex, channels, flip in _trace(inp, None, 0, False):
                if channels is None:
                    custom.setdefault(str(tex.GetPath()), (tex, consumer))
                else:
                    uses.append(_texture_use(mat_name, tex, RoleUse(role, channels, consumer), flip))
    return uses, list(custom.values())


def _pick(channels: str, pick: tuple[int, ...] | None) -> str:
    if pick is None:
        return channels
    return "".join(channels[i] for i in pick if i < len(channels)) or channels


def _compose(inner: tuple[int, ...], outer: tuple[int, ...] | None) -> tuple[int, ...]:
    return inner if outer is None else tuple(inner[i] for i in outer if i < len(inner))


def _trace(inp, pick, depth, flip, seen=None):
    """Yield ``(texture prim, channels, normal_y_flip)`` for every texture node feeding ``inp``.

    ``seen`` holds the (node, output, channel pick, flip) visits of this trace: a node reached
    again the same way yields nothing new, so cycles end and shared upstream nodes (diamonds,
    a mix fed twice by one node) are walked once instead of once per path (exponential).
    """
    if depth > _MAX_DEPTH:
        return
    seen = set() if seen is None else seen
    for prim, out_name, out_type in usdgraph.producing_outputs(inp):
        visit = (str(prim.GetPath()), out_name, pick, flip)
        if visit in seen:
            continue
        seen.add(visit)
        sid = usdgraph.shader_id(prim)
        if is_texture_id(sid):
            channels = channels_of(out_type, out_name) if sid != ShaderIds.UV_TEXTURE else out_name
            yield prim, _pick(channels or "rgb", pick), flip
            continue
        if _is_uv_id(sid):
            continue
        shader = UsdShade.Shader(prim)
        if any(isinstance(i.Get(), Sdf.AssetPath) and i.Get().path for i in shader.GetInputs()):
            yield prim, None, flip  # a shader reading a file this tool does not know: named, not followed
            continue
        if sid.startswith(ShaderIds.ND_SEPARATE) and out_name in SEPARATE_OUTPUTS:
            yield from _trace(shader.GetInput(MtlxInputs.IN), _compose((SEPARATE_OUTPUTS[out_name],), pick), depth + 1, flip, seen)
            continue
        if sid.startswith(ShaderIds.ND_EXTRACT):
            index, _ = usdgraph.input_value(prim, MtlxInputs.INDEX, 0)
            yield from _trace(shader.GetInput(MtlxInputs.IN), _compose((int(index),), pick), depth + 1, flip, seen)
            continue
        if sid.startswith(ShaderIds.ND_NORMALMAP):
            scale, _ = usdgraph.input_value(prim, MtlxInputs.SCALE, 1.0)
            flip = flip or _negative_y(scale)
        for upstream in shader.GetInputs():
            if upstream.HasConnectedSource():
                yield from _trace(upstream, pick, depth + 1, flip, seen)


def _negative_y(scale) -> bool:
    try:
        return float(scale[1]) < 0
    except (TypeError, IndexError):
        return False


def _texture_use(material: str, tex: Usd.Prim, role: RoleUse, flip: bool) -> TextureUse:
    sid = usdgraph.shader_id(tex)
    is_preview = sid == ShaderIds.UV_TEXTURE
    file_attr = usdgraph.value_attribute(tex, Inputs.FILE)
    asset = resolved = udim = expected = ""
    file_at = None
    in_variant = False
    labels: list[Label] = []
    animated = 0
    if file_attr is not None:
        animated = file_attr.GetNumTimeSamples()  # a texture swapped over time: its default is not what renders
        asset, resolved = usdgraph.asset_text(file_attr.Get())
        spec = usdgraph.value_spec(file_attr)  # the opinion whose value is read: where, and whether in a variant
        file_at = usdgraph.authored_at(file_attr, spec)
        in_variant = spec is not None and spec.path.ContainsPrimVariantSelection()
        expected = _anchor(file_attr, asset) if asset else ""
        if tile_token(asset):
            udim = expected
    if is_preview:
        source_cs, _ = usdgraph.input_value(tex, Inputs.SOURCE_COLOR_SPACE, "auto")
        if str(source_cs) in (ColorSpace.SRGB.value, ColorSpace.RAW.value):
            labels.append(Label(str(source_cs), "inputs:sourceColorSpace"))
        elif str(source_cs) not in ("auto", ""):  # not a UsdUVTexture token: read as auto, and said so
            labels.append(Label(str(source_cs), "inputs:sourceColorSpace", understood=False))
    node_file = UsdShade.Shader(tex).GetInput(Inputs.FILE)
    holders = [node_file.GetAttr()] if node_file else []
    if file_attr is not None and file_attr.GetPath() not in [a.GetPath() for a in holders]:
        holders.append(file_attr)  # the interface input holding the value
    for attr in holders:
        if attr.HasColorSpace():
            labels.append(Label(attr.GetColorSpace(), "colorSpace metadata"))
    image_type = None if is_preview else mtlx_image_type(sid)
    if image_type is not None and image_type not in COLOUR_TYPES:  # as in a .mtlx document (discover.mtlx)
        labels = [Label("raw", f"MaterialX {image_type} image, never colour-transformed")]
    if is_preview:
        scale, _ = usdgraph.input_value(tex, Inputs.SCALE, None)
        bias, _ = usdgraph.input_value(tex, Inputs.BIAS, None)
        wrap_s, _ = usdgraph.input_value(tex, Inputs.WRAP_S, Wrap.USD_DEFAULT)
        wrap_t, _ = usdgraph.input_value(tex, Inputs.WRAP_T, Wrap.USD_DEFAULT)
        scale_t = usdgraph.as_tuple(scale, 4, (1.0, 1.0, 1.0, 1.0))
        bias_t = usdgraph.as_tuple(bias, 4, (0.0, 0.0, 0.0, 0.0))
        flip = flip or scale_t[1] < 0
    else:
        scale_t, bias_t = (1.0, 1.0, 1.0, 1.0), (0.0, 0.0, 0.0, 0.0)
        tiled = sid.startswith(ShaderIds.ND_TILEDIMAGE)
        wrap_s = Wrap.MTLX_DEFAULT if tiled else usdgraph.input_value(tex, MtlxInputs.UADDRESSMODE, Wrap.MTLX_DEFAULT)[0]
        wrap_t = Wrap.MTLX_DEFAULT if tiled else usdgraph.input_value(tex, MtlxInputs.VADDRESSMODE, Wrap.MTLX_DEFAULT)[0]
    return TextureUse(
        material=material,
        node=str(tex.GetPath()),
        node_type=sid,
        origin=Origin.USD,
        asset=asset,
        resolved=resolved,
        udim_pattern=udim,
        expected=expected,
        file_at=file_at,
        role=role,
        labels=labels,
        scale=scale_t,
        bias=bias_t,
        wrap_s=str(wrap_s),
        wrap_t=str(wrap_t),
        uv=usd_uv_chain(tex, sid),
        normal_y_flip=flip and role.role in NORMAL_ROLES,
        recorded_passed=_recorded_passed(tex),
        recorded_source=_recorded_source(tex),
        animated=animated,
        file_in_variant=in_variant,
    )


def _recorded_passed(tex: Usd.Prim) -> bool | None:
    """Whether the tile on ``tex`` passed when this tool wrote it (its provenance), or None when it is not one."""
    source, passed = tex.GetAttribute(Recorded.USD_SOURCE), tex.GetAttribute(Recorded.USD_PASSED)
    if not (source and source.HasAuthoredValue() and passed and passed.HasAuthoredValue()):
        return None
    return bool(passed.Get())


def _recorded_source(tex: Usd.Prim) -> RecordedSource | None:
    """The source the tile on ``tex`` records (its provenance), or None when it is not one of this tool's tiles."""
    attr = tex.GetAttribute(Recorded.USD_SOURCE)
    value = attr.Get() if attr and attr.HasAuthoredValue() else None
    if not isinstance(value, Sdf.AssetPath) or not value.path:
        return None
    resolved = value.resolvedPath
    return RecordedSource(value.path, resolved if resolved and Path(resolved).is_file() else "")


def _anchor(attr: Usd.Attribute, asset: str) -> str:
    for spec in attr.GetPropertyStack(Usd.TimeCode.Default()):
        if spec.HasDefaultValue():
            return usdgraph.anchored(spec.layer, asset)
    return asset
