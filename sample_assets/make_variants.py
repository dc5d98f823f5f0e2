"""Sample assets whose looks live in variant sets, as published and studio assets keep them.

Called by ``make_scenes.py``; builds with ``usdkit.py``. Three assets in ``shading/``, placed side by side by ``set.usda``:

- ``teapot.usda``: root -> payload -> references to a geometry layer and a materials layer. Both
  have ``modelVariant`` {Utah, Fancy}; inside Fancy the materials layer has ``shadingVariant``
  {Plain, PorcelainFlowers}. The porcelain material (a UV atlas and a packed ARM atlas) is
  defined and bound to the Fancy body only inside that nested variant, which is not selected.
- ``king.usda``: root -> payload -> references to a geometry layer and a look layer; the look
  layer references ``king_mat.mtlx`` and has ``shadingVariant`` {White, Black}, each binding one
  atlas material of the document to the same render mesh.
- ``set.usda``: both assets and a floor whose tiling material lives in ``floorVariant=Tiled``
  (the selected ``Bare`` has no texture).

The atlas textures are baked here from the sample textures: each UV island of the mesh is
filled with a window of a photo, padded by a few texels, on a flat background (as a baker leaves
it).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio
from pxr import Sdf, Usd, UsdGeom, UsdShade

from usdkit import atlas_mesh, bind, new_layer, plane, preview_material, root_with_payload

HERE = Path(__file__).resolve().parent
TEXTURES = HERE / "textures"

# (lo, hi, grid, box_islands) of each atlas mesh, shared by its texture
UTAH = (0.05, 0.95, 3, 3)
FANCY = (0.03, 0.97, 5, 4)
KING = (0.02, 0.97, 4, 2)


def _read(name: str) -> np.ndarray:
    return oiio.ImageBuf(str(TEXTURES / name)).get_pixels(oiio.FLOAT)


def _write(name: str, pixels: np.ndarray, color: bool) -> None:
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, oiio.UINT8)
    spec.attribute("oiio:ColorSpace", "srgb_rec709_scene" if color else "lin_rec709_scene")
    out = oiio.ImageOutput.create(str(TEXTURES / name))
    out.open(str(TEXTURES / name), spec)
    out.write_image(np.clip(pixels, 0, 1).astype(np.float32))
    out.close()


def bake_atlas(layout: tuple, source: np.ndarray, background, size: int = 256, pad: int = 2,
               seed: int = 0) -> np.ndarray:
    """An atlas image for :func:`make_scenes.atlas_mesh` ``layout``: each island a window of
    ``source`` padded by ``pad`` texels (edge copies), the rest ``background``."""
    lo, hi, grid, _ = layout
    rng = np.random.default_rng(seed)
    out = np.empty((size, size, source.shape[2]), np.float32)
    out[:] = np.asarray(background, np.float32)[: source.shape[2]]
    cell = (hi - lo) / grid
    gap = cell * 0.08
    for k in range(grid * grid):
        i, j = divmod(k, grid)
        u0, v0, side = lo + j * cell + gap, lo + i * cell + gap, cell - 2 * gap
        x0, x1 = int(round(u0 * size)), int(round((u0 + side) * size))
        y0, y1 = int(round((1 - v0 - side) * size)), int(round((1 - v0) * size))
        h, w = y1 - y0 + 2 * pad, x1 - x0 + 2 * pad
        sy, sx = rng.integers(0, source.shape[0] - h), rng.integers(0, source.shape[1] - w)
        window = source[sy:sy + h, sx:sx + w]
        out[max(y0 - pad, 0):y1 + pad, max(x0 - pad, 0):x1 + pad] = window[
            max(pad - y0, 0):h - max(y1 + pad - size, 0), max(pad - x0, 0):w - max(x1 + pad - size, 0)]
    return out


def bake_textures() -> None:
    brick, wood, cloth, orm = (_read(n) for n in ("brick_albedo.png", "wood_color.png", "cloth.png", "brick_orm.png"))
    _write("teapot_utah_atlas.png", bake_atlas(UTAH, brick, (0, 0, 0), seed=1), color=True)
    _write("teapot_porcelain_atlas.png", bake_atlas(FANCY, 0.35 + 0.65 * cloth, (0, 0, 0), seed=2), color=True)
    _write("teapot_porcelain_arm.png", bake_atlas(FANCY, orm, (1.0, 0.5, 0.0), seed=2), color=False)
    _write("king_white_atlas.png", bake_atlas(KING, 0.4 + 0.6 * wood, (0.5, 0.5, 0.5), seed=3), color=True)
    _write("king_black_atlas.png", bake_atlas(KING, 0.3 * wood, (0.5, 0.5, 0.5), seed=3), color=True)


def _variant(stage: Usd.Stage, site: str, vset_name: str, names: list[str], default: str):
    """Yield each variant name of set ``vset_name`` on ``site`` (a prim path, possibly inside
    outer variants: ``/Teapot{modelVariant=Fancy}``) with the stage editing that variant."""
    layer = stage.GetRootLayer()
    spec = Sdf.CreatePrimInLayer(layer, Sdf.Path(site))
    if vset_name not in spec.variantSetNameList.prependedItems:
        spec.variantSetNameList.prependedItems.append(vset_name)
    for name in names:
        path = Sdf.Path(site).AppendVariantSelection(vset_name, name)
        Sdf.CreatePrimInLayer(layer, path)
        spec.variantSelections[vset_name] = name  # composed while it is edited
        with Usd.EditContext(stage, Usd.EditTarget.ForLocalDirectVariant(layer, path)):
            yield name
    spec.variantSelections[vset_name] = default


def _payload_with_references(path: Path, prim: str, references: list[str]) -> None:
    stage = new_layer(path, prim)
    xf = UsdGeom.Xform.Define(stage, f"/{prim}").GetPrim()
    for ref in references:
        xf.GetReferences().AddReference(ref)
    stage.Save()


def make_teapot(d: Path) -> None:
    root_with_payload(d / "teapot.usda", "Teapot", "./teapot_payload.usda",
                      "A teapot whose look lives in a nested modelVariant / shadingVariant (payload, "
                      "geometry and materials layers).")
    _payload_with_references(d / "teapot_payload.usda", "Teapot", ["./teapot_mtl.usda", "./teapot_geo.usda"])
    geo = new_layer(d / "teapot_geo.usda", "Teapot")
    UsdGeom.Xform.Define(geo, "/Teapot")
    for name in _variant(geo, "/Teapot", "modelVariant", ["Utah", "Fancy"], "Utah"):
        atlas_mesh(geo, "/Teapot/Geom/Body", *(UTAH if name == "Utah" else FANCY))
    geo.Save()
    mtl = new_layer(d / "teapot_mtl.usda", "Teapot")
    UsdGeom.Xform.Define(mtl, "/Teapot")
    for name in _variant(mtl, "/Teapot", "modelVariant", ["Utah", "Fancy"], "Utah"):
        if name == "Utah":
            preview_material(mtl, "/Teapot/Looks/M_utah", {
                "diffuseColor": ("../textures/teapot_utah_atlas.png", "rgb", "sRGB")})
            bind(mtl.OverridePrim("/Teapot/Geom/Body"), "/Teapot/Looks/M_utah")
            continue
        for shading in _variant(mtl, "/Teapot{modelVariant=Fancy}", "shadingVariant", ["Plain", "PorcelainFlowers"],
                                "Plain"):
            if shading == "Plain":
                mat = UsdShade.Material.Define(mtl, "/Teapot/Looks/M_glaze")
                surface = UsdShade.Shader.Define(mtl, "/Teapot/Looks/M_glaze/Surface")
                surface.CreateIdAttr("UsdPreviewSurface")
                surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set((0.8, 0.8, 0.75))
                mat.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
                bind(mtl.OverridePrim("/Teapot/Geom/Body"), "/Teapot/Looks/M_glaze")
                continue
            preview_material(mtl, "/Teapot/Looks/M_porcelain", {
                "diffuseColor": ("../textures/teapot_porcelain_atlas.png", "rgb", "sRGB")})
            _arm(mtl, "/Teapot/Looks/M_porcelain", "../textures/teapot_porcelain_arm.png")
            bind(mtl.OverridePrim("/Teapot/Geom/Body"), "/Teapot/Looks/M_porcelain")
    mtl.Save()


def _arm(stage: Usd.Stage, path: str, asset: str) -> None:
    """A packed ARM map: occlusion (r), roughness (g), metallic (b) of one UsdUVTexture."""
    tex = UsdShade.Shader.Define(stage, f"{path}/armTex")
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(asset)
    tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set("raw")
    reader = UsdShade.Shader(stage.GetPrimAtPath(f"{path}/StReader"))
    tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), "result")
    surface = UsdShade.Shader(stage.GetPrimAtPath(f"{path}/Surface"))
    for role, channel in (("occlusion", "r"), ("roughness", "g"), ("metallic", "b")):
        tex.CreateOutput(channel, Sdf.ValueTypeNames.Float)
        surface.CreateInput(role, Sdf.ValueTypeNames.Float).ConnectToSource(tex.ConnectableAPI(), channel)


MTLX_KING = """<?xml version="1.0"?>
<!-- The two looks of a chess king, referenced from USD through a payload (king_look.usda:
     references = @./king_mat.mtlx@</MaterialX/Materials>); shadingVariant binds one of them. -->
<materialx version="1.39" colorspace="lin_rec709">
{materials}</materialx>
"""

MTLX_KING_MATERIAL = """  <image name="{name}_color" type="color3">
    <input name="file" type="filename" value="../textures/king_{name}_atlas.png" colorspace="srgb_texture" />
  </image>
  <standard_surface name="SR_king_{name}" type="surfaceshader">
    <input name="base_color" type="color3" nodename="{name}_color" />
  </standard_surface>
  <surfacematerial name="M_king_{name}" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_king_{name}" />
  </surfacematerial>
"""


def make_king(d: Path) -> None:
    (d / "king_mat.mtlx").write_text(MTLX_KING.format(materials="".join(
        MTLX_KING_MATERIAL.format(name=n) for n in ("white", "black"))), encoding="utf-8")
    root_with_payload(d / "king.usda", "King", "./king_payload.usda",
                      "A chess king with two shading variants binding two MaterialX atlas looks.")
    _payload_with_references(d / "king_payload.usda", "King", ["./king_look.usda", "./king_geo.usda"])
    geo = new_layer(d / "king_geo.usda", "King")
    UsdGeom.Xform.Define(geo, "/King")
    atlas_mesh(geo, "/King/Geom/Render", *KING)
    geo.Save()
    look = new_layer(d / "king_look.usda", "King")
    UsdGeom.Xform.Define(look, "/King")
    UsdGeom.Scope.Define(look, "/King/Looks").GetPrim().GetReferences().AddReference(
        "./king_mat.mtlx", "/MaterialX/Materials")
    for name in _variant(look, "/King", "shadingVariant", ["White", "Black"], "White"):
        bind(look.OverridePrim("/King/Geom/Render"), f"/King/Looks/M_king_{name.lower()}")
    look.Save()


def make_set(d: Path) -> None:
    stage = new_layer(d / "set.usda", "World", "The teapot and the king side by side, and a floor whose "
                                               "tiling material lives in floorVariant=Tiled.")
    UsdGeom.Xform.Define(stage, "/World")
    for name, asset in (("Teapot", "./teapot.usda"), ("King", "./king.usda")):
        stage.DefinePrim(f"/World/{name}").GetReferences().AddReference(asset)
    floor = plane(stage, "/World/Floor", 6.0, 4.0).GetPrim()
    for name in _variant(stage, "/World/Floor", "floorVariant", ["Bare", "Tiled"], "Bare"):
        if name == "Tiled":
            preview_material(stage, "/World/Floor/Looks/M_tiles", {
                "diffuseColor": ("../textures/brick_albedo.png", "rgb", "sRGB"),
                "roughness": ("../textures/brick_roughness.png", "r", "raw")})
            bind(floor, "/World/Floor/Looks/M_tiles")
    stage.Save()


def make_variants() -> None:
    d = HERE / "shading"
    d.mkdir(exist_ok=True)
    bake_textures()
    make_teapot(d)
    make_king(d)
    make_set(d)
