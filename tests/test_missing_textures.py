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
