"""Reading a USD shading network the way authoring needs it: node kinds, values where they are
authored, connections, and the composed UV affine map of a texture.

Shared by the planning (``usdplan``), in-place (``usdinplace``) and entry-point (``usd``) modules.
"""
from __future__ import annotations

import os

from pxr import Sdf, Usd, UsdShade

from seamless_usd.authoring.uvmath import Affine2, place2d, transform2d

__all__ = ["Names", "uv_affine"]


class Names:
    """Node ids, input names and values, named once."""

    OUTPUT_SUFFIX = ".seamless"  # scene.usda -> scene.seamless.usda
    MADE_FROM = "seamlessMadeFrom"  # the new layer's customLayerData: the SHA-256 of the stage it was made over
    UV_NODE = "SeamlessUV"
    SHADER_TYPE = "Shader"
    INFO_ID = "info:id"
    USD_UV_TEXTURE = "UsdUVTexture"
    USD_TRANSFORM_2D = "UsdTransform2d"
    MX_PLACE_2D = "ND_place2d_vector2"
    MX_TEXCOORD = "ND_texcoord_vector2"
    UV_READER = "SeamlessUVReader"  # the texcoord node (UV0) a MaterialX image with no texcoord input gets
    MX_IMAGE_PREFIX = "ND_image_"
    MX_TILED_PREFIX = "ND_tiledimage_"
    MX_GLTF_IMAGE_PREFIX = "ND_gltf_"
    FILE = "file"
    ST = "st"
    TEXCOORD = "texcoord"
    IN = "in"
    RESULT = "result"
    OUT = "out"
    SCALE = "scale"
    ROTATION = "rotation"
    TRANSLATION = "translation"
    PIVOT = "pivot"
    ROTATE = "rotate"
    OFFSET = "offset"
    OPERATION_ORDER = "operationorder"
    WRAP_S = "wrapS"
    WRAP_T = "wrapT"
    REPEAT = "repeat"
    U_ADDRESS = "uaddressmode"
    V_ADDRESS = "vaddressmode"
    PERIODIC = "periodic"
    UV_TILING = "uvtiling"
    UV_OFFSET = "uvoffset"






class _Kind:
    USD_UV_TEXTURE = "UsdUVTexture"
    MX_IMAGE = "mx-image"
    MX_TILED = "mx-tiledimage"
    MX_GLTF = "mx-gltf-image"
    OTHER = "other"


def _kind(shader: UsdShade.Shader) -> str:
    node_id = shader.GetShaderId() or ""
    if node_id == Names.USD_UV_TEXTURE:
        return _Kind.USD_UV_TEXTURE
    if node_id.startswith(Names.MX_TILED_PREFIX):
        return _Kind.MX_TILED
    if node_id.startswith(Names.MX_IMAGE_PREFIX):
        return _Kind.MX_IMAGE
    if node_id.startswith(Names.MX_GLTF_IMAGE_PREFIX) and "image" in node_id:
        return _Kind.MX_GLTF
    return _Kind.OTHER


def _uv_input_name(kind: str) -> str:
    return Names.ST if kind == _Kind.USD_UV_TEXTURE else Names.TEXCOORD


def _uv_source(shader: UsdShade.Shader, kind: str) -> UsdShade.ConnectableAPI | None:
    uv_input = shader.GetInput(_uv_input_name(kind))
    return _connected(uv_input) if uv_input else None


def _connected(shade_input: UsdShade.Input | None) -> UsdShade.ConnectableAPI | None:
    """The node (or Material / NodeGraph) ``shade_input`` is connected to, if any."""
    if not shade_input:
        return None
    sources, _invalid = shade_input.GetConnectedSources()
    return sources[0].source if sources else None


def _producing_attr(shade_input: UsdShade.Input | None) -> Usd.Attribute | None:
    """The attribute whose authored value ``shade_input`` gets (itself when nothing is authored)."""
    if not shade_input:
        return None
    attrs = shade_input.GetValueProducingAttributes(shaderOutputsOnly=False)
    for attr in attrs:
        if UsdShade.Input.IsInput(attr):
            return attr
    return None if attrs else shade_input.GetAttr()


def _value(shade_input: UsdShade.Input | None, default):
    attr = _producing_attr(shade_input)
    value = attr.Get() if attr else None
    if value is None:
        return default
    return tuple(float(v) for v in value) if isinstance(default, tuple) else value


def _close(a, b, tol: float = 1e-6) -> bool:
    if a is None or b is None:
        return False
    return all(abs(float(x) - float(y)) <= tol * max(1.0, abs(float(x))) for x, y in zip(a, b))



def _connection_source_attr(shade_input: UsdShade.Input) -> Sdf.Path:
    sources, _invalid = shade_input.GetConnectedSources()
    info = sources[0]
    prefix = "outputs:" if info.sourceType == UsdShade.AttributeType.Output else "inputs:"
    return info.source.GetPath().AppendProperty(prefix + info.sourceName)


def _gltf_transform_is_identity(shader: UsdShade.Shader) -> bool:
    affine = place2d(
        _value(shader.GetInput(Names.PIVOT), (0.0, 0.0)),
        _value(shader.GetInput(Names.SCALE), (1.0, 1.0)),
        _value(shader.GetInput(Names.ROTATE), 0.0),
        _value(shader.GetInput(Names.OFFSET), (0.0, 0.0)),
        int(_value(shader.GetInput(Names.OPERATION_ORDER), 0)),
    )
    return affine.close_to(Affine2())


def _same_file(asset: Sdf.AssetPath | None, path: str) -> bool:
    if not asset or not path:
        return False
    resolved = asset.resolvedPath if isinstance(asset, Sdf.AssetPath) else str(asset)
    if not resolved:
        return False
    try:
        return os.path.samefile(resolved, path)
    except OSError:
        return os.path.normcase(os.path.abspath(resolved)) == os.path.normcase(os.path.abspath(path))



def uv_affine(stage: Usd.Stage, texture: str | Sdf.Path) -> Affine2:
    """The composed affine map from the primvar read to the UVs ``texture`` samples with.

    Follows the texture's ``st`` / ``texcoord`` connection through ``UsdTransform2d`` and
    MaterialX ``place2d`` nodes (input values read where they are authored, e.g. on Material
    interface inputs) down to the primvar reader, and includes a ``tiledimage``'s own
    ``uvtiling`` / ``uvoffset``.
    """
    prim = stage.GetPrimAtPath(str(texture))
    shader = UsdShade.Shader(prim)
    kind = _kind(shader)
    total = Affine2()
    if kind == _Kind.MX_TILED:
        tiling = _value(shader.GetInput(Names.UV_TILING), (1.0, 1.0))
        offset = _value(shader.GetInput(Names.UV_OFFSET), (0.0, 0.0))
        total = Affine2(a=tiling[0], d=tiling[1], tx=-offset[0], ty=-offset[1])
    source = _uv_source(shader, kind)
    steps = []
    seen = set()
    while source is not None and source.GetPrim().GetPath() not in seen:
        node = UsdShade.Shader(source.GetPrim())
        seen.add(node.GetPath())
        node_id = node.GetShaderId() or ""
        if node_id == Names.USD_TRANSFORM_2D:
            steps.append(transform2d(
                _value(node.GetInput(Names.SCALE), (1.0, 1.0)),
                _value(node.GetInput(Names.ROTATION), 0.0),
                _value(node.GetInput(Names.TRANSLATION), (0.0, 0.0)),
            ))
            source = _connected(node.GetInput(Names.IN))
        elif node_id == Names.MX_PLACE_2D:
            steps.append(place2d(
                _value(node.GetInput(Names.PIVOT), (0.0, 0.0)),
                _value(node.GetInput(Names.SCALE), (1.0, 1.0)),
                _value(node.GetInput(Names.ROTATE), 0.0),
                _value(node.GetInput(Names.OFFSET), (0.0, 0.0)),
                int(_value(node.GetInput(Names.OPERATION_ORDER), 0)),
            ))
            source = _connected(node.GetInput(Names.TEXCOORD))
        else:
            break  # primvar reader / geomprop: the chain starts here
    chain = Affine2()
    for step in reversed(steps):  # collected texture-first; apply reader-first
        chain = chain.then(step)
    return chain.then(total)


