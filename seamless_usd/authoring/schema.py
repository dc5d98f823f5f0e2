"""The seamless-usd USD schema plugin: registration, tokens, provenance read/write.

The plugin is codeless (``plugInfo.json`` + ``generatedSchema.usda`` in the
``seamless_usd_schemas`` package, folder ``usd/``), so it works from an installed wheel with
nothing compiled. USD builds its schema registry once, the first time a stage is opened, so
:func:`register_schemas` must run before that; importing :mod:`seamless_usd.authoring` does it.
"""
from __future__ import annotations

from pathlib import Path

from pxr import Gf, Plug, Sdf, Usd

from seamless_usd.authoring.types import Provenance

__all__ = [
    "Schema",
    "register_schemas",
    "schemas_known",
    "has_applied",
    "write_provenance",
    "read_provenance",
    "mark_uv_transform",
    "is_seamless_uv_transform",
    "PROPERTIES",
]


class Schema:
    """Schema and property names, named once."""

    TILE_API = "SeamlessTileAPI"
    UV_TRANSFORM_API = "SeamlessUVTransformAPI"
    SOURCE_ASSET = "seamless:sourceAsset"
    CROP_SIZE = "seamless:cropSize"
    UV_SCALE = "seamless:uvScale"
    PASSED = "seamless:passed"
    VERDICT = "seamless:verdict"
    Q_PASSED = "seamless:qPassed"
    Q_TAU = "seamless:qTau"
    Q_BAND_MIN = "seamless:qBandMin"
    MODEL_HASH = "seamless:modelHash"
    TOOL_VERSION = "seamless:toolVersion"
    STRAIGHTENED = "seamless:straightened"
    LEVELLED = "seamless:levelled"
    EVENED = "seamless:evened"
    UV_TURN = "seamless:uvTurn"
    RECTIFIED = "seamless:rectified"


# Property name -> (Sdf type, how a Provenance value becomes a USD value).
PROPERTIES = {
    Schema.SOURCE_ASSET: (Sdf.ValueTypeNames.Asset, lambda p: Sdf.AssetPath(p.source_asset)),
    Schema.CROP_SIZE: (Sdf.ValueTypeNames.Int2, lambda p: Gf.Vec2i(*map(int, p.crop_size))),
    Schema.UV_SCALE: (Sdf.ValueTypeNames.Double2, lambda p: Gf.Vec2d(*p.uv_scale)),
    Schema.PASSED: (Sdf.ValueTypeNames.Bool, lambda p: bool(p.passed)),
    Schema.VERDICT: (Sdf.ValueTypeNames.String, lambda p: str(p.verdict)),
    Schema.Q_PASSED: (Sdf.ValueTypeNames.Bool, lambda p: bool(p.q_passed)),
    Schema.Q_TAU: (Sdf.ValueTypeNames.Double, lambda p: float(p.q_tau)),
    Schema.Q_BAND_MIN: (Sdf.ValueTypeNames.Double2, lambda p: Gf.Vec2d(*p.q_band_min)),
    Schema.MODEL_HASH: (Sdf.ValueTypeNames.String, lambda p: str(p.model_hash)),
    Schema.TOOL_VERSION: (Sdf.ValueTypeNames.String, lambda p: str(p.tool_version)),
    Schema.STRAIGHTENED: (Sdf.ValueTypeNames.Double, lambda p: float(p.straightened)),
    Schema.LEVELLED: (Sdf.ValueTypeNames.Double, lambda p: float(p.levelled)),
    Schema.EVENED: (Sdf.ValueTypeNames.Double, lambda p: float(p.evened)),
    Schema.UV_TURN: (Sdf.ValueTypeNames.Double, lambda p: float(p.uv_turn)),
    Schema.RECTIFIED: (Sdf.ValueTypeNames.Double3, lambda p: Gf.Vec3d(*p.rectified)),
}


#: The discriminator's figures, recorded only when Q ran on the written tile.
Q_PROPERTIES = (Schema.Q_PASSED, Schema.Q_TAU, Schema.Q_BAND_MIN)


def _plugin_dir() -> Path:
    from seamless_usd_schemas import usd_plugin_dir

    return usd_plugin_dir()


def register_schemas() -> bool:
    """Register the schema plugin with USD; safe to call any number of times.

    Returns whether USD's schema registry knows ``SeamlessTileAPI`` afterwards. It does not when
    a stage was opened before the first call (the registry was already built); the provenance
    attributes are then still written, typed, with the schema name in ``apiSchemas``.

    >>> register_schemas()
    True
    """
    Plug.Registry().RegisterPlugins(str(_plugin_dir().resolve()))
    return schemas_known()


def schemas_known() -> bool:
    """Whether USD's schema registry has the seamless-usd API schemas."""
    registry = Usd.SchemaRegistry()
    return registry.FindAppliedAPIPrimDefinition(Schema.TILE_API) is not None


def has_applied(prim: Usd.Prim, schema: str) -> bool:
    """Whether ``schema`` is applied to ``prim``, also when this process's registry lacks it."""
    if not prim:
        return False
    return schema in prim.GetAppliedSchemas() or schema in prim.GetPrimTypeInfo().GetAppliedAPISchemas()


def write_provenance(prim: Usd.Prim, provenance: Provenance, source_asset: str | None = None) -> None:
    """Apply ``SeamlessTileAPI`` to ``prim`` and author its attributes at the edit target.

    ``source_asset`` overrides ``provenance.source_asset`` (a re-run keeps the original source).
    """
    prim.AddAppliedSchema(Schema.TILE_API)
    for name, (type_name, convert) in PROPERTIES.items():
        if (name in Q_PROPERTIES and provenance.q_passed is None) or (name == Schema.MODEL_HASH and not provenance.model_hash):
            # Q never ran / no network made the tile: record none of it
            attr = prim.GetAttribute(name)
            if attr:
                attr.Block()
            continue
        value = convert(provenance)
        if name == Schema.SOURCE_ASSET and source_asset is not None:
            value = Sdf.AssetPath(source_asset)
        prim.CreateAttribute(name, type_name, custom=False).Set(value)


def read_provenance(prim: Usd.Prim) -> Provenance | None:
    """The provenance recorded on ``prim``, or None when it has no ``SeamlessTileAPI``."""
    if not has_applied(prim, Schema.TILE_API):
        return None

    def get(name, default):
        attr = prim.GetAttribute(name)
        value = attr.Get() if attr else None
        return default if value is None else value

    source = get(Schema.SOURCE_ASSET, Sdf.AssetPath(""))
    return Provenance(
        source_asset=source.path if isinstance(source, Sdf.AssetPath) else str(source),
        crop_size=tuple(int(v) for v in get(Schema.CROP_SIZE, (0, 0))),
        uv_scale=tuple(float(v) for v in get(Schema.UV_SCALE, (1.0, 1.0))),
        q_passed=None if get(Schema.Q_PASSED, None) is None else bool(get(Schema.Q_PASSED, False)),
        q_tau=float(get(Schema.Q_TAU, 0.0)),
        q_band_min=tuple(float(v) for v in get(Schema.Q_BAND_MIN, (0.0, 0.0))),
        model_hash=str(get(Schema.MODEL_HASH, "")),
        tool_version=str(get(Schema.TOOL_VERSION, "")),
        passed=bool(get(Schema.PASSED, False)),
        verdict=str(get(Schema.VERDICT, "")),
        straightened=float(get(Schema.STRAIGHTENED, 0.0)),
        levelled=float(get(Schema.LEVELLED, 0.0)),
        evened=float(get(Schema.EVENED, 0.0)),
        uv_turn=float(get(Schema.UV_TURN, 0.0)),
        rectified=tuple(float(v) for v in get(Schema.RECTIFIED, (0.0, 0.0, 0.0))),
    )


def mark_uv_transform(prim: Usd.Prim) -> None:
    """Mark ``prim`` as the UV transform seamless-usd inserted (``SeamlessUVTransformAPI``)."""
    prim.AddAppliedSchema(Schema.UV_TRANSFORM_API)


def is_seamless_uv_transform(prim: Usd.Prim) -> bool:
    """Whether ``prim`` is a UV transform inserted by seamless-usd."""
    return has_applied(prim, Schema.UV_TRANSFORM_API)
