"""Edits land where the material lives: inside payloads, inside the selected variant, in a .mtlx
look reached through a payload; the report and exit code agree with what is on disk."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import MaterialX as mx
import pytest
from runchecks import assert_all_written as _assert_all_written
from pxr import Sdf, Usd, UsdShade

from seamless_usd.authoring import MapResult, Provenance, StackResult, author_usd
from seamless_usd.discover import scan_paths
from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


@pytest.fixture(scope="module")
def cache(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("payload-cache")


@pytest.fixture()
def assets(tmp_path) -> Path:
    out = tmp_path / "assets"
    for name in ("prop", "chess", "tileable", "textures"):
        shutil.copytree(SAMPLES / name, out / name)
    return out


def _process(*args: str, cache: Path, capsys) -> tuple[int, dict]:
    code = main(["process", "--preset", "tiny", "--max-size", "128", "--cache-dir", str(cache), "--json", *args])
    return code, json.loads(capsys.readouterr().out)




def _file(stage: Usd.Stage, prim: str) -> str:
    return UsdShade.Shader(stage.GetPrimAtPath(prim)).GetInput("file").Get().path


def test_edits_inside_a_payload_land_in_each_variant(assets, cache, capsys):
    root = assets / "prop" / "prop.usda"
    before = {p: p.read_bytes() for p in (assets / "prop").iterdir()}
    code, payload = _process(str(root), cache=cache, capsys=capsys)
    _assert_all_written(code, payload)
    by_material = {s["material"]: s for s in payload["stacks"] if not s["variant"]}
    assert by_material["</Prop/Materials/M_floor>"]["status"] in ("passed", "not-passed")
    (cloth,) = [s for s in payload["stacks"] if s["variant"]]  # the floor under finish=cloth
    assert cloth["material"] == "</Prop/Materials/M_floor>" and cloth["variant"] == "finish=cloth"
    assert cloth["status"] in ("passed", "not-passed")
    assert by_material["</Prop/Materials/M_body>"]["status"] == "left-alone"
    assert by_material["</Prop/Materials/M_body>"]["intent"] == "uv-atlas"
    assert "36 islands" in by_material["</Prop/Materials/M_body>"]["intent_reason"]
    assert by_material["</Prop/Materials/M_label>"]["status"] == "left-alone"
    assert {p: p.read_bytes() for p in before} == before  # sources untouched
    layer = root.with_name("prop.seamless.usda")
    stage = Usd.Stage.Open(str(layer))
    floor = "/Prop/Materials/M_floor/diffuseColorTex"
    assert "tileable/" in _file(stage, floor) and Path(
        UsdShade.Shader(stage.GetPrimAtPath(floor)).GetInput("file").Get().resolvedPath).is_file()
    assert stage.GetPrimAtPath("/Prop/Materials/M_floor/SeamlessUV")
    # the atlas and the decal keep their textures and UVs
    assert _file(stage, "/Prop/Materials/M_body/diffuseColorTex") == "../textures/brick_albedo.png"
    assert not stage.GetPrimAtPath("/Prop/Materials/M_body/SeamlessUV")
    # the edits are inside each variant: the cloth variant gets its own tile, made from its texture
    wood_tile = _file(stage, floor)
    assert "brick" not in wood_tile and "cloth" not in wood_tile
    for variant in ("wood", "cloth"):
        spec = Sdf.Layer.FindOrOpen(str(layer)).GetPrimAtPath(f"/Prop{{finish={variant}}}Materials/M_floor/diffuseColorTex")
        assert spec is not None
    stage.GetPrimAtPath("/Prop").GetVariantSets().GetVariantSet("finish").SetVariantSelection("cloth")
    assert "tileable/cloth." in _file(stage, floor) and _file(stage, floor) != wood_tile
    assert stage.GetPrimAtPath("/Prop/Materials/M_floor/SeamlessUV")


def test_force_processes_the_atlas_too(assets, cache, capsys):
    root = assets / "prop" / "prop.usda"
    code, payload = _process(str(root), "--force-materials", "M_body", cache=cache, capsys=capsys)
    _assert_all_written(code, payload)
    body = next(s for s in payload["stacks"] if s["material"] == "</Prop/Materials/M_body>")
    assert body["status"] in ("passed", "not-passed") and "forced" in body["message"]
    stage = Usd.Stage.Open(str(root.with_name("prop.seamless.usda")))
    assert "tileable/" in _file(stage, "/Prop/Materials/M_body/diffuseColorTex")
    label = next(s for s in payload["stacks"] if s["material"] == "</Prop/Materials/M_label>")
    assert label["status"] == "left-alone"


def test_a_material_forced_but_left_out_by_materials_is_named(assets, cache, capsys):
    """--force-materials naming only a material --materials leaves out: not processed, and the run says so (the
    option was silently ignored); one --materials selects too is processed, without the warning."""
    root = str(assets / "prop" / "prop.usda")
    code, payload = _process(root, "--dry-run", "--materials", "M_floor", "--force-materials", "M_body", cache=cache,
                             capsys=capsys)
    [found] = [f for f in payload["findings"] if f["where"] == "--force-materials"]
    assert "M_body names only materials --materials leaves out" in found["message"]
    assert not [s for s in payload["stacks"] if s["material"] == "</Prop/Materials/M_body>"]
    code, payload = _process(root, "--dry-run", "--materials", "M_floor", "--materials", "M_body",
                             "--force-materials", "M_body", cache=cache, capsys=capsys)
    assert not [f for f in payload["findings"] if f["where"] == "--force-materials"]
    assert [s["status"] for s in payload["stacks"] if s["material"] == "</Prop/Materials/M_body>"] == ["planned"]


def test_mtlx_look_through_a_payload_is_processed_and_referenced(assets, cache, capsys):
    root = assets / "chess" / "piece.usda"
    code, payload = _process(str(root), cache=cache, capsys=capsys)
    _assert_all_written(code, payload)
    statuses = {s["material"]: s["status"] for s in payload["stacks"]}
    assert statuses["</Piece/Materials/M_piece>"] == "left-alone"
    assert statuses["</Piece/Materials/M_board>"] in ("passed", "not-passed")
    new_doc = assets / "chess" / "piece_mat.seamless.mtlx"
    assert str(new_doc) in payload["layers_written"]
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(new_doc))
    board = doc.getChild("board_color").getInput("file").getValueString()
    assert board.startswith("tileable/") and (assets / "chess" / board).is_file()
    assert doc.getChild("piece_color").getInput("file").getValueString() == "../textures/brick_albedo.png"
    layer = Sdf.Layer.FindOrOpen(str(root.with_name("piece.seamless.usda")))
    refs = layer.GetPrimAtPath("/Piece/Materials").referenceList
    assert [(r.assetPath, str(r.primPath)) for r in refs.prependedItems] == [
        ("./piece_mat.seamless.mtlx", "/MaterialX/Materials")]


def test_already_tileable_floor_only_gets_wrap_repeat(assets, cache, capsys):
    floor = assets / "tileable" / "floor.usda"
    code, payload = _process(str(floor), cache=cache, capsys=capsys)
    _assert_all_written(code, payload)
    [stack] = payload["stacks"]
    assert stack["status"] == "left-alone" and stack["intent"] == "already-tileable"
    assert payload["counts"]["trained"] == 0 and not (assets / "tileable" / "tileable").exists()
    stage = Usd.Stage.Open(str(floor.with_name("floor.seamless.usda")))
    tex = UsdShade.Shader(stage.GetPrimAtPath("/World/Looks/Wood/diffuseColorTex"))
    assert tex.GetInput("wrapS").Get() == "repeat" and tex.GetInput("wrapT").Get() == "repeat"
    assert tex.GetInput("file").Get().path == "../textures/wood_tileable.jpg"


def test_nothing_written_is_never_reported_as_written(assets, tmp_path):
    """A map whose node is not on the stage is listed as not written (and process fails its stack)."""
    scan = scan_paths([assets / "prop" / "prop.usda"])
    floor = next(s for s in scan.stacks if s.material == "</Prop/Materials/M_floor>")
    [m] = floor.maps
    tile = tmp_path / "tile.png"
    shutil.copy(assets / "textures" / "wood_color.png", tile)
    prov = Provenance("x", (1, 1), (1.0, 1.0), True, 0.0, (0.0, 0.0), "", "0")
    moved = type(m)(**{**m.__dict__, "node": "</Prop/Materials/M_floor/Gone>"})
    result = author_usd(assets / "prop" / "prop.usda", [StackResult(floor, [MapResult(moved, tile)], (1.0, 1.0), prov)])
    assert result.not_written == [("</Prop/Materials/M_floor/Gone>", "texture node not found on the stage; nothing written for it")]
    assert result.layers_written == []


def test_a_stack_whose_edits_cannot_be_written_fails_and_exits_1(assets, cache, capsys):
    # in place, the floor's opinion is in the materials layer; put that layer in a package (its
    # textures stay outside, by absolute path) so that it cannot be edited in place
    prop = assets / "prop"
    mtl = prop / "prop_mtl.usda"
    mtl.write_text(mtl.read_text().replace("@../textures/", f"@{(assets / 'textures').as_posix()}/"))
    writer = Sdf.ZipFileWriter.CreateNew(str(prop / "prop_mtl.usdz"))
    writer.AddFile(str(mtl), "prop_mtl.usda")
    writer.Save()
    payload_layer = Sdf.Layer.FindOrOpen(str(prop / "prop_payload.usda"))
    payload_layer.subLayerPaths[0] = "./prop_mtl.usdz"
    payload_layer.Save()
    code, payload = _process(str(prop / "prop.usda"), "--in-place", cache=cache, capsys=capsys)
    floor = next(s for s in payload["stacks"] if s["material"] == "</Prop/Materials/M_floor>")
    assert floor["status"] == "failed", floor
    assert "edits were not" in floor["message"] and "package" in floor["message"]
    assert code == 1 and payload["exit_code"] == 1
    # nothing claims otherwise: no layer holding the floor was written
    assert not any("prop_mtl" in layer for layer in payload["layers_written"])


def test_a_usdz_whose_maps_are_inside_it_is_left_alone_saying_why_and_is_never_edited_in_place(tmp_path, capsys):
    """A .usdz with its textures packed inside: its maps are not read from inside the package, so the stack is left
    alone with that reason (exit 0, nothing written), in a dry run as in a run; ``--in-place`` on a package, with
    textures inside or outside it, is refused before any work."""
    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    (tmp_path / "textures").mkdir()
    for name in ("brick_albedo.png", "brick_normal.png", "brick_roughness.png"):
        shutil.copy(samples / "textures" / name, tmp_path / "textures" / name)
    (tmp_path / "scene.usda").write_text((samples / "brick" / "scene.usda").read_text().replace("@../textures/",
                                                                                               "@./textures/"))
    from pxr import UsdUtils

    package = tmp_path / "brick.usdz"
    assert UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(tmp_path / "scene.usda")), str(package))
    for extra in ((), ("--dry-run",)):
        code = main(["process", str(package), "--preset", "tiny", "--cache-dir", str(tmp_path / "cache"), "--json",
                     *extra])
        [stack] = json.loads(capsys.readouterr().out)["stacks"]
        assert code == 0 and stack["status"] == "left-alone", stack
        assert "inside a .usdz package" in stack["message"] and "unpack" in stack["message"]
    assert not (tmp_path / "tileable").exists() and not (tmp_path / "brick.seamless.usda").exists()
    assert main(["process", str(package), "--in-place", "--cache-dir", str(tmp_path / "cache")]) == 2
    assert "not edited in place" in capsys.readouterr().err


def test_a_stage_with_one_payload_loaded_scans_and_plans_that_ones_materials(tmp_path):
    """An export hook's stage, one prop's payload loaded and the other's not, each prop with a shading variant set:
    opened whole to explore variants, the unloaded prop's set read as a choice the stage does not make, so the
    loaded prop's floor was found under a selection other than the stage's own, planned nothing (variant not
    editable) and the unloaded prop's floor was listed as if scanned."""
    import sys

    import seamless_usd
    from pxr import UsdGeom

    sys.path.insert(0, str(SAMPLES))
    from usdkit import bind, plane, preview_material

    shutil.copy(SAMPLES / "textures" / "cloth.png", tmp_path / "cloth.png")
    prop = Usd.Stage.CreateNew(str(tmp_path / "prop.usda"))
    root = UsdGeom.Xform.Define(prop, "/Prop").GetPrim()
    prop.SetDefaultPrim(root)
    preview_material(prop, "/Prop/Looks/Tiles", {"diffuseColor": ("./cloth.png", "rgb", "sRGB")})
    bind(plane(prop, "/Prop/Floor", 10, 4).GetPrim(), "/Prop/Looks/Tiles")
    shading = root.GetVariantSets().AddVariantSet("shadingVariant")
    for name in ("clean", "worn"):
        shading.AddVariant(name)
    shading.SetVariantSelection("clean")
    prop.GetRootLayer().Save()
    scene = Usd.Stage.CreateNew(str(tmp_path / "scene.usda"))
    UsdGeom.Xform.Define(scene, "/World")
    for name in ("A", "B"):
        scene.DefinePrim(f"/World/{name}").GetPayloads().AddPayload("./prop.usda")
    scene.GetRootLayer().Save()

    stage = Usd.Stage.Open(str(tmp_path / "scene.usda"), Usd.Stage.LoadNone)
    stage.Load("/World/A")
    scanned = seamless_usd.scan(stage)
    assert [(s.material, s.selection) for s in scanned.stacks] == [("</World/A/Looks/Tiles>", ())]
    assert [f.where for f in scanned.findings if f.code == "unloaded-payload"] == ["</World/B>"]
    report = seamless_usd.process_stage(stage, seamless_usd.Options(
        preset="tiny", mode=seamless_usd.WriteMode.DRY_RUN, cache_dir=tmp_path / "cache", output_dir=tmp_path / "out"))
    assert [(s.material, s.status.value) for s in report.stacks] == [("</World/A/Looks/Tiles>", "planned")]
    assert report.exit_code == 0 and list(stage.GetLoadSet()) == ["/World/A"]  # the caller's stage as it was
