"""Small helpers over UsdShade: shader ids, input values and where they are authored."""
from __future__ import annotations

import os

from pxr import Ar, Sdf, Usd, UsdShade

from seamless_usd.textures import AuthoredAt

__all__ = [
    "shader_id", "layer_of", "authored_at", "input_value", "value_attribute", "producing_outputs",
    "as_tuple", "asset_text", "anchored",
]


def shader_id(prim: Usd.Prim) -> str:
    """``info:id`` of a shader prim ("" when it is not a shader or has none)."""
    if not prim.IsA(UsdShade.Shader):
        return ""
    sid = UsdShade.Shader(prim).GetShaderId()
    return str(sid) if sid else ""


def value_spec(attr: Usd.Attribute) -> Sdf.PropertySpec | None:
    """The strongest spec holding a value opinion for ``attr`` (its path says whether it is inside a variant)."""
    for spec in attr.GetPropertyStack(Usd.TimeCode.Default()):
        if spec.HasDefaultValue() or spec.layer.GetNumTimeSamplesForPath(spec.path):
            return spec
    return None


def layer_of(attr: Usd.Attribute, spec: Sdf.PropertySpec | None = None) -> str:
    """The strongest layer holding a value opinion for ``attr`` (real path when it has one); ``spec``: its
    :func:`value_spec`, when at hand."""
    spec = spec if spec is not None else value_spec(attr)
    return "" if spec is None else spec.layer.realPath or spec.layer.identifier


def authored_at(attr: Usd.Attribute, spec: Sdf.PropertySpec | None = None) -> AuthoredAt:
    return AuthoredAt(prim=str(attr.GetPrim().GetPath()), attribute=attr.GetName(), layer=layer_of(attr, spec))


def _value_attribute(inp: UsdShade.Input) -> Usd.Attribute | None:
    """The attribute whose value ``inp`` reads: itself, or an interface input it is connected to."""
    for attr in inp.GetValueProducingAttributes(shaderOutputsOnly=False):
        if UsdShade.Input.IsInput(attr) and attr.HasAuthoredValue():
            return attr
    return None


def input_value(prim: Usd.Prim, name: str, default=None):
    """``(value, AuthoredAt | None)`` of input ``name`` of a shader prim.

    The location is ``None`` when the value is authored on the shader itself or falls back to
    ``default``; otherwise it names the interface input (Material or NodeGraph) holding it.
    """
    inp = UsdShade.Shader(prim).GetInput(name)
    if not inp:
        return default, None
    attr = _value_attribute(inp)
    if attr is None:
        if inp.HasConnectedSource():
            return default, None
        value = inp.Get()
        return (default if value is None else value), None
    value = attr.Get()
    if value is None:
        return default, None
    if attr.GetPrim() == prim and attr.GetName() == inp.GetAttr().GetName():
        return value, None
    return value, authored_at(attr)


def value_attribute(prim: Usd.Prim, name: str) -> Usd.Attribute | None:
    """The attribute that authors the value of input ``name`` (the input or an interface input)."""
    inp = UsdShade.Shader(prim).GetInput(name)
    return _value_attribute(inp) if inp else None


def producing_outputs(inp: UsdShade.Input | UsdShade.Output) -> list[tuple[Usd.Prim, str, str]]:
    """Shader outputs feeding ``inp`` through NodeGraphs and interface inputs.

    Each item is ``(shader prim, output base name, output type name)``.
    """
    found = []
    for attr in inp.GetValueProducingAttributes(shaderOutputsOnly=True):
        prim = attr.GetPrim()
        base = attr.GetName().split(":", 1)[1] if ":" in attr.GetName() else attr.GetName()
        found.append((prim, base, str(attr.GetTypeName().scalarType)))
    return found


def as_tuple(value, n: int, default: tuple) -> tuple:
    """Gf vectors and scalars to plain float tuples of length ``n``."""
    if value is None:
        return default
    try:
        return tuple(float(value[i]) for i in range(n))
    except (TypeError, IndexError):
        return tuple(float(value) for _ in range(n))


def asset_text(value) -> tuple[str, str]:
    """``(authored path, resolved path)`` of an ``Sdf.AssetPath`` value."""
    if isinstance(value, Sdf.AssetPath):
        return value.path, value.resolvedPath
    return (str(value) if value else ""), ""


def anchored(layer: Sdf.Layer, asset: str) -> str:
    """``asset`` as Ar resolves it from ``layer`` (relative and search paths are tried next to
    the layer first); a path next to the layer when it does not exist (for messages, UDIM tiles).
    """
    identifier = Ar.GetResolver().CreateIdentifier(asset, Ar.ResolvedPath(layer.resolvedPath or layer.identifier))
    if os.path.isabs(identifier) or Ar.IsPackageRelativePath(identifier) or not layer.realPath:
        return identifier
    return os.path.normpath(os.path.join(os.path.dirname(layer.realPath), asset))
