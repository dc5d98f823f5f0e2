"""Tracing through USD NodeGraphs and interface inputs, and glTF image nodes inside USD."""
from __future__ import annotations

from pathlib import Path

from seamless_usd.discover import scan_paths

TEXTURES = (Path(__file__).resolve().parents[1] / "sample_assets" / "textures").as_posix()

NODEGRAPH_SCENE = f'''#usda 1.0
def Material "M"
{{
    asset inputs:albedoFile = @{TEXTURES}/wood_color.png@
    token outputs:surface.connect = </M/Surface.outputs:surface>

    def Shader "Surface"
    {{
        uniform token info:id = "UsdPreviewSurface"
        color3f inputs:diffuseColor.connect = </M/Graph.outputs:color>
        float inputs:roughness.connect = </M/Graph.outputs:rough>
        token outputs:surface
    }}

    def NodeGraph "Graph"
    {{
        asset inputs:file.connect = </M.inputs:albedoFile>
        color3f outputs:color.connect = </M/Graph/Tex.outputs:rgb>
        float outputs:rough.connect = </M/Graph/Rough.outputs:r>

        def Shader "St"
        {{
            uniform token info:id = "UsdPrimvarReader_float2"
            string inputs:varname = "uv"
            float2 outputs:result
        }}

        def Shader "Tex"
        {{
            uniform token info:id = "UsdUVTexture"
            asset inputs:file.connect = </M/Graph.inputs:file>
            float2 inputs:st.connect = </M/Graph/St.outputs:result>
            float3 outputs:rgb
        }}

        def Shader "Rough"
        {{
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @{TEXTURES}/wood_roughness.png@
            float2 inputs:st.connect = </M/Graph/St.outputs:result>
            float outputs:r
        }}
    }}
}}
'''

GLTF_SCENE = f'''#usda 1.0
def Material "G"
{{
    token outputs:mtlx:surface.connect = </G/Pbr.outputs:out>

    def Shader "Pbr"
    {{
        uniform token info:id = "ND_gltf_pbr_surfaceshader"
        color3f inputs:base_color.connect = </G/Base.outputs:out>
        float inputs:roughness.connect = </G/Orm.outputs:outy>
        token outputs:out
    }}

    def Shader "Base"
    {{
        uniform token info:id = "ND_gltf_image_color3_color3_1_0"
        asset inputs:file = @{TEXTURES}/brick_albedo.png@ (
            colorSpace = "srgb_texture"
        )
        float2 inputs:scale = (4, 4)
        string inputs:uaddressmode = "mirror"
        color3f outputs:out
    }}

    def Shader "OrmImage"
    {{
        uniform token info:id = "ND_gltf_image_vector3_vector3_1_0"
        asset inputs:file = @{TEXTURES}/brick_orm.png@
        vector3f outputs:out
    }}

    def Shader "Orm"
    {{
        uniform token info:id = "ND_separate3_vector3"
        vector3f inputs:in.connect = </G/OrmImage.outputs:out>
        float outputs:outy
    }}
}}
'''


def test_nodegraph_outputs_and_nested_interface_inputs(tmp_path):
    path = tmp_path / "graph.usda"
    path.write_text(NODEGRAPH_SCENE)
    result = scan_paths([path])
    (stack,) = result.stacks
    maps = {Path(m.resolved).name: m for m in stack.maps}
    color = maps["wood_color.png"]
    assert color.node == "/M/Graph/Tex"
    # Tex.inputs:file -> Graph.inputs:file -> M.inputs:albedoFile, where the value is authored
    assert (color.file_at.prim, color.file_at.attribute) == ("/M", "inputs:albedoFile")
    assert color.roles[0].shader_input == "</M/Surface.inputs:diffuseColor>"
    assert stack.uv.primvar == "uv" and stack.uv.reader == "/M/Graph/St"
    assert [(r.role, r.channels) for r in maps["wood_roughness.png"].roles] == [("roughness", "r")]


def test_gltf_image_nodes_with_builtin_transform(tmp_path):
    path = tmp_path / "gltf.usda"
    path.write_text(GLTF_SCENE)
    result = scan_paths([path])
    maps = {Path(m.resolved).name: m for s in result.stacks for m in s.maps}
    base, orm = maps["brick_albedo.png"], maps["brick_orm.png"]
    (t,) = base.uv.transforms
    assert t.kind == "place2d" and t.node == "/G/Base" and t.scale == (4.0, 4.0) and t.pivot == (0.0, 1.0)
    assert base.wrap_s == "mirror" and base.wrap_t == "periodic"
    assert base.color_space.value == "sRGB"
    assert [(r.role, r.channels) for r in orm.roles] == [("roughness", "g")]
    assert orm.uv.transforms == ()
    # different tiling: two stacks in one material
    assert len(result.stacks) == 2


def test_a_material_that_cannot_be_followed_is_an_error_and_the_rest_go_on(tmp_path, samples_dir):
    # rotation authored as a string: the transform cannot be read
    text = (samples_dir / "transform2d" / "scene.usda").read_text()
    text = text.replace("float inputs:rotation = 90", 'string inputs:rotation = "ninety"')
    text = text.replace("@../textures/", f"@{TEXTURES}/")
    path = tmp_path / "bad.usda"
    path.write_text(text)
    other = tmp_path / "good.usda"
    other.write_text((samples_dir / "orm" / "scene.usda").read_text().replace("@../textures/", f"@{TEXTURES}/"))
    result = scan_paths([path, other])
    (error,) = result.findings
    assert error.severity.value == "error" and error.code == "discovery-error"
    assert error.where == "</World/Looks/Wood>"
    assert [s.material for s in result.stacks] == ["</World/Looks/BrickOrm>"]
