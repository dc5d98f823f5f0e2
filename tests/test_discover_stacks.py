"""Stacks: grouping by UV chain, identical stacks, and composition (instances, variants, payloads)."""
from __future__ import annotations

from pathlib import Path

from seamless_usd.discover import scan_paths

TEXTURES = (Path(__file__).resolve().parents[1] / "sample_assets" / "textures").as_posix()


def material(root: str, name: str, *, albedo: str = "brick_albedo.png", rough: str = "brick_roughness.png",
             rough_reader: str = "St", normal_scale: str | None = None,
             normal_bias: str = "(-1, 1, -1, 0)") -> str:
    """USDA text of Material ``root/name`` with an albedo, a roughness and optionally a normal texture."""
    m = f"{root}/{name}"
    normal = ""
    normal_in = ""
    if normal_scale:
        normal_in = f"normal3f inputs:normal.connect = <{m}/Normal.outputs:rgb>"
        normal = f'''
        def Shader "Normal" {{
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @{TEXTURES}/brick_normal.png@
            token inputs:sourceColorSpace = "raw"
            float4 inputs:scale = {normal_scale}
            float4 inputs:bias = {normal_bias}
            float2 inputs:st.connect = <{m}/St.outputs:result>
            float3 outputs:rgb
        }}'''
    return f'''
    def Material "{name}" {{
        token outputs:surface.connect = <{m}/Surface.outputs:surface>
        def Shader "Surface" {{
            uniform token info:id = "UsdPreviewSurface"
            color3f inputs:diffuseColor.connect = <{m}/Albedo.outputs:rgb>
            float inputs:roughness.connect = <{m}/Rough.outputs:r>
            {normal_in}
            token outputs:surface
        }}
        def Shader "St" {{
            uniform token info:id = "UsdPrimvarReader_float2"
            string inputs:varname = "st"
            float2 outputs:result
        }}
        def Shader "St2" {{
            uniform token info:id = "UsdPrimvarReader_float2"
            string inputs:varname = "st1"
            float2 outputs:result
        }}
        def Shader "Albedo" {{
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @{TEXTURES}/{albedo}@
            float2 inputs:st.connect = <{m}/St.outputs:result>
            float3 outputs:rgb
        }}
        def Shader "Rough" {{
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @{TEXTURES}/{rough}@
            token inputs:sourceColorSpace = "raw"
            float2 inputs:st.connect = <{m}/{rough_reader}.outputs:result>
            float outputs:r
        }}{normal}
    }}'''


def write(path: Path, body: str) -> Path:
    path.write_text("#usda 1.0\n" + body + "\n")
    return path


def test_identical_stacks_are_marked_duplicate(tmp_path):
    path = write(tmp_path / "s.usda", f'def Scope "Looks" {{\n{material("/Looks", "A")}{material("/Looks", "B")}{material("/Looks", "C", albedo="wood_color.png")}\n}}')
    result = scan_paths([path])
    a, b, c = result.stacks
    assert a.material == "</Looks/A>" and a.duplicate_of is None
    assert b.duplicate_of == a.id and b.content_key == a.content_key
    assert c.duplicate_of is None and c.content_key != a.content_key


def test_maps_on_different_uv_chains_form_separate_stacks(tmp_path):
    result = scan_paths([write(tmp_path / "s.usda", f'def Scope "Looks" {{\n{material("/Looks", "A", rough_reader="St2")}\n}}')])
    assert len(result.stacks) == 2
    assert {s.uv.primvar for s in result.stacks} == {"st", "st1"}
    assert len({s.id for s in result.stacks}) == 2


def test_y_flipped_normal_scale_bias(tmp_path):
    path = write(tmp_path / "s.usda", f'def Scope "Looks" {{\n{material("/Looks", "A", normal_scale="(2, -2, 2, 1)")}\n}}')
    (stack,) = scan_paths([path]).stacks
    (normal,) = [m for m in stack.maps if m.is_normal]
    assert normal.scale == (2.0, -2.0, 2.0, 1.0) and normal.bias == (-1.0, 1.0, -1.0, 0.0)
    assert normal.normal_y_flip


def test_normal_without_scale_bias_is_warned(tmp_path):
    path = write(tmp_path / "s.usda", f'def Scope "Looks" {{\n{material("/Looks", "A", normal_scale="(1, 1, 1, 1)", normal_bias="(0, 0, 0, 0)")}\n}}')
    result = scan_paths([path])
    assert "normal-scale-bias" in [f.code for f in result.findings]


def test_instances_variants_and_payloads_are_composed(tmp_path):
    write(tmp_path / "asset.usda", f'(defaultPrim = "Asset")\ndef Xform "Asset" {{{material("/Asset", "Mat")}\n}}')
    write(tmp_path / "payload.usda", f'(defaultPrim = "P")\ndef Xform "P" {{{material("/P", "PMat", albedo="wood_color.png")}\n}}')
    body = f'''
def Xform "Inst1" (
    instanceable = true
    references = @./asset.usda@
) {{}}
def Xform "Inst2" (
    instanceable = true
    references = @./asset.usda@
) {{}}
def Xform "Loaded" (
    payload = @./payload.usda@
) {{}}
def Xform "Switch" (
    variants = {{
        string look = "wood"
    }}
    prepend variantSets = "look"
) {{
    variantSet "look" = {{
        "brick" {{ {material("/Switch", "V")}
        }}
        "wood" {{ {material("/Switch", "V", albedo="wood_color.png", rough="wood_roughness.png")}
        }}
    }}
}}'''
    result = scan_paths([write(tmp_path / "s.usda", body)])
    by_material = {s.material: s for s in result.stacks if not s.selection}
    # instance proxies: both instances seen; the second is the same content
    assert {"</Inst1/Mat>", "</Inst2/Mat>"} <= set(by_material)
    assert by_material["</Inst2/Mat>"].duplicate_of == by_material["</Inst1/Mat>"].id
    # payloads loaded
    assert "</Loaded/PMat>" in by_material
    # the selected variant as the stage has it, the other found under its own selection
    names = {Path(m.resolved).name for m in by_material["</Switch/V>"].maps}
    assert names == {"wood_color.png", "wood_roughness.png"}
    (other,) = [s for s in result.stacks if s.selection]
    assert other.material == "</Switch/V>" and other.to_dict()["variant"] == "look=brick"
    assert {Path(m.resolved).name for m in other.maps} == {"brick_albedo.png", "brick_roughness.png"}
    assert [(v.mode, v.combinations) for v in result.variants] == [("all", 2)]
    # assets authored in the referenced layer resolve against it
    albedo = next(m for m in by_material["</Inst1/Mat>"].maps if "albedo" in m.asset)
    assert Path(albedo.file_at.layer).name == "asset.usda"


def test_stack_to_dict_has_id_and_content_key(samples_dir):
    (stack,) = scan_paths([samples_dir / "orm" / "scene.usda"]).stacks
    d = stack.to_dict()
    assert d["id"] == stack.id and d["content_key"] == stack.content_key and len(d["maps"]) == 2


def test_stacks_inside_instances_fail_before_any_tile_is_made(tmp_path, capsys):
    """A material an instanceable reference brings in cannot be edited over the stage: process says so for each
    instance and makes no tile for it (the asset itself, processed on its own, is edited as usual)."""
    import json

    from seamless_usd_cli.main import main

    write(tmp_path / "asset.usda", f'(defaultPrim = "Asset")\ndef Xform "Asset" {{{material("/Asset", "Mat")}\n}}')
    body = "".join(f'def Xform "Inst{i}" (\n    instanceable = true\n    references = @./asset.usda@\n) {{}}\n'
                   for i in (1, 2))
    scene = write(tmp_path / "s.usda", body)
    code = main(["process", str(scene), "--dry-run", "--json"])
    stacks = json.loads(capsys.readouterr().out)["stacks"]
    assert code == 1 and [s["status"] for s in stacks] == ["failed", "failed"]
    assert all("is inside an instance" in s["message"] and "</Inst" in s["message"] for s in stacks)
    code = main(["process", str(scene), "--preset", "tiny", "--json", "--cache-dir", str(tmp_path / "cache")])
    assert code == 1 and not (tmp_path / "tileable").exists()


def test_stacks_inside_instances_are_edited_in_their_prototype_s_layer_in_place(tmp_path, capsys):
    """With --in-place, a material an instanceable reference brings in is edited where its prototype is made: the
    referenced asset's layer (backed up), so every instance shows the tile; the stage itself is not touched, and a
    run again changes nothing. Without --in-place the failure names that layer and the flag."""
    import json

    from pxr import Usd

    from seamless_usd.pipeline.check import check_paths
    from seamless_usd_cli.main import main

    write(tmp_path / "asset.usda", f'(defaultPrim = "Asset")\ndef Xform "Asset" {{{material("/Asset", "Mat")}\n}}')
    body = "".join(f'def Xform "Inst{i}" (\n    instanceable = true\n    references = @./asset.usda@\n) {{}}\n'
                   for i in (1, 2))
    scene = write(tmp_path / "s.usda", body)
    scene_text, asset_text = scene.read_text(), (tmp_path / "asset.usda").read_text()
    run = ["process", str(scene), "--preset", "tiny", "--seeds", "1", "--json", "--cache-dir", str(tmp_path / "cache")]
    assert main([*run[:2], "--dry-run", "--json"]) == 1
    [failed, _] = json.loads(capsys.readouterr().out)["stacks"]
    assert "--in-place" in failed["message"] and "asset.usda" in failed["message"], failed["message"]
    code = main([*run, "--in-place"])
    stacks = json.loads(capsys.readouterr().out)["stacks"]
    assert [s["status"] for s in stacks] in (["passed", "reused"], ["not-passed", "not-passed"]), stacks
    assert code == (0 if stacks[0]["status"] == "passed" else 1)
    assert scene.read_text() == scene_text and (tmp_path / "asset.usda.bak").read_text() == asset_text
    stage = Usd.Stage.Open(str(scene))
    for i in (1, 2):
        albedo = stage.GetPrimAtPath(f"/Inst{i}/Mat/Albedo").GetAttribute("inputs:file").Get()
        assert Path(albedo.resolvedPath).parent == tmp_path / "tileable", albedo
    assert [i.passed for i in check_paths([scene]).items] == [stacks[0]["status"] == "passed"]
    edited = (tmp_path / "asset.usda").read_text()
    assert main([*run, "--in-place"]) == code and (tmp_path / "asset.usda").read_text() == edited
    capsys.readouterr()
