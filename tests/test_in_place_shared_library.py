"""In place, over a library whose shots reference one material library layer: the library's textures are edited
once, never under a shot or prop whose use of them is not made tileable.

Each stage was edited on its own: a prop that unwraps the material as a UV atlas (left alone, its report said) saw
the library's texture turned into a tile all the same; and two shots tiling the same material each set the library
to the tiles in their own folder, the last winning, so every run again wrote the library twice."""
from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

from pxr import Usd

from seamless_usd_cli.main import main

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "sample_assets"))
WOOD = {"diffuseColor": ("../textures/wood_color.png", "rgb", "sRGB"),
        "roughness": ("../textures/wood_roughness.png", "r", "raw")}


def _material_library(root: Path) -> None:
    """The sample textures and ``matlib/materials.usda``: the wood material under ``/Looks``."""
    from usdkit import new_layer, preview_material

    shutil.copytree(ROOT / "sample_assets" / "textures", root / "textures")
    (root / "matlib").mkdir()
    stage = new_layer(root / "matlib" / "materials.usda", "Looks")
    stage.DefinePrim("/Looks", "Scope")
    preview_material(stage, "/Looks/Wood", WOOD)
    stage.Save()


def _library(root: Path, prop: bool) -> Path:
    """``matlib/materials.usda`` (the wood material), referenced by ``shotA`` and ``shotB`` (ground planes tiling it
    3 and 5 times) and, with ``prop``, by ``prop`` (a mesh unwrapped as a UV atlas)."""
    from usdkit import atlas_mesh, bind, new_layer, plane

    _material_library(root)
    for name, periods in (("shotA", 3.0), ("shotB", 5.0), *((("prop", 0.0),) if prop else ())):
        (root / name).mkdir()
        stage = new_layer(root / name / f"{name}.usda", "World")
        stage.DefinePrim("/World", "Xform")
        stage.DefinePrim("/World/Looks").GetReferences().AddReference("../matlib/materials.usda", "/Looks")
        mesh = (atlas_mesh(stage, "/World/Body", 0.12, 0.88, 6, 4) if name == "prop"
                else plane(stage, "/World/Floor", 2.0, periods))
        bind(mesh.GetPrim(), "/World/Looks/Wood")
        stage.Save()
    return root


def _run(root: Path, capsys) -> tuple[int, dict]:
    code = main(["process", str(root), "--in-place", "--preset", "tiny", "--seeds", "1", "--max-size", "128",
                 "--cache-dir", str(root.parent / "cache"), "--json"])
    return code, json.loads(capsys.readouterr().out)


def test_a_library_texture_a_prop_leaves_alone_is_not_edited_under_it(tmp_path, capsys):
    root = _library(tmp_path / "lib", prop=True)
    before = (root / "matlib" / "materials.usda").read_text()
    code, payload = _run(root, capsys)
    rows = {Path(s["source"]).name: s for s in payload["stacks"]}
    assert rows["prop.usda"]["status"] == "left-alone", rows["prop.usda"]
    for shot in ("shotA.usda", "shotB.usda"):
        assert rows[shot]["status"] == "failed" and "prop.usda" in rows[shot]["message"], rows[shot]
        assert "--in-place" in rows[shot]["message"] and not any(m.get("output") for m in rows[shot]["maps"])
    assert code == 1 and not payload["layers_written"]
    assert (root / "matlib" / "materials.usda").read_text() == before
    assert not (root / "shotA" / "tileable").exists()  # failed before its tiles were made


def test_two_shots_tiling_one_library_material_edit_it_once(tmp_path, capsys):
    root = _library(tmp_path / "lib", prop=False)
    code, payload = _run(root, capsys)
    assert [Path(p).name for p in payload["layers_written"]] == ["materials.usda"]  # once
    statuses = {Path(s["source"]).name: s["status"] for s in payload["stacks"]}
    assert statuses["shotB.usda"] in ("reused", "not-passed") and statuses["shotA.usda"] in ("passed", "not-passed")
    edited = (root / "matlib" / "materials.usda").read_text()
    assert "../shotA/tileable/" in edited and "../shotB/" not in edited
    for shot in ("shotA", "shotB"):  # each shot shows the tile, at its own texel density
        stage = Usd.Stage.Open(str(root / shot / f"{shot}.usda"))
        albedo = stage.GetPrimAtPath("/World/Looks/Wood/diffuseColorTex").GetAttribute("inputs:file").Get()
        assert "shotA/tileable" in albedo.resolvedPath.replace("\\", "/")
    again, repeat = _run(root, capsys)  # a run again writes nothing
    assert again == code and not repeat["layers_written"] and not repeat["backups"]
    assert (root / "matlib" / "materials.usda").read_text() == edited


def test_two_materials_of_one_stage_referencing_one_asset_are_not_edited_under_the_one_left_alone(tmp_path, capsys):
    """One stage references the library's looks twice (``/World/A/Looks`` and ``/World/B/Looks``): A's wood tiles a
    floor, B's is unwrapped as an atlas on a prop (left alone). In place, the library's texture was edited for A,
    and B's atlas showed the tile at A's UV scale while the run exited 0. A now fails, naming B."""
    from usdkit import atlas_mesh, bind, new_layer, plane

    root = tmp_path / "lib"
    _material_library(root)
    (root / "shot").mkdir()
    stage = new_layer(root / "shot" / "shot.usda", "World")
    stage.DefinePrim("/World", "Xform")
    for name, mesh in (("A", plane(stage, "/World/Floor", 2.0, 3.0)), ("B", atlas_mesh(stage, "/World/Prop", 0.12,
                                                                                        0.88, 6, 4))):
        stage.DefinePrim(f"/World/{name}/Looks").GetReferences().AddReference("../matlib/materials.usda", "/Looks")
        bind(mesh.GetPrim(), f"/World/{name}/Looks/Wood")
    stage.Save()
    before = (root / "matlib" / "materials.usda").read_text()
    code, payload = _run(root, capsys)
    rows = {s["material"]: s for s in payload["stacks"]}
    assert rows["</World/B/Looks/Wood>"]["status"] == "left-alone"
    failed = rows["</World/A/Looks/Wood>"]
    assert failed["status"] == "failed" and "</World/B/Looks/Wood>" in failed["message"], failed
    assert code == 1 and (root / "matlib" / "materials.usda").read_text() == before
