#!/usr/bin/env python3
"""Regenerate the structured sample assets: payloads, variants, sublayers, a .mtlx look in a payload.

They are built the way published USD assets are (a root layer whose prim payloads the asset,
the payload sublayering a geometry layer and a materials or look layer) and exercise tiling
intent: unwrapped UV-atlas meshes next to tiling materials whose UVs span several periods, a
clamped decal, and an already tileable texture. Run from the repository root::

    python3 sample_assets/make_scenes.py [/path/to/shared/textures]

The already-tileable texture ``textures/wood_tileable.jpg`` (and its roughness) is the
MaterialX example ``wood_color.jpg`` reduced 4x with exact 4x4 means (a periodic image stays
periodic); it is only rebuilt when the source folder is given.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from pxr import Sdf, UsdGeom

from make_variants import make_variants
from usdkit import atlas_mesh, bind, new_layer, payload_layer, plane, preview_material, root_with_payload

HERE = Path(__file__).resolve().parent


# -- assets -----------------------------------------------------------------------------------

def make_prop() -> None:
    """prop/: root -> payload -> geometry + materials layers; an atlas body, a decal, a tiling
    floor whose texture is chosen by a variant set "finish" in the materials layer."""
    d = HERE / "prop"
    d.mkdir(exist_ok=True)
    root_with_payload(d / "prop.usda", "Prop", "./prop_payload.usda",
                      "A prop built like published assets: payload, then geometry and materials layers.")
    payload_layer(d / "prop_payload.usda", "Prop", ["./prop_mtl.usda", "./prop_geo.usda"])
    geo = new_layer(d / "prop_geo.usda", "Prop")
    UsdGeom.Xform.Define(geo, "/Prop")
    body = atlas_mesh(geo, "/Prop/Geom/Body", 0.11, 0.89, 6, 6)  # 36 islands
    bind(body.GetPrim(), "/Prop/Materials/M_body")
    bind(plane(geo, "/Prop/Geom/Label", 0.3, 1.0, 1).GetPrim(), "/Prop/Materials/M_label")
    bind(plane(geo, "/Prop/Geom/Floor", 4.0, 4.0).GetPrim(), "/Prop/Materials/M_floor")
    geo.Save()
    mtl = new_layer(d / "prop_mtl.usda", "Prop")
    UsdGeom.Xform.Define(mtl, "/Prop")
    UsdGeom.Scope.Define(mtl, "/Prop/Materials")
    preview_material(mtl, "/Prop/Materials/M_body", {
        "diffuseColor": ("../textures/brick_albedo.png", "rgb", "sRGB"),
        "roughness": ("../textures/brick_roughness.png", "r", "raw")})
    preview_material(mtl, "/Prop/Materials/M_label", {"diffuseColor": ("../textures/cloth.png", "rgb", "sRGB")},
                     wrap="clamp")
    # The floor's texture comes from a variant: the file is authored only inside the variants.
    preview_material(mtl, "/Prop/Materials/M_floor", {"diffuseColor": ("", "rgb", "sRGB")})
    floor_tex = mtl.GetPrimAtPath("/Prop/Materials/M_floor/diffuseColorTex")
    floor_tex.GetAttribute("inputs:file").Clear()
    prop = mtl.GetPrimAtPath("/Prop")
    vset = prop.GetVariantSets().AddVariantSet("finish")
    for name, asset in (("wood", "../textures/wood_color.png"), ("cloth", "../textures/cloth.png")):
        vset.AddVariant(name)
        vset.SetVariantSelection(name)
        with vset.GetVariantEditContext():
            floor_tex.GetAttribute("inputs:file").Set(Sdf.AssetPath(asset))
    vset.SetVariantSelection("wood")
    mtl.Save()


MTLX_PIECE = """<?xml version="1.0"?>
<!-- Looks of a chess piece and its board, referenced from USD through a payload
     (piece_look.usda: references = @./piece_mat.mtlx@</MaterialX/Materials>). -->
<materialx version="1.39" colorspace="lin_rec709">
  <image name="piece_color" type="color3">
    <input name="file" type="filename" value="../textures/brick_albedo.png" colorspace="srgb_texture" />
  </image>
  <image name="piece_roughness" type="float">
    <input name="file" type="filename" value="../textures/brick_roughness.png" />
  </image>
  <standard_surface name="SR_piece" type="surfaceshader">
    <input name="base_color" type="color3" nodename="piece_color" />
    <input name="specular_roughness" type="float" nodename="piece_roughness" />
  </standard_surface>
  <surfacematerial name="M_piece" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_piece" />
  </surfacematerial>
  <image name="board_color" type="color3">
    <input name="file" type="filename" value="../textures/wood_color.png" colorspace="srgb_texture" />
  </image>
  <image name="board_roughness" type="float">
    <input name="file" type="filename" value="../textures/wood_roughness.png" />
  </image>
  <standard_surface name="SR_board" type="surfaceshader">
    <input name="base_color" type="color3" nodename="board_color" />
    <input name="specular_roughness" type="float" nodename="board_roughness" />
  </standard_surface>
  <surfacematerial name="M_board" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_board" />
  </surfacematerial>
</materialx>
"""


def make_chess() -> None:
    """chess/: root -> payload -> geometry + look layers; the look layer references the .mtlx."""
    d = HERE / "chess"
    d.mkdir(exist_ok=True)
    (d / "piece_mat.mtlx").write_text(MTLX_PIECE, encoding="utf-8")
    root_with_payload(d / "piece.usda", "Piece", "./piece_payload.usda",
                      "A chess piece with MaterialX looks: root -> payload -> look layer -> .mtlx.")
    payload_layer(d / "piece_payload.usda", "Piece", ["./piece_look.usda", "./piece_geo.usda"])
    look = new_layer(d / "piece_look.usda", "Piece")
    UsdGeom.Xform.Define(look, "/Piece")
    scope = UsdGeom.Scope.Define(look, "/Piece/Materials").GetPrim()
    scope.GetReferences().AddReference("./piece_mat.mtlx", "/MaterialX/Materials")
    look.Save()
    geo = new_layer(d / "piece_geo.usda", "Piece")
    UsdGeom.Xform.Define(geo, "/Piece")
    bind(atlas_mesh(geo, "/Piece/Geom/Piece", 0.005, 0.994, 4, 2).GetPrim(), "/Piece/Materials/M_piece")
    bind(plane(geo, "/Piece/Geom/Board", 2.0, 3.0).GetPrim(), "/Piece/Materials/M_board")
    geo.Save()


MTLX_WOOD = """<?xml version="1.0"?>
<!-- A MaterialX example pattern: tiledimage with uvtiling 4 on a texture that already tiles
     (textures/wood_tileable*.jpg, reduced from the MaterialX wood_color.jpg / wood_roughness.jpg). -->
<materialx version="1.39" colorspace="lin_rec709">
  <nodegraph name="NG_wood">
    <tiledimage name="wood_color" type="color3">
      <input name="file" type="filename" value="../textures/wood_tileable.jpg" colorspace="srgb_texture" />
      <input name="uvtiling" type="vector2" value="4.0, 4.0" />
    </tiledimage>
    <tiledimage name="wood_roughness" type="float">
      <input name="file" type="filename" value="../textures/wood_tileable_roughness.jpg" />
      <input name="uvtiling" type="vector2" value="4.0, 4.0" />
    </tiledimage>
    <output name="base_color_out" type="color3" nodename="wood_color" />
    <output name="roughness_out" type="float" nodename="wood_roughness" />
  </nodegraph>
  <standard_surface name="SR_wood" type="surfaceshader">
    <input name="base_color" type="color3" nodegraph="NG_wood" output="base_color_out" />
    <input name="specular_roughness" type="float" nodegraph="NG_wood" output="roughness_out" />
  </standard_surface>
  <surfacematerial name="M_wood_tiled" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_wood" />
  </surfacematerial>
</materialx>
"""


def make_tileable(textures: Path | None) -> None:
    """tileable/: the already tileable wood as a MaterialX document and as a USD floor (UVs 0-4,
    wrap left to useMetadata: processing only sets repeat)."""
    d = HERE / "tileable"
    d.mkdir(exist_ok=True)
    if textures is not None:
        import OpenImageIO as oiio

        for src, name in (("wood_color.jpg", "wood_tileable.jpg"), ("wood_roughness.jpg", "wood_tileable_roughness.jpg")):
            px = oiio.ImageBuf(str(textures / src)).get_pixels(oiio.FLOAT)
            h, w, c = px.shape
            small = px.reshape(h // 4, 4, w // 4, 4, c).mean(axis=(1, 3))
            spec = oiio.ImageSpec(w // 4, h // 4, c, oiio.UINT8)
            spec.attribute("Compression", "jpeg:95")
            out = oiio.ImageOutput.create(str(HERE / "textures" / name))
            out.open(str(HERE / "textures" / name), spec)
            out.write_image(np.clip(small, 0, 1).astype(np.float32))
            out.close()
    (d / "wood_tiled.mtlx").write_text(MTLX_WOOD, encoding="utf-8")
    stage = new_layer(d / "floor.usda", "World", "A floor whose wood texture already tiles.")
    UsdGeom.Xform.Define(stage, "/World")
    bind(plane(stage, "/World/Floor", 8.0, 4.0).GetPrim(), "/World/Looks/Wood")
    preview_material(stage, "/World/Looks/Wood", {
        "diffuseColor": ("../textures/wood_tileable.jpg", "rgb", "sRGB"),
        "roughness": ("../textures/wood_tileable_roughness.jpg", "r", "raw")}, wrap=None)
    stage.Save()


if __name__ == "__main__":
    make_prop()
    make_chess()
    make_tileable(Path(sys.argv[1]) if len(sys.argv) > 1 else None)
    make_variants()
