"""The UV chain feeding a texture node: primvar reader, existing transforms, tiling.

USD: ``UsdUVTexture.inputs:st`` (or a MaterialX node's ``texcoord``) traced through
``UsdTransform2d`` / ``ND_place2d_*`` to a ``UsdPrimvarReader_float2`` / ``ND_texcoord_*`` /
``ND_geompropvalue_*``. MaterialX documents: the same through ``place2d``, ``texcoord`` and
``geompropvalue`` nodes, plus ``tiledimage``'s own ``uvtiling``/``uvoffset``. Transform values
authored on an interface input are listed in ``UVTransform.authored`` so authoring edits them there.
"""
from __future__ import annotations

from dataclasses import replace

import MaterialX as mx
from pxr import Usd, UsdShade

from seamless_usd.discover import mtlxgraph, usdgraph
from seamless_usd.discover.tokens import Inputs, MtlxCategories, MtlxInputs, Recorded, ShaderIds, TransformKinds
from seamless_usd.textures import AuthoredAt, UVChain, UVTransform

__all__ = ["usd_uv_chain", "mtlx_uv_chain"]

_MAX_CHAIN = 32
GLTF_PIVOT = (0.0, 1.0)  # KHR_texture_transform pivot as in the MaterialX gltf_image nodedefs


def _is_identity(t: UVTransform) -> bool:
    return t.scale == (1.0, 1.0) and t.rotation == 0.0 and t.translation == (0.0, 0.0) and not t.authored


def _pair(value, default=(0.0, 0.0)) -> tuple[float, float]:
    return usdgraph.as_tuple(value, 2, default)


def _usd_inputs(prim: Usd.Prim, spec: dict[str, tuple[str, object]]):
    """Read transform inputs: ``spec`` maps field -> (input name, default)."""
    values: dict[str, object] = {}
    authored: list[tuple[str, AuthoredAt]] = []
    for field, (name, default) in spec.items():
        value, where = usdgraph.input_value(prim, name, default)
        values[field] = value
        if where is not None:
            authored.append((name, where))
    return values, tuple(authored)


def _usd_transform(prim: Usd.Prim, sid: str, pivot_default=(0.0, 0.0)) -> UVTransform:
    path = str(prim.GetPath())
    if sid == ShaderIds.TRANSFORM_2D:
        v, authored = _usd_inputs(
            prim,
            {"scale": (Inputs.SCALE, None), "rotation": (Inputs.ROTATION, 0.0), "translation": (Inputs.TRANSLATION, None)},
        )
        return UVTransform(
            node=path, kind=TransformKinds.USD_TRANSFORM_2D, scale=_pair(v["scale"], (1.0, 1.0)),
            rotation=float(v["rotation"]), translation=_pair(v["translation"]), authored=authored,
        )
    v, authored = _usd_inputs(
        prim,
        {
            "scale": (MtlxInputs.SCALE, None), "rotate": (MtlxInputs.ROTATE, 0.0), "offset": (MtlxInputs.OFFSET, None),
            "pivot": (MtlxInputs.PIVOT, None), "order": (MtlxInputs.OPERATIONORDER, 0),
        },
    )
    return UVTransform(
        node=path, kind=TransformKinds.PLACE2D, scale=_pair(v["scale"], (1.0, 1.0)), rotation=float(v["rotate"]),
        translation=_pair(v["offset"]), pivot=_pair(v["pivot"], pivot_default), operation_order=int(v["order"]),
        authored=authored,
    )


def _usd_uvtiling(prim: Usd.Prim) -> UVTransform:
    v, authored = _usd_inputs(prim, {"tiling": (MtlxInputs.UVTILING, None), "offset": (MtlxInputs.UVOFFSET, None)})
    return UVTransform(
        node=str(prim.GetPath()), kind=TransformKinds.UVTILING, scale=_pair(v["tiling"], (1.0, 1.0)),
        translation=_pair(v["offset"]), authored=authored,
    )


def usd_uv_chain(texture: Usd.Prim, sid: str) -> UVChain | None:
    """UV chain of a USD texture shader; None for a UsdUVTexture with no ``st`` connection.

    A MaterialX image node with nothing on ``texcoord`` reads the default texture coordinates
    (``primvar`` and ``reader`` None).
    """
    is_preview = sid == ShaderIds.UV_TEXTURE
    nearest: list[UVTransform] = []  # nearest the texture first
    if sid.startswith(ShaderIds.ND_TILEDIMAGE):
        nearest.append(_usd_uvtiling(texture))
    elif sid.startswith(ShaderIds.ND_GLTF):
        builtin = _usd_transform(texture, sid, GLTF_PIVOT)  # glTF image nodes hold a place2d
        if not _is_identity(builtin):
            nearest.append(builtin)
    inp = UsdShade.Shader(texture).GetInput(Inputs.ST if is_preview else MtlxInputs.TEXCOORD)
    sources = usdgraph.producing_outputs(inp) if inp else []
    if not sources:
        return None if is_preview else UVChain(None, None, tuple(reversed(nearest)))
    prim, out_name, _ = sources[0]
    connected_from = f"{prim.GetPath()}.outputs:{out_name}"
    primvar = reader = None
    before = _BeforeOurs(connected_from)
    for _ in range(_MAX_CHAIN):
        node_id = usdgraph.shader_id(prim)
        if node_id == ShaderIds.TRANSFORM_2D or node_id.startswith(ShaderIds.ND_PLACE2D):
            ours = Recorded.USD_UV_API in prim.GetPrimTypeInfo().GetAppliedAPISchemas() or (
                Recorded.USD_UV_API in prim.GetAppliedSchemas())
            nearest.append(replace(_usd_transform(prim, node_id), ours=ours))
            nxt = UsdShade.Shader(prim).GetInput(Inputs.IN if node_id == ShaderIds.TRANSFORM_2D else MtlxInputs.TEXCOORD)
            ups = usdgraph.producing_outputs(nxt) if nxt else []
            before.step(ours, f"{ups[0][0].GetPath()}.outputs:{ups[0][1]}" if ups else None)
            if not ups:
                break
            prim = ups[0][0]
            continue
        reader = str(prim.GetPath())
        if node_id.startswith("UsdPrimvarReader"):
            value, _ = usdgraph.input_value(prim, Inputs.VARNAME, "")
            primvar = str(value) if value else None
        elif node_id.startswith(ShaderIds.ND_GEOMPROPVALUE):
            value, _ = usdgraph.input_value(prim, MtlxInputs.GEOMPROP, "")
            primvar = str(value) if value else None
        elif node_id.startswith(ShaderIds.ND_TEXCOORD):
            index, _ = usdgraph.input_value(prim, MtlxInputs.INDEX, 0)
            primvar = "st" if int(index) == 0 else f"st{int(index)}"
        break
    ours_reader = bool(reader) and reader.rsplit("/", 1)[-1].startswith(Recorded.USD_UV_READER)
    return UVChain(primvar=primvar, reader=reader, transforms=tuple(reversed(nearest)), connected_from=connected_from,
                   before_ours=before.chain(primvar, reader, ours_reader))


def _mx_pair(value, default=(0.0, 0.0)) -> tuple[float, float]:
    if value is None:
        return default
    if isinstance(value, (int, float)):
        return (float(value), float(value))
    return (float(value[0]), float(value[1]))


def _mx_inputs(node: mx.Node, document: str, spec: dict[str, tuple[str, object]]):
    values: dict[str, object] = {}
    authored: list[tuple[str, AuthoredAt]] = []
    for field, (name, default) in spec.items():
        value, where = mtlxgraph.input_value(node, name, default, document)
        values[field] = value
        if where is not None:
            authored.append((name, where))
    return values, tuple(authored)


def _mx_place2d(node: mx.Node, document: str, pivot_default=(0.0, 0.0)) -> UVTransform:
    v, authored = _mx_inputs(
        node, document,
        {"scale": (MtlxInputs.SCALE, None), "rotate": (MtlxInputs.ROTATE, 0.0), "offset": (MtlxInputs.OFFSET, None),
         "pivot": (MtlxInputs.PIVOT, None), "order": (MtlxInputs.OPERATIONORDER, 0)},
    )
    return UVTransform(
        node=node.getNamePath(), kind=TransformKinds.PLACE2D, scale=_mx_pair(v["scale"], (1.0, 1.0)),
        rotation=float(v["rotate"]), translation=_mx_pair(v["offset"]), pivot=_mx_pair(v["pivot"], pivot_default),
        operation_order=int(v["order"]), authored=authored,
    )


def mtlx_uv_chain(texture: mx.Node, document: str) -> UVChain:
    """UV chain of a MaterialX texture node in a document (never None: the default is UV0)."""
    nearest: list[UVTransform] = []
    if texture.getCategory() == MtlxCategories.TILEDIMAGE:
        v, authored = _mx_inputs(texture, document, {"tiling": (MtlxInputs.UVTILING, None), "offset": (MtlxInputs.UVOFFSET, None)})
        nearest.append(
            UVTransform(node=texture.getNamePath(), kind=TransformKinds.UVTILING, scale=_mx_pair(v["tiling"], (1.0, 1.0)),
                        translation=_mx_pair(v["offset"]), authored=authored)
        )
    elif texture.getCategory() in MtlxCategories.GLTF_TEXTURES:
        builtin = _mx_place2d(texture, document, GLTF_PIVOT)  # glTF image nodes hold a place2d
        if not _is_identity(builtin):
            nearest.append(builtin)
    up = mtlxgraph.upstream(texture.getInput(MtlxInputs.TEXCOORD))
    if up is None:
        return UVChain(None, None, tuple(reversed(nearest)))
    node, out_name = up
    connected_from = f"{node.getNamePath()}.{out_name}"
    primvar = reader = None
    before = _BeforeOurs(connected_from)
    for _ in range(_MAX_CHAIN):
        category = node.getCategory()
        if category == MtlxCategories.PLACE2D:
            ours = node.hasAttribute(Recorded.MTLX_UV_MARK)
            nearest.append(replace(_mx_place2d(node, document), ours=ours))
            nxt = mtlxgraph.upstream(node.getInput(MtlxInputs.TEXCOORD))
            before.step(ours, f"{nxt[0].getNamePath()}.{nxt[1]}" if nxt else None)
            if nxt is None:
                break
            node = nxt[0]
            continue
        reader = node.getNamePath()
        if category == MtlxCategories.TEXCOORD:
            index, _ = mtlxgraph.input_value(node, MtlxInputs.INDEX, 0, document)
            primvar = f"UV{int(index)}"
        elif category == MtlxCategories.GEOMPROPVALUE:
            value, _ = mtlxgraph.input_value(node, MtlxInputs.GEOMPROP, "", document)
            primvar = str(value) or None
        break
    ours_reader = bool(reader) and reader.rsplit("/", 1)[-1].startswith(Recorded.MTLX_UV_READER)
    return UVChain(primvar=primvar, reader=reader, transforms=tuple(reversed(nearest)), connected_from=connected_from,
                   before_ours=before.chain(primvar, reader, ours_reader))


class _BeforeOurs:
    """Walks a UV chain from the texture with :func:`usd_uv_chain` / :func:`mtlx_uv_chain` and keeps what the texture
    read before the nodes this tool inserts, which always sit nearest the texture (``UVChain.before_ours``)."""

    def __init__(self, connected_from: str | None) -> None:
        self.connected = connected_from
        self.ours = False  # any of this tool's nodes seen
        self._theirs = False  # a node of the asset's own seen: nothing nearer the reader is this tool's

    def step(self, ours: bool, upstream: str | None) -> None:
        """A transform node, ``ours`` or not, reading ``upstream`` (None: nothing connected)."""
        if ours and not self._theirs:
            self.ours, self.connected = True, upstream
        else:
            self._theirs = True

    def chain(self, primvar, reader, ours_reader: bool) -> tuple | None:
        if ours_reader and not self._theirs:  # the UV0 reader this tool inserted: the image read its default UVs
            return (None, None, None)
        return (primvar, reader, self.connected) if self.ours else None
