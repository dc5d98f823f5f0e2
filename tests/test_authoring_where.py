"""Where a material's edits go when its texture node is reached another way: brought in by a payload (or a
reference) authored inside a variant, the edits go inside that variant, so the other selections keep their own
look; a node two materials share keeps the first one's tile, and the other is told so; in place, every edit of a
texture goes into the layer holding its file value."""
from __future__ import annotations

import shutil
import sys
from pathlib import Path

import pytest
from pxr import Sdf, Usd, UsdShade

from standins import stand_ins

from seamless_usd.authoring import author_usd

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"


def _material(stage: Usd.Stage, path: str, texture: str, transform: bool) -> None:
    """usdkit's UsdPreviewSurface material reading ``texture`` (its node ``diffuseColorTex``) through st, and with
    ``transform`` a UsdTransform2d between them."""
    sys.path.insert(0, str(TEXTURES.parent))
    from usdkit import preview_material

    preview_material(stage, path, {"diffuseColor": (texture, "rgb", "sRGB")}, wrap=None)
    if transform:
        xf = UsdShade.Shader.Define(stage, f"{path}/Xf")
        xf.CreateIdAttr("UsdTransform2d")
        xf.CreateInput("in", Sdf.ValueTypeNames.Float2).ConnectToSource(
            UsdShade.Shader.Get(stage, f"{path}/StReader").ConnectableAPI(), "result")
        xf.CreateInput("scale", Sdf.ValueTypeNames.Float2).Set((2.0, 2.0))
        UsdShade.Shader.Get(stage, f"{path}/diffuseColorTex").GetInput("st").ConnectToSource(
            xf.CreateOutput("result", Sdf.ValueTypeNames.Float2))


def _asset(root: Path) -> Path:
    """asset.usda: variant set ``look``; ``brick`` payloads the material from mtl/payload.usda, ``plain`` defines
    its own material at the same path."""
    (root / "tex").mkdir()
    for name in ("brick_albedo.png", "wood_color.png"):
        shutil.copyfile(TEXTURES / name, root / "tex" / name)
    (root / "asset" / "mtl").mkdir(parents=True)
    payload = Usd.Stage.CreateNew(str(root / "asset" / "mtl" / "payload.usda"))
    payload.DefinePrim("/Mtl", "Scope")
    _material(payload, "/Mtl/Brick", "../../tex/brick_albedo.png", transform=True)
    payload.GetRootLayer().Save()
    stage = Usd.Stage.CreateNew(str(root / "asset" / "asset.usda"))
    asset = stage.DefinePrim("/Asset", "Xform")
    stage.SetDefaultPrim(asset)
    looks = asset.GetVariantSets().AddVariantSet("look")
    for name in ("brick", "plain"):
        looks.AddVariant(name)
        looks.SetVariantSelection(name)
        with looks.GetVariantEditContext():
            scope = stage.DefinePrim("/Asset/Looks", "Scope")
            if name == "brick":
                scope.GetPayloads().AddPayload("./mtl/payload.usda", "/Mtl")
            else:
                _material(stage, "/Asset/Looks/Brick", "../tex/wood_color.png", transform=False)
    looks.SetVariantSelection("brick")
    stage.GetRootLayer().Save()
    return root / "asset" / "asset.usda"


def _composed(layer: Path, selection: str) -> tuple[str, bool, list]:
    stage = Usd.Stage.Open(str(layer))
    stage.GetPrimAtPath("/Asset").GetVariantSets().GetVariantSet("look").SetVariantSelection(selection)
    color = stage.GetPrimAtPath("/Asset/Looks/Brick/diffuseColorTex")
    st = color.GetAttribute("inputs:st").GetConnections()
    transform = stage.GetPrimAtPath(st[0].GetPrimPath()) if st else None
    upstream = transform.GetAttribute("inputs:in").GetConnections() if transform else []
    valid = all(stage.GetPrimAtPath(p.GetPrimPath()).IsValid() for p in upstream)
    return Path(color.GetAttribute("inputs:file").Get().path).name, valid, [str(p) for p in upstream]


@pytest.mark.parametrize("referenced", [False, True])
def test_a_payload_inside_a_variant_is_edited_inside_that_variant(tmp_path, referenced):
    path = _asset(tmp_path)
    if referenced:  # a shot stage referencing the asset: the same, one arc further
        shot = Usd.Stage.CreateNew(str(tmp_path / "shot.usda"))
        shot.DefinePrim("/Asset").GetReferences().AddReference("./asset/asset.usda")
        shot.GetRootLayer().Save()
        path = tmp_path / "shot.usda"
    results = stand_ins(path)
    assert len(results) == 2  # one stack per selection
    written = author_usd(path, results).output
    brick, brick_linked, _ = _composed(written, "brick")
    plain, plain_linked, upstream = _composed(written, "plain")
    assert brick == "brick_albedo_tile.png" and plain == "wood_color_tile.png"
    assert brick_linked and plain_linked and upstream == ["/Asset/Looks/Brick/StReader.outputs:result"]
    layer = Sdf.Layer.FindOrOpen(str(written))
    assert not layer.GetPrimAtPath("/Asset/Looks"), "an edit outside the variant changes every selection"


def test_a_texture_node_two_materials_share_keeps_the_first_ones_tile_and_names_the_other(tmp_path):
    """M2's diffuse colour reads M1's texture node: each material's stack gets its tile, but the node can show one;
    the second material is told its tile is not used (process then fails its row instead of passing it)."""
    from dataclasses import replace

    from seamless_usd.authoring import StackResult

    (tmp_path / "tex").mkdir()
    shutil.copyfile(TEXTURES / "brick_albedo.png", tmp_path / "tex" / "brick_albedo.png")
    stage = Usd.Stage.CreateNew(str(tmp_path / "scene.usda"))
    _material(stage, "/Looks/M1", "./tex/brick_albedo.png", transform=False)
    m2 = UsdShade.Material.Define(stage, "/Looks/M2")
    surface = UsdShade.Shader.Define(stage, "/Looks/M2/Surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    m2.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(
        UsdShade.Shader.Get(stage, "/Looks/M1/diffuseColorTex").ConnectableAPI(), "rgb")
    stage.GetRootLayer().Save()
    first, second = stand_ins(tmp_path / "scene.usda")
    assert (first.stack.material, second.stack.material) == ("</Looks/M1>", "</Looks/M2>")
    second = StackResult(second.stack, second.maps, (3.0, 3.0), replace(second.provenance, uv_scale=(3.0, 3.0)))
    result = author_usd(tmp_path / "scene.usda", [first, second])
    assert "</Looks/M1/diffuseColorTex>" not in result.unwritten_nodes("</Looks/M1>")
    assert "shared with </Looks/M1>" in result.unwritten_nodes("</Looks/M2>")["</Looks/M1/diffuseColorTex>"]


def test_a_run_over_other_materials_keeps_the_earlier_runs_edits_unless_the_stage_changed(tmp_path):
    """Two runs with different material selections write one new layer holding both runs' edits; when the stage has
    changed since, the layer is made again over it, and the edits it does not keep are named."""
    from seamless_usd.authoring import StackResult

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("brick", "orm", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    (tmp_path / "combo").mkdir()
    scene = tmp_path / "combo" / "combo.usda"
    scene.write_text('#usda 1.0\n(\n    subLayers = [@../brick/scene.usda@, @../orm/scene.usda@]\n)\n')
    results = {r.stack.material: r for r in stand_ins(scene)}
    brick, orm = results["</World/Looks/Brick>"], results["</World/Looks/BrickOrm>"]
    assert isinstance(brick, StackResult)

    def files(layer: Path) -> dict[str, str]:
        stage = Usd.Stage.Open(str(layer))
        return {str(p.GetPath()): Path(p.GetAttribute("inputs:file").Get().path).name for p in stage.Traverse()
                if p.GetAttribute("inputs:file") and "_tile" in str(p.GetAttribute("inputs:file").Get().path)}

    first = author_usd(scene, [orm]).output
    author_usd(scene, [brick])
    both = files(first)
    assert any("/BrickOrm/" in p for p in both) and any("/Brick/" in p for p in both)
    again = author_usd(scene, [brick])  # nothing new: the layer is left as it is
    assert again.layers_written == [] and files(first) == both
    scene.write_text(scene.read_text() + "# edited\n")
    changed = author_usd(scene, [brick])
    assert changed.layers_written == [first]
    kept = files(first)
    assert not any("/BrickOrm/" in p for p in kept) and any("/Brick/" in p for p in kept)
    [warning] = [f for f in changed.findings if f.code == "edits-replaced"]
    assert "</World/Looks/BrickOrm/" in warning.message


def _library_and_shot(root: Path, override: bool) -> Path:
    """lib/mat.usda defines /Mat (a texture reading st); shots/shot.usda references it as /World/M, and with
    ``override`` sets the texture's file itself."""
    (root / "lib").mkdir()
    (root / "shots").mkdir()
    lib = Usd.Stage.CreateNew(str(root / "lib" / "mat.usda"))
    _material(lib, "/Mat", str(TEXTURES / "brick_roughness.png"), transform=False)
    lib.SetDefaultPrim(lib.GetPrimAtPath("/Mat"))
    lib.GetRootLayer().Save()
    shot = Usd.Stage.CreateNew(str(root / "shots" / "shot.usda"))
    shot.DefinePrim("/World/M").GetReferences().AddReference("../lib/mat.usda")
    if override:
        shot.OverridePrim("/World/M/diffuseColorTex").CreateAttribute("inputs:file", Sdf.ValueTypeNames.Asset).Set(
            str(TEXTURES / "brick_albedo.png"))
    shot.GetRootLayer().Save()
    return root / "shots" / "shot.usda"


@pytest.mark.parametrize("override", [True, False])
def test_in_place_every_edit_of_a_texture_goes_where_its_file_is(tmp_path, override):
    """In place, a texture's file, wrap, UV link, UV transform and provenance go into one layer, the one holding its
    file value: the shot's override (the library it references stays as it was; its UV link had gone there, scaling
    every stage's untiled texture), or the library itself, which is then said to be shared."""
    from seamless_usd.authoring import WriteMode

    shot = _library_and_shot(tmp_path, override)
    library = (tmp_path / "lib" / "mat.usda").read_bytes()
    planned = author_usd(shot, stand_ins(shot), mode=WriteMode.DRY_RUN, plan_mode=WriteMode.IN_PLACE)
    result = author_usd(shot, stand_ins(shot), mode=WriteMode.IN_PLACE)
    # the dry run warns as the run does
    assert [f.code for f in planned.findings if f.code == "shared-layer-edited"] == [
        f.code for f in result.findings if f.code == "shared-layer-edited"]
    stage = Usd.Stage.Open(str(shot))
    tex = stage.GetPrimAtPath("/World/M/diffuseColorTex")
    assert "_tile" in tex.GetAttribute("inputs:file").Get().path
    assert tex.GetAttribute("inputs:st").GetConnections() == [Sdf.Path("/World/M/SeamlessUV.outputs:result")]
    shared = [f for f in result.findings if f.code == "shared-layer-edited"]
    if override:
        assert result.layers_written == [shot] and (tmp_path / "lib" / "mat.usda").read_bytes() == library
        assert not shared
    else:
        assert result.layers_written == [tmp_path / "lib" / "mat.usda"]
        assert [f.where for f in shared] == [f"@{tmp_path / 'lib' / 'mat.usda'}@"]
