"""A material whose textures cannot be read is not left out: ``process`` gives it a failed row and exit code 1,
and ``check`` names it, also when only one of its maps is missing (judged on the maps left it would pass a broken
material)."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import jsonschema
from pxr import Sdf, Usd

from seamless_usd_cli.main import main
from seamless_usd_schemas import json_schema

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


def _scene(root: Path) -> Path:
    """The brick scene with a copy of its material whose three textures are missing, and its roughness missing."""
    shutil.copytree(SAMPLES / "brick", root / "brick")
    shutil.copytree(SAMPLES / "textures", root / "textures")
    scene = root / "brick" / "scene.usda"
    layer = Sdf.Layer.FindOrOpen(str(scene))
    assert Sdf.CopySpec(layer, "/World/Looks/Brick", layer, "/World/Looks/Missing")
    stage = Usd.Stage.Open(layer)
    for prim in stage.GetPrimAtPath("/World/Looks/Missing").GetChildren():
        if prim.GetAttribute("inputs:file"):
            prim.GetAttribute("inputs:file").Set(Sdf.AssetPath(f"../textures/gone_{prim.GetName()}.png"))
        for attr in prim.GetAttributes():
            targets = attr.GetConnections()
            if targets:
                attr.SetConnections([Sdf.Path(str(t).replace("/Looks/Brick/", "/Looks/Missing/")) for t in targets])
    layer.Save()
    return scene


def test_process_fails_a_material_none_of_whose_textures_can_be_read(tmp_path, capsys):
    scene = _scene(tmp_path)
    code = main(["process", str(scene), "--dry-run", "--json"])
    payload = json.loads(capsys.readouterr().out)
    jsonschema.validate(payload, json_schema("report"))
    assert code == 1 == payload["exit_code"]
    rows = {s["material"]: s for s in payload["stacks"]}
    assert rows["</World/Looks/Brick>"]["status"] == "planned"
    missing = rows["</World/Looks/Missing>"]
    assert missing["status"] == "failed" and "@../textures/gone_Albedo.png@ (missing-file)" in missing["message"]
    assert payload["counts"]["failed"] == 1


def test_check_names_a_material_with_a_texture_that_cannot_be_read(tmp_path, capsys):
    scene = _scene(tmp_path)
    layer = Sdf.Layer.FindOrOpen(str(scene))
    layer.GetAttributeAtPath("/World/Looks/Brick/Roughness.inputs:file").default = Sdf.AssetPath("../textures/no.png")
    layer.Save()
    code = main(["check", str(scene), "--json"])
    payload = json.loads(capsys.readouterr().out)
    jsonschema.validate(payload, json_schema("check"))
    assert code == 1 == payload["exit_code"]
    items = {i["name"]: i for i in payload["items"]}
    assert set(items) == {"</World/Looks/Brick>", "</World/Looks/Missing>"}
    assert "@../textures/no.png@ (missing-file)" in items["</World/Looks/Brick>"]["error"]
    assert "gone_Normal.png" in items["</World/Looks/Missing>"]["error"]
    assert not any(i["passed"] for i in items.values())


def test_a_texture_that_cannot_be_read_beside_maps_left_alone_fails_the_run(tmp_path, capsys):
    """A material whose albedo file is not a picture and whose roughness is already tileable: the roughness was left
    alone, the albedo skipped, and the run exited 0, as if all were well (the README promises 1)."""
    import sys

    sys.path.insert(0, str(SAMPLES))
    from usdkit import bind, new_layer, plane, preview_material

    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    (tmp_path / "textures" / "broken.png").write_text("not a picture")
    stage = new_layer(tmp_path / "scene.usda", "World")
    stage.DefinePrim("/World", "Xform")
    bind(plane(stage, "/World/Floor", 2.0, 3.0).GetPrim(), "/World/Looks/M")
    preview_material(stage, "/World/Looks/M", {"diffuseColor": ("./textures/broken.png", "rgb", "sRGB"),
                                               "roughness": ("./textures/wood_tileable_roughness.jpg", "r", "raw")})
    stage.Save()
    code = main(["process", str(tmp_path / "scene.usda"), "--preset", "tiny", "--json", "--cache-dir",
                 str(tmp_path / "cache")])
    payload = json.loads(capsys.readouterr().out)
    assert [s["status"] for s in payload["stacks"]] == ["left-alone"], payload["stacks"]
    assert any(f["code"] == "unreadable-file" for f in payload["findings"])
    assert code == payload["exit_code"] == 1


def test_a_missing_texture_says_how_to_make_it_found(tmp_path):
    """A search-path name (@common/cloth.png@, not anchored by ./) is looked up beside the layer and on the asset
    resolver's search path: the skip says so and how to set it; an anchored one says to restore it or fix the path.
    A UDIM set says what to do to make one texture tileable."""
    from test_reliability_inputs import write_scene

    from seamless_usd.discover import scan_paths

    scene = write_scene(tmp_path / "scene.usda", {"Searched": "common/cloth.png", "Anchored": "./gone.png",
                                                  "Tiles": "./tex.<UDIM>.png"})
    said = {f.material: f.message for f in scan_paths([scene]).findings if f.code in ("missing-file", "udim")}
    searched = next(m for k, m in said.items() if "Searched" in k)
    assert "PXR_AR_DEFAULT_SEARCH_PATH" in searched
    anchored = next(m for k, m in said.items() if "Anchored" in k)
    assert "restore the file or fix the asset path" in anchored and "SEARCH_PATH" not in anchored
    assert "point the material at it" in next(m for k, m in said.items() if "Tiles" in k)
