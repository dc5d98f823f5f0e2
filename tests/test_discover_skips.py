"""Items discovery leaves out, each with a reason and a stable code, and never a crash."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
from pxr import Sdf, Usd, UsdShade, UsdUtils

from seamless_usd.discover import scan_paths, scan_stage

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"


def write_image(path: Path, size: int = 128, channels: int = 3, dtype=oiio.UINT8) -> Path:
    spec = oiio.ImageSpec(size, size, channels, dtype)
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), spec)
    out.write_image(np.full((size, size, channels), 0.5, np.float32))
    out.close()
    return path


def texture_scene(path: Path, file: str | None, *, st: bool = True) -> Path:
    """A quad material whose diffuseColor reads one UsdUVTexture with ``file``."""
    stage = Usd.Stage.CreateNew(str(path))
    mat = UsdShade.Material.Define(stage, "/Looks/M")
    surf = UsdShade.Shader.Define(stage, "/Looks/M/Surface")
    surf.CreateIdAttr("UsdPreviewSurface")
    mat.CreateSurfaceOutput().ConnectToSource(surf.ConnectableAPI(), "surface")
    tex = UsdShade.Shader.Define(stage, "/Looks/M/Tex")
    tex.CreateIdAttr("UsdUVTexture")
    if file is not None:
        tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(file)
    surf.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(
        tex.ConnectableAPI(), "rgb")
    if st:
        reader = UsdShade.Shader.Define(stage, "/Looks/M/St")
        reader.CreateIdAttr("UsdPrimvarReader_float2")
        reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
        tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), "result")
    stage.Save()
    return path


def _only_finding(result):
    assert not result.stacks
    (finding,) = result.findings
    assert finding.severity.value == "skipped"
    return finding


def test_missing_texture_is_skipped_naming_prim_and_asset(tmp_path):
    result = scan_paths([texture_scene(tmp_path / "s.usda", "tex/absent.png")])
    f = _only_finding(result)
    assert f.code == "missing-file"
    assert "</Looks/M/Tex>" in f.where and "@tex/absent.png@" in f.where
    assert "absent.png" in f.message


def test_udim_is_skipped_listing_tiles_found(tmp_path):
    (tmp_path / "tex").mkdir()
    for tile in (1001, 1002, 1011):
        write_image(tmp_path / "tex" / f"body.{tile}.png")
    result = scan_paths([texture_scene(tmp_path / "s.usda", "tex/body.<UDIM>.png")])
    f = _only_finding(result)
    assert f.code == "udim" and "1001, 1002, 1011" in f.message


def test_other_tile_set_tokens_are_tile_sets_not_missing_files(tmp_path):
    """``<UDIMSET>`` and Mari's ``<UVTILE>`` name tile sets too: skipped as such, their tiles listed."""
    (tmp_path / "tex").mkdir()
    for name in ("body.1001.png", "body.1002.png", "arm.u1_v1.png", "arm.u2_v1.png"):
        write_image(tmp_path / "tex" / name)
    for asset, tiles in (("tex/body.<UDIMSET>.png", "1001, 1002"), ("tex/arm.<UVTILE>.png", "u1_v1, u2_v1")):
        f = _only_finding(scan_paths([texture_scene(tmp_path / "s.usda", asset)]))
        assert f.code == "udim" and tiles in f.message, f.message


def test_a_material_with_a_udim_map_is_left_alone_not_failed(tmp_path, capsys):
    """Its other maps are not tiled (they would no longer line up with the UDIM set), and nothing failed: the
    stack is left alone, exit 0."""
    import json

    from seamless_usd_cli.main import main

    (tmp_path / "tex").mkdir()
    for tile in (1001, 1002):
        write_image(tmp_path / "tex" / f"body.{tile}.png")
    shutil.copyfile(TEXTURES / "brick_roughness.png", tmp_path / "tex" / "rough.png")
    path = texture_scene(tmp_path / "s.usda", "tex/body.<UDIM>.png")
    stage = Usd.Stage.Open(str(path))
    rough = UsdShade.Shader.Define(stage, "/Looks/M/Rough")
    rough.CreateIdAttr("UsdUVTexture")
    rough.CreateInput("file", Sdf.ValueTypeNames.Asset).Set("tex/rough.png")
    rough.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(
        UsdShade.Shader.Get(stage, "/Looks/M/St").ConnectableAPI(), "result")
    UsdShade.Shader.Get(stage, "/Looks/M/Surface").CreateInput("roughness", Sdf.ValueTypeNames.Float).ConnectToSource(
        rough.ConnectableAPI(), "r")
    stage.Save()
    code = main(["process", str(path), "--dry-run", "--json"])
    report = json.loads(capsys.readouterr().out)
    [stack] = report["stacks"]
    assert code == 0 == report["exit_code"] and stack["status"] == "left-alone" and "(udim)" in stack["message"]


def test_texture_without_file_is_skipped(tmp_path):
    f = _only_finding(scan_paths([texture_scene(tmp_path / "s.usda", None)]))
    assert f.code == "no-file"


def test_texture_without_uv_input_is_skipped(tmp_path):
    write_image(tmp_path / "a.png")
    f = _only_finding(scan_paths([texture_scene(tmp_path / "s.usda", "a.png", st=False)]))
    assert f.code == "no-uv" and "swatch" in f.message


def test_image_below_16_px_is_skipped(tmp_path):
    write_image(tmp_path / "small.png", size=12)
    f = _only_finding(scan_paths([texture_scene(tmp_path / "s.usda", "small.png")]))
    assert f.code == "too-small" and "12x12" in f.message and "16 px" in f.message


def test_image_of_64_px_is_a_stack(tmp_path):
    """Icons and small game textures are processed (with a tile cut from the source: see test_process_small)."""
    write_image(tmp_path / "small.png", size=64)
    result = scan_paths([texture_scene(tmp_path / "s.usda", "small.png")])
    assert not result.findings and len(result.stacks) == 1


def test_unreadable_image_is_skipped(tmp_path):
    (tmp_path / "junk.png").write_bytes(b"this is not an image")
    f = _only_finding(scan_paths([texture_scene(tmp_path / "s.usda", "junk.png")]))
    assert f.code == "unreadable-file"


def test_usdz_texture_is_read_through_ar_and_marked_in_package(tmp_path):
    shutil.copy(TEXTURES / "brick_albedo.png", tmp_path / "albedo.png")
    texture_scene(tmp_path / "s.usda", "albedo.png")
    assert UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(tmp_path / "s.usda")), str(tmp_path / "s.usdz"))
    (tmp_path / "albedo.png").unlink()  # only the packaged copy is left
    result = scan_paths([tmp_path / "s.usdz"])
    (stack,) = result.stacks
    (m,) = stack.maps
    assert m.in_package and m.resolved.endswith("]") and "s.usdz[" in m.resolved
    assert (m.image.width, m.image.channels) == (256, 3)


def test_in_memory_stage_with_missing_and_good_textures(tmp_path):
    write_image(tmp_path / "good.png")
    stage = Usd.Stage.Open(str(texture_scene(tmp_path / "s.usda", "good.png")))
    stage.GetRootLayer().Save()
    mem = Usd.Stage.CreateInMemory()
    mem.GetRootLayer().subLayerPaths.append(str(tmp_path / "s.usda"))
    result = scan_stage(mem)
    assert len(result.stacks) == 1 and not result.findings
    assert result.sources and result.sources[0].startswith("anon:")


def test_an_animated_file_input_is_named_and_its_material_left_alone(tmp_path, capsys):
    """A file input with time samples (a texture swapped over time; with a default too, or without) renders the
    samples, not its default: it is named as animated, not as a node with no file, and its material is left
    alone (exit 0), since a layer over it would replace the swap with one tile."""
    import json

    from seamless_usd_cli.main import main

    shutil.copyfile(TEXTURES / "brick_albedo.png", tmp_path / "a.png")
    shutil.copyfile(TEXTURES / "cloth.png", tmp_path / "b.png")
    for with_default in (True, False):
        path = texture_scene(tmp_path / f"s{int(with_default)}.usda", "a.png" if with_default else None)
        stage = Usd.Stage.Open(str(path))
        attr = UsdShade.Shader.Get(stage, "/Looks/M/Tex").CreateInput("file", Sdf.ValueTypeNames.Asset).GetAttr()
        attr.Set(Sdf.AssetPath("a.png"), 1)
        attr.Set(Sdf.AssetPath("b.png"), 10)
        stage.Save()
        f = _only_finding(scan_paths([path]))
        assert f.code == "animated-file" and "2 time sample(s)" in f.message
        assert main(["process", str(path), "--dry-run", "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["layers_written"] == []


def test_a_material_whose_only_texture_is_a_udim_set_has_a_left_alone_row(tmp_path, capsys):
    """It has no stack, so it was only a finding: no row in the table or the JSON and not counted left alone, where
    a material whose texture is missing gets a failed row. Now a left-alone row says why."""
    import json

    from seamless_usd_cli.main import main

    (tmp_path / "tex").mkdir()
    for tile in (1001, 1002):
        write_image(tmp_path / "tex" / f"body.{tile}.png")
    path = texture_scene(tmp_path / "s.usda", "tex/body.<UDIM>.png")
    code = main(["process", str(path), "--dry-run", "--json"])
    report = json.loads(capsys.readouterr().out)
    [row] = report["stacks"]
    assert code == 0 and row["status"] == "left-alone" and report["counts"]["left-alone"] == 1
    assert "body.<UDIM>.png" in row["message"] and "1001, 1002" in row["message"]


def test_a_texture_node_whose_id_is_misspelt_is_named_and_its_material_left_alone(tmp_path, capsys):
    """``info:id = "UsdUVTextur"``: the albedo was dropped without a word and the material's roughness tiled on its
    own (its albedo then misaligned with it). The node is a ``file-node-not-read`` finding and the material is
    left alone."""
    import json

    from seamless_usd_cli.main import main

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    shutil.copytree(samples / "textures", tmp_path / "textures")
    (tmp_path / "brick").mkdir()
    scene = (samples / "brick" / "scene.usda").read_text()
    start = scene.index('def Shader "Albedo"')
    scene = scene[:start] + scene[start:].replace('"UsdUVTexture"', '"UsdUVTextur"', 1)
    (tmp_path / "brick" / "scene.usda").write_text(scene)
    result = scan_paths([tmp_path / "brick" / "scene.usda"])
    [finding] = [f for f in result.findings if f.code == "file-node-not-read"]
    assert "UsdUVTextur" in finding.message and "brick_albedo.png" in finding.where and "is the id" in finding.message
    main(["process", str(tmp_path / "brick" / "scene.usda"), "--dry-run", "--json"])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    assert stack["status"] == "left-alone", stack
