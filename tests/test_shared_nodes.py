"""A texture node read by a use that is not made tileable is not edited for another use: the edit (the tile's path,
repeat, the UV scale) is made on the node, so the other use would show the tile too. Real stages: a node graph
shared by a tiling material and a UV atlas's, and a material whose clamped variant is left alone while its file is
authored outside the variants."""
from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

from pxr import Usd, UsdShade
from runchecks import PLUMBING

from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


def _quad(name: str, x0: int, uv: tuple[float, float], material: str) -> str:
    """A quad at ``x0`` whose UVs run from ``uv[0]`` to ``uv[1]`` both ways, bound to ``material``."""
    lo, hi = uv
    return f"""    def Mesh "{name}" (
        prepend apiSchemas = ["MaterialBindingAPI"]
    )
    {{
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        point3f[] points = [({x0}, -1, 0), ({x0 + 2}, -1, 0), ({x0 + 2}, 1, 0), ({x0}, 1, 0)]
        texCoord2f[] primvars:st = [({lo}, {lo}), ({hi}, {lo}), ({hi}, {hi}), ({lo}, {hi})] (
            interpolation = "vertex"
        )
        rel material:binding = <{material}>
    }}
"""

SHARED = """#usda 1.0
(
    defaultPrim = "World"
)

def Xform "World"
{
    def Scope "Looks"
    {
        def NodeGraph "SharedTex"
        {
            float3 outputs:rgb.connect = </World/Looks/SharedTex/Tex.outputs:rgb>
            def Shader "StReader"
            {
                uniform token info:id = "UsdPrimvarReader_float2"
                string inputs:varname = "st"
                float2 outputs:result
            }
            def Shader "Tex"
            {
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @../textures/brick_albedo.png@
                float2 inputs:st.connect = </World/Looks/SharedTex/StReader.outputs:result>
                token inputs:wrapS = "repeat"
                token inputs:wrapT = "repeat"
                float3 outputs:rgb
            }
        }
        def Material "M_tile"
        {
            token outputs:surface.connect = </World/Looks/M_tile/Surface.outputs:surface>
            def Shader "Surface"
            {
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor.connect = </World/Looks/SharedTex.outputs:rgb>
                token outputs:surface
            }
        }
        def Material "M_other"
        {
            token outputs:surface.connect = </World/Looks/M_other/Surface.outputs:surface>
            def Shader "Surface"
            {
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor.connect = </World/Looks/SharedTex.outputs:rgb>
                float inputs:roughness = 0.2
                token outputs:surface
            }
        }
    }
@MESHES@
}
""".replace("@MESHES@\n", _quad("A", -1, (0, 4), "/World/Looks/M_tile") + _quad("B", 2, (0.1, 0.45), "/World/Looks/M_other"))

WRAP_VARIANTS = """#usda 1.0
(
    defaultPrim = "World"
)

def Xform "World" (
    variants = {
        string wrapMode = "rep"
    }
    prepend variantSets = "wrapMode"
)
{
    def Scope "Looks"
    {
        def Material "M_wrapvar"
        {
            token outputs:surface.connect = </World/Looks/M_wrapvar/Surface.outputs:surface>
            def Shader "Surface"
            {
                uniform token info:id = "UsdPreviewSurface"
                float inputs:roughness.connect = </World/Looks/M_wrapvar/Tex.outputs:r>
                token outputs:surface
            }
            def Shader "StReader"
            {
                uniform token info:id = "UsdPrimvarReader_float2"
                string inputs:varname = "st"
                float2 outputs:result
            }
            def Shader "Tex"
            {
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @../textures/brick_roughness.png@
                token inputs:sourceColorSpace = "raw"
                float2 inputs:st.connect = </World/Looks/M_wrapvar/StReader.outputs:result>
                float outputs:r
            }
        }
    }
@MESHES@
    variantSet "wrapMode" = {
        "rep" {
            over "Looks"
            {
                over "M_wrapvar"
                {
                    over "Tex"
                    {
                        token inputs:wrapS = "repeat"
                        token inputs:wrapT = "repeat"
                    }
                }
            }
        }
        "clp" {
            over "Looks"
            {
                over "M_wrapvar"
                {
                    over "Tex"
                    {
                        token inputs:wrapS = "clamp"
                        token inputs:wrapT = "clamp"
                    }
                }
            }
            over "G"
            {
                texCoord2f[] primvars:st = [(0, 0), (1, 0), (1, 1), (0, 1)] (
                    interpolation = "vertex"
                )
            }
        }
    }
}
""".replace("@MESHES@\n", _quad("G", -1, (0, 4), "/World/Looks/M_wrapvar"))


def _scene(tmp_path: Path, text: str) -> Path:
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    (tmp_path / "looks").mkdir()
    scene = tmp_path / "looks" / "scene.usda"
    scene.write_text(text)
    return scene


def _process(scene: Path, cache: Path, capsys, *extra: str) -> tuple[int, dict]:
    code = main(["process", *PLUMBING, "--max-size", "112", "--json", "--cache-dir", str(cache), str(scene), *extra])
    return code, json.loads(capsys.readouterr().out)


def _file(layer: Path, node: str, variant: tuple[str, str] | None = None) -> str:
    stage = Usd.Stage.Open(str(layer))
    if variant:
        stage.GetPrimAtPath("/World").GetVariantSets().GetVariantSet(variant[0]).SetVariantSelection(variant[1])
    return UsdShade.Shader(stage.GetPrimAtPath(node)).GetInput("file").Get().path


def test_a_node_shared_with_an_atlas_is_not_edited_and_the_tiling_material_says_why(tmp_path, model_cache, capsys):
    scene = _scene(tmp_path, SHARED)
    before = hashlib.sha256(scene.read_bytes()).hexdigest()
    code, payload = _process(scene, model_cache, capsys)
    rows = {s["material"]: s for s in payload["stacks"]}
    assert rows["</World/Looks/M_other>"]["status"] == "left-alone"
    tiling = rows["</World/Looks/M_tile>"]
    assert tiling["status"] == "failed" and code == 1
    assert "</World/Looks/SharedTex/Tex>" in tiling["message"] and "</World/Looks/M_other>" in tiling["message"]
    layer = scene.with_name("scene.seamless.usda")
    assert not layer.exists() or _file(layer, "/World/Looks/SharedTex/Tex") == "../textures/brick_albedo.png"
    assert not (scene.parent / "tileable").exists() or not list((scene.parent / "tileable").glob("*.tile.*"))
    assert hashlib.sha256(scene.read_bytes()).hexdigest() == before
    # both uses made tileable, asked for: the node is edited for both
    code, payload = _process(scene, model_cache, capsys, "--force-materials", "*M_other")
    assert {s["status"] for s in payload["stacks"]} <= {"passed", "not-passed", "reused"}, payload["stacks"]
    assert "tileable" in _file(layer, "/World/Looks/SharedTex/Tex")


def test_a_left_alone_variant_keeps_its_texture_when_the_file_is_authored_outside_the_variants(tmp_path, model_cache,
                                                                                             capsys):
    scene = _scene(tmp_path, WRAP_VARIANTS)
    code, payload = _process(scene, model_cache, capsys)
    by_variant = {s["variant"]: s for s in payload["stacks"]}
    assert by_variant["wrapMode=clp"]["status"] == "left-alone" and code == 1
    failed = by_variant[""]  # the stage's own selection (repeat): it would have edited the file both read
    assert failed["status"] == "failed"
    assert "wrapMode=clp" in failed["message"] and "inside each variant" in failed["message"]
    layer = scene.with_name("scene.seamless.usda")
    if layer.exists():  # whatever else it holds, the clamped variant still reads the photo
        assert _file(layer, "/World/Looks/M_wrapvar/Tex", ("wrapMode", "clp")) == "../textures/brick_roughness.png"


def _variant_albedo_shared_roughness(folder: Path) -> Path:
    """A wall whose material sets its albedo inside each variant of ``shading`` (clean: brick, dirty: wood) and reads
    one roughness authored outside the variants, as a look that swaps one map per variant is often built."""
    import sys

    from pxr import Sdf, UsdGeom

    sys.path.insert(0, str(SAMPLES))
    from usdkit import bind, new_layer, plane, preview_material

    shutil.copytree(SAMPLES / "textures", folder / "tex")
    stage = new_layer(folder / "scene.usda", "World")
    UsdGeom.Xform.Define(stage, "/World")
    bind(plane(stage, "/World/Wall", 4, 3).GetPrim(), "/World/Looks/M")
    preview_material(stage, "/World/Looks/M", {"diffuseColor": ("./tex/brick_albedo.png", "rgb", "sRGB"),
                                               "roughness": ("./tex/brick_roughness.png", "r", "raw")})
    UsdShade.Shader.Get(stage, "/World/Looks/M/diffuseColorTex").GetInput("file").GetAttr().Clear()
    shading = stage.GetPrimAtPath("/World/Looks/M").GetVariantSets().AddVariantSet("shading")
    for variant, texture in (("clean", "./tex/brick_albedo.png"), ("dirty", "./tex/wood_tileable.jpg")):
        shading.AddVariant(variant)
        shading.SetVariantSelection(variant)
        with shading.GetVariantEditContext():
            UsdShade.Shader.Get(stage, "/World/Looks/M/diffuseColorTex").CreateInput(
                "file", Sdf.ValueTypeNames.Asset).Set(texture)
    shading.SetVariantSelection("clean")
    stage.Save()
    return folder / "scene.usda"


def test_a_variant_that_swaps_one_map_lists_all_it_reads_and_a_node_both_read_is_not_edited(tmp_path, model_cache,
                                                                                            capsys):
    """The dirty variant's stack was its albedo alone (the roughness, found first under the clean selection, was the
    clean stack's only): judged without it, and the roughness node, edited outside the variants for the clean stack's
    tile and UV scale, changed the dirty look and misaligned its maps."""
    scene = _variant_albedo_shared_roughness(tmp_path)
    import seamless_usd

    stacks = {s.selection and s.selection[0].variant: s for s in seamless_usd.scan(scene).stacks}
    assert {Path(m.asset).name for m in stacks["dirty"].maps} == {"wood_tileable.jpg", "brick_roughness.png"}
    assert {Path(m.asset).name for m in stacks[()].maps} == {"brick_albedo.png", "brick_roughness.png"}
    before = hashlib.sha256(scene.read_bytes()).hexdigest()
    code, payload = _process(scene, model_cache, capsys)
    assert code == 1 and [s["status"] for s in payload["stacks"]] == ["failed", "failed"], payload["stacks"]
    for row in payload["stacks"]:
        assert "</World/Looks/M/roughnessTex>" in row["message"] and "inside each variant" in row["message"]
    assert not (tmp_path / "tileable").exists() and not scene.with_name("scene.seamless.usda").exists()
    assert hashlib.sha256(scene.read_bytes()).hexdigest() == before


def test_look_variants_that_each_name_the_same_roughness_inside_the_variant_are_each_made(tmp_path, model_cache,
                                                                                          capsys):
    """Look variants that author every file inside the variant, naming the same roughness file: the two stacks read
    one node with one value, so both failed as if the value were authored once outside the variants ('author the
    texture's file inside each variant', which it was). Each variant's edits go inside it."""
    from pxr import Sdf

    scene = _variant_albedo_shared_roughness(tmp_path)
    stage = Usd.Stage.Open(str(scene))
    UsdShade.Shader.Get(stage, "/World/Looks/M/roughnessTex").GetInput("file").GetAttr().Clear()
    shading = stage.GetPrimAtPath("/World/Looks/M").GetVariantSet("shading")
    for variant in ("clean", "dirty"):
        shading.SetVariantSelection(variant)
        with shading.GetVariantEditContext():
            UsdShade.Shader.Get(stage, "/World/Looks/M/roughnessTex").CreateInput(
                "file", Sdf.ValueTypeNames.Asset).Set("./tex/brick_roughness.png")
    shading.SetVariantSelection("clean")
    stage.Save()
    code, payload = _process(scene, model_cache, capsys)
    assert {s["status"] for s in payload["stacks"]} <= {"passed", "not-passed"}, payload["stacks"]
    layer = Usd.Stage.Open(str(scene.with_name("scene.seamless.usda")))
    tiles = {}
    for variant in ("clean", "dirty"):
        layer.GetPrimAtPath("/World/Looks/M").GetVariantSet("shading").SetVariantSelection(variant)
        tiles[variant] = UsdShade.Shader.Get(layer, "/World/Looks/M/roughnessTex").GetInput("file").Get().path
    assert all("/tileable/" in t for t in tiles.values()) and tiles["clean"] != tiles["dirty"], tiles
