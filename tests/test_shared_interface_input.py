"""A material input that two texture nodes read their file from (a tiling albedo and a decal left alone, the same
photo): the tile is set on the tiling node itself, its connection to the input cut, so the decal keeps the photo;
the material's input was set, and the decal showed a crop of the tile while the run said left alone."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from pxr import Usd, UsdShade

from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"
SCENE = """#usda 1.0
def Mesh "Floor" (
    prepend apiSchemas = ["MaterialBindingAPI"]
)
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1)]
    texCoord2f[] primvars:st = [(0, 0), (4, 0), (4, 4), (0, 4)] (
        interpolation = "vertex"
    )
    rel material:binding = </Looks/M>
}
def Scope "Looks"
{
    def Material "M"
    {
        asset inputs:baseTex = @./tex/brick_albedo.png@
        token outputs:surface.connect = </Looks/M/Surface.outputs:surface>
        def Shader "Surface"
        {
            uniform token info:id = "UsdPreviewSurface"
            color3f inputs:diffuseColor.connect = </Looks/M/Albedo.outputs:rgb>
            color3f inputs:emissiveColor.connect = </Looks/M/Decal.outputs:rgb>
            token outputs:surface
        }
        def Shader "St"
        {
            uniform token info:id = "UsdPrimvarReader_float2"
            string inputs:varname = "st"
            float2 outputs:result
        }
        def Shader "DecalPlace"
        {
            uniform token info:id = "UsdTransform2d"
            float2 inputs:in.connect = </Looks/M/St.outputs:result>
            float2 inputs:scale = (0.25, 0.25)
            float2 outputs:result
        }
        def Shader "Albedo"
        {
            uniform token info:id = "UsdUVTexture"
            asset inputs:file.connect = </Looks/M.inputs:baseTex>
            float2 inputs:st.connect = </Looks/M/St.outputs:result>
            token inputs:wrapS = "repeat"
            token inputs:wrapT = "repeat"
            float3 outputs:rgb
        }
        def Shader "Decal"
        {
            uniform token info:id = "UsdUVTexture"
            asset inputs:file.connect = </Looks/M.inputs:baseTex>
            float2 inputs:st.connect = </Looks/M/DecalPlace.outputs:result>
            token inputs:wrapS = "clamp"
            token inputs:wrapT = "clamp"
            float3 outputs:rgb
        }
    }
}
"""


def _file(stage: Usd.Stage, node: str) -> str:
    attr = UsdShade.Shader(stage.GetPrimAtPath(f"/Looks/M/{node}")).GetInput("file").GetValueProducingAttributes()[0]
    return Path(attr.Get().resolvedPath).name


@pytest.mark.parametrize("mode", ["new-layer", "in-place"])
@pytest.mark.parametrize("decal", ["clamp", "repeat"])
def test_a_decal_reading_the_same_material_input_keeps_its_photo(tmp_path, capsys, mode, decal):
    """With ``repeat`` both nodes are tiled (the decal's stack, identical, takes the albedo's tiles), each node set
    on its own; run again, the input is still left as it is (the second run found it read by no node any more and
    set it to a tile)."""
    (tmp_path / "tex").mkdir()
    shutil.copy(SAMPLES / "brick_albedo.png", tmp_path / "tex")
    scene = tmp_path / "scene.usda"
    scene.write_text(SCENE.replace('"clamp"', f'"{decal}"'))
    extra = ["--in-place"] if mode == "in-place" else []
    code = main(["process", "--preset", "tiny", "--max-size", "128", "--cache-dir", str(tmp_path / "cache"), "--json",
                 *extra, str(scene)])
    payload = json.loads(capsys.readouterr().out)
    status = {s["maps"][0]["node"].rsplit("/", 1)[-1].strip(">"): s["status"] for s in payload["stacks"]}
    assert status["Albedo"] == "passed" and code == payload["exit_code"], status
    assert status["Decal"] == ("left-alone" if decal == "clamp" else status["Decal"]) != "failed"
    stage = Usd.Stage.Open(str(scene if extra else tmp_path / "scene.seamless.usda"))
    assert _file(stage, "Albedo").endswith(".tile.png")
    if decal == "clamp":
        assert _file(stage, "Decal") == "brick_albedo.png"  # the decal as it was
    else:
        assert _file(stage, "Decal").endswith(".tile.png")  # an identical stack: the first's tile, set on the node
    assert stage.GetAttributeAtPath("/Looks/M.inputs:baseTex").Get().path == "./tex/brick_albedo.png"
    # run again: nothing more to do
    main(["process", "--preset", "tiny", "--max-size", "128", "--cache-dir", str(tmp_path / "cache"), "--json",
          *extra, str(scene)])
    again = json.loads(capsys.readouterr().out)
    assert not again["layers_written"], again["layers_written"]
    stage = Usd.Stage.Open(str(scene if extra else tmp_path / "scene.seamless.usda"))
    assert stage.GetAttributeAtPath("/Looks/M.inputs:baseTex").Get().path == "./tex/brick_albedo.png"
