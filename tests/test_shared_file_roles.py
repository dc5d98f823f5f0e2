"""One RGBA file read by two texture nodes of one material, its colour (sRGB) by one and its alpha (raw) by the
other: each node gets a tile of its own, the colour kept in one and the alpha in the other; neither overwrites the
other, and what the run says is what ``check`` finds on disk."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
from pxr import Usd

from seamless_usd.pipeline.check import check_paths
from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"
SCENE = """#usda 1.0
def Scope "Looks"
{
    def Material "M"
    {
        token outputs:surface.connect = </Looks/M/Surface.outputs:surface>
        def Shader "Surface"
        {
            uniform token info:id = "UsdPreviewSurface"
            color3f inputs:diffuseColor.connect = </Looks/M/Colour.outputs:rgb>
            float inputs:opacity.connect = </Looks/M/Opacity.outputs:a>
            token outputs:surface
        }
        def Shader "St"
        {
            uniform token info:id = "UsdPrimvarReader_float2"
            string inputs:varname = "st"
            float2 outputs:result
        }
        def Shader "Colour"
        {
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @./tex/leaf.png@
            token inputs:sourceColorSpace = "sRGB"
            float2 inputs:st.connect = </Looks/M/St.outputs:result>
            float3 outputs:rgb
        }
        def Shader "Opacity"
        {
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @./tex/leaf.png@
            token inputs:sourceColorSpace = "raw"
            float2 inputs:st.connect = </Looks/M/St.outputs:result>
            float outputs:a
        }
    }
}
"""


def test_colour_and_alpha_of_one_file_read_by_two_nodes_get_a_tile_each(tmp_path, capsys):
    wood = oiio.ImageBuf(str(SAMPLES / "wood_color.png")).get_pixels(oiio.FLOAT)[:160, :160, :3]
    alpha = wood.mean(axis=2, keepdims=True) ** 0.5  # a mask that follows the grain
    (tmp_path / "tex").mkdir()
    out = oiio.ImageOutput.create(str(tmp_path / "tex" / "leaf.png"))
    spec = oiio.ImageSpec(160, 160, 4, oiio.UINT8)
    spec.attribute("oiio:UnassociatedAlpha", 1)
    assert out.open(str(tmp_path / "tex" / "leaf.png"), spec)
    assert out.write_image(np.concatenate([wood, alpha], axis=2).astype(np.float32))
    out.close()
    scene = tmp_path / "leaf.usda"
    scene.write_text(SCENE)
    code = main(["process", str(scene), "--preset", "tiny", "--seeds", "1", "--max-size", "128", "--cache-dir",
                 str(tmp_path / "cache"), "--json"])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    outputs = {m["roles"][0]: Path(m["output"]) for m in stack["maps"]}
    assert len(set(outputs.values())) == 2, outputs  # one tile each
    stage = Usd.Stage.Open(str(tmp_path / "leaf.seamless.usda"))
    for node, role in (("Colour", "diffuseColor"), ("Opacity", "opacity")):
        authored = stage.GetPrimAtPath(f"/Looks/M/{node}").GetAttribute("inputs:file").Get().resolvedPath
        assert Path(authored).resolve() == outputs[role].resolve()
    colour = oiio.ImageBuf(str(outputs["diffuseColor"]))
    assert colour.spec().getattribute("oiio:ColorSpace").lower().startswith("srgb")
    assert colour.get_pixels(oiio.FLOAT)[..., :3].std() > 0.02  # the colour is kept, not a constant
    opacity = oiio.ImageBuf(str(outputs["opacity"]))
    assert opacity.get_pixels(oiio.FLOAT)[..., 3].std() > 0.02
    [checked] = check_paths([tmp_path / "leaf.seamless.usda"]).items
    assert checked.verdict["reference"] == "source"
    assert checked.passed == (stack["status"] == "passed") == (code == 0)


def test_two_stages_with_one_material_path_and_copies_of_one_file(tmp_path, capsys):
    """Two stages in one folder, each with ``/Looks/M`` reading its own copy of the same bytes: both are processed
    (the second from the cache), each layer points at its own tile, and neither run nor a rerun fails."""
    import shutil

    (tmp_path / "tex").mkdir()
    for name in ("x.png", "y.png"):
        shutil.copyfile(SAMPLES / "brick_albedo.png", tmp_path / "tex" / name)
        (tmp_path / f"s_{name[0]}.usda").write_text(SCENE.replace("leaf.png", name).replace(
            'float inputs:opacity.connect = </Looks/M/Opacity.outputs:a>', ""))
    cache = str(tmp_path / "cache")
    for args in ([str(tmp_path / "s_x.usda")], [str(tmp_path / "s_y.usda")], [str(tmp_path)]):
        code = main(["process", *args, "--preset", "tiny", "--seeds", "1", "--cache-dir", cache, "--json"])
        stacks = json.loads(capsys.readouterr().out)["stacks"]
        assert all("internal error" not in s["message"] for s in stacks), stacks
        assert code == (0 if all(s["status"] in ("passed", "reused") for s in stacks) else 1)
    for name in ("x", "y"):
        stage = Usd.Stage.Open(str(tmp_path / f"s_{name}.seamless.usda"))
        tile = stage.GetPrimAtPath("/Looks/M/Colour").GetAttribute("inputs:file").Get().resolvedPath
        assert Path(tile).name.startswith(f"{name}.") and Path(tile).is_file()


def test_two_stacks_of_one_material_path_sharing_one_map_write_two_tiles_of_it(tmp_path, capsys):
    """Two stages in one folder, each with ``/World/Looks/Brick``: the same roughness file, albedos that differ (one is
    the other mirrored). Every map's tile is cut through one field made from the whole stack, so each stack gets its
    own roughness tile; neither overwrites the other, and each layer's tiles are judged by ``check`` as ``process``
    judged them."""
    import shutil

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    shutil.copytree(samples / "textures", tmp_path / "textures")
    shutil.copytree(samples / "brick", tmp_path / "brick")
    mirrored = oiio.ImageBufAlgo.flop(oiio.ImageBuf(str(tmp_path / "textures" / "brick_albedo.png")))
    assert mirrored.write(str(tmp_path / "textures" / "brick_albedo_mirrored.png"))
    scene = tmp_path / "brick" / "scene.usda"
    (tmp_path / "brick" / "other.usda").write_text(scene.read_text().replace("brick_albedo.png",
                                                                             "brick_albedo_mirrored.png"))
    code = main(["process", str(tmp_path / "brick"), "--preset", "tiny", "--seeds", "1", "--max-size", "128",
                 "--cache-dir", str(tmp_path / "cache"), "--json"])
    stacks = json.loads(capsys.readouterr().out)["stacks"]
    assert len(stacks) == 2 and all(s["origin"] != "duplicate" for s in stacks)
    roughness = {Path(m["output"]) for s in stacks for m in s["maps"] if "roughness" in m["asset"]}
    assert len(roughness) == 2 and all(p.is_file() for p in roughness)  # one tile of the shared map per stack
    for s in stacks:
        [item] = check_paths([Path(s["source"]).with_name(Path(s["source"]).stem + ".seamless.usda")]).items
        assert item.passed == (s["status"] == "passed"), (item.verdict, s["status"])
    assert code == (0 if all(s["status"] == "passed" for s in stacks) else 1)


def test_two_nodes_reading_the_same_channels_of_one_file_share_one_tile(tmp_path, capsys):
    """Two texture nodes of one stack reading the same channels of one file: one tile, which both read (two were
    written, numbered, and both nodes read the second: the first was left on disk, read by nothing)."""
    import shutil

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("brick", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    scene = tmp_path / "brick" / "scene.usda"
    text = scene.read_text()
    start = text.index('            def Shader "Albedo"')
    end = text.index("            }\n", start) + len("            }\n")
    twin = text[start:end].replace('"Albedo"', '"Glow"')
    text = (text[:end] + "\n" + twin + text[end:]).replace(
        "color3f inputs:diffuseColor.connect = </World/Looks/Brick/Albedo.outputs:rgb>",
        "color3f inputs:diffuseColor.connect = </World/Looks/Brick/Albedo.outputs:rgb>\n"
        "                color3f inputs:emissiveColor.connect = </World/Looks/Brick/Glow.outputs:rgb>")
    scene.write_text(text)
    main(["process", str(scene), "--preset", "tiny", "--max-size", "128", "--cache-dir", str(tmp_path / "cache"),
          "--json"])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    assert len(stack["maps"]) == 4
    tiles = sorted(p.name for p in (tmp_path / "brick" / "tileable").iterdir())
    assert len(tiles) == 3, tiles  # albedo (both nodes), normal, roughness
    stage = Usd.Stage.Open(str(scene.with_name("scene.seamless.usda")))
    read = {stage.GetAttributeAtPath(f"/World/Looks/Brick/{n}.inputs:file").Get().resolvedPath for n in ("Albedo", "Glow")}
    assert len(read) == 1 and Path(read.pop()).name in tiles


def test_tiles_made_otherwise_never_replace_the_tiles_another_layer_names(tmp_path, capsys):
    """Two stages in one folder read the same brick maps, so their tiles share ``tileable/``. Made again for one of
    them with other settings (another seed, preset or --refine), or read as raw by it where the other reads sRGB,
    the tiles got the same names and replaced those the other stage's layer names, judged and recorded as they were
    (a passed 144 px tile became a 160 px not-passed one under the other's UV scale). Each now gets its own."""
    import shutil

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    shutil.copytree(samples / "textures", tmp_path / "textures")
    (tmp_path / "shots").mkdir()
    scene = (samples / "brick" / "scene.usda").read_text()
    (tmp_path / "shots" / "a.usda").write_text(scene)
    (tmp_path / "shots" / "b.usda").write_text(scene)
    run = ["process", "--preset", "tiny", "--seeds", "1", "--refine", "off", "--cache-dir", str(tmp_path / "cache"),
           "--json"]
    main([*run, "--max-size", "128", str(tmp_path / "shots")])
    capsys.readouterr()

    def named(stage: str) -> dict[str, bytes]:
        layer = Usd.Stage.Open(str(tmp_path / "shots" / f"{stage}.seamless.usda"))
        paths = [layer.GetPrimAtPath(f"/World/Looks/Brick/{n}").GetAttribute("inputs:file").Get().resolvedPath
                 for n in ("Albedo", "Normal", "Roughness")]
        return {p: Path(p).read_bytes() for p in paths}

    b_before = named("b")
    assert main([*run, "--max-size", "128", "--seed", "7", str(tmp_path / "shots" / "a.usda")]) in (0, 1)
    capsys.readouterr()  # a made again with another seed
    assert named("b") == b_before  # b's layer names the same tiles, byte for byte
    assert not set(named("a")) & set(b_before)
    # the albedo read as raw by a, sRGB by b: another tile of it, b's kept
    (tmp_path / "shots" / "a.usda").write_text(scene.replace(
        '@../textures/brick_albedo.png@', '@../textures/brick_albedo.png@\n                token inputs:sourceColorSpace = "raw"'))
    assert main([*run, "--max-size", "128", str(tmp_path / "shots" / "a.usda")]) in (0, 1)
    capsys.readouterr()
    assert named("b") == b_before and not set(named("a")) & set(b_before)
    for stage in ("a", "b"):  # check agrees with what each run recorded
        [item] = check_paths([tmp_path / "shots" / f"{stage}.seamless.usda"]).items
        assert item.verdict["reference"] == "source", item
