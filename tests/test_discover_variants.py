"""Variant space: materials and bindings found under selections the stage does not make are
judged under those selections, nested sets included; the space is reported, and walked one set
at a time when it is too large."""
from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest
from pxr import Usd

from seamless_usd.discover import scan_paths, scan_stage
from seamless_usd.discover.variants import MAX_COMBINATIONS, VariantSpace
from seamless_usd_cli.main import main
from test_discover_stacks import material
from seamless_usd_schemas import json_schema

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"
SHADING = SAMPLES / "shading"


def _by_material(result):
    return {(s.material, s.to_dict()["variant"]): s for s in result.stacks}


def test_nested_variants_inside_a_payload_are_all_composed():
    stage = Usd.Stage.Open(str(SHADING / "teapot.usda"))
    space = VariantSpace(stage)
    labels = [", ".join(f"{c.set}={c.variant}" for c in sel) for sel in space.selections()]
    # a nested set the stage's own selection does not reveal is always named
    assert labels == ["", "modelVariant=Fancy, shadingVariant=Plain",
                      "modelVariant=Fancy, shadingVariant=PorcelainFlowers"]
    assert (space.mode, space.combinations) == ("all", 3)
    # the caller's stage keeps its own selection and an empty session layer
    assert stage.GetPrimAtPath("/Teapot").GetVariantSet("modelVariant").GetVariantSelection() == "Utah"
    assert stage.GetSessionLayer().empty


def test_teapot_porcelain_is_an_atlas_in_its_nested_variant():
    stacks = _by_material(scan_paths([SHADING / "teapot.usda"]))
    utah = stacks[("</Teapot/Looks/M_utah>", "")]
    assert utah.intent == "uv-atlas" and "9 islands on </Teapot/Geom/Body>:" in utah.intent_reason
    porcelain = stacks[("</Teapot/Looks/M_porcelain>", "modelVariant=Fancy, shadingVariant=PorcelainFlowers")]
    assert porcelain.intent == "uv-atlas"
    assert ("25 islands on </Teapot/Geom/Body> in modelVariant=Fancy, shadingVariant=PorcelainFlowers"
            in porcelain.intent_reason)
    assert {m.asset.rsplit("/", 1)[-1] for m in porcelain.maps} == {
        "teapot_porcelain_atlas.png", "teapot_porcelain_arm.png"}


def test_king_shading_variants_bind_both_mtlx_atlases():
    result = scan_paths([SHADING / "king.usda"])
    stacks = _by_material(result)
    white = stacks[("</King/Looks/M_king_white>", "")]
    black = stacks[("</King/Looks/M_king_black>", "")]  # the material is on the stage as selected
    assert white.intent == black.intent == "uv-atlas"
    assert "16 islands on </King/Geom/Render>:" in white.intent_reason
    assert "16 islands on </King/Geom/Render> in shadingVariant=Black" in black.intent_reason
    (explored,) = result.variants
    assert [(s.selection[0].variant if s.selection else "", s.materials) for s in explored.selections] == [
        ("", ("</King/Looks/M_king_white>", "</King/Looks/M_king_black>")),
        ("Black", ("</King/Looks/M_king_white>", "</King/Looks/M_king_black>")),
    ]


def test_set_floor_found_in_its_own_variant():
    result = scan_paths([SHADING / "set.usda"])
    stacks = _by_material(result)
    floor = stacks[("</World/Floor/Looks/M_tiles>", "floorVariant=Tiled")]
    assert floor.intent == "tiling"
    assert "on </World/Floor> in floorVariant=Tiled: 4.00 x 4.00 periods" in floor.intent_reason
    assert sum(1 for s in result.stacks if s.intent == "uv-atlas") == 4
    assert (result.variants[0].mode, result.variants[0].combinations) == ("all", 12)
    found_in = {s.to_dict()["label"]: s.materials for s in result.variants[0].selections}
    assert "</World/Floor/Looks/M_tiles>" in found_in["floorVariant=Tiled"]
    assert "</World/Floor/Looks/M_tiles>" not in found_in[""]


def _many_sets(tmp_path: Path, n: int) -> Path:
    """``n`` prims with a variant set {a, b} each (2**n combinations); variant b of each defines
    a material; prim 0's variant b also holds a nested set {x, y} whose y defines one more."""
    prims = []
    for i in range(n):
        nested = ""
        if i == 0:
            nested = f'''(
                variants = {{ string inner = "x" }}
                prepend variantSets = "inner"
            ) {{
                variantSet "inner" = {{
                    "x" {{ }}
                    "y" {{ {material(f"/P{i}", "Inner", albedo="wood_color.png", rough="wood_roughness.png")}
                    }}
                }}
            '''
        else:
            nested = "{"
        prims.append(f'''
def Xform "P{i}" (
    variants = {{ string set{i} = "a" }}
    prepend variantSets = "set{i}"
) {{
    variantSet "set{i}" = {{
        "a" {{ }}
        "b" {nested}{material(f"/P{i}", "M", albedo="wood_color.png", rough="wood_roughness.png")}
        }}
    }}
}}''')
    path = tmp_path / "many.usda"
    path.write_text("#usda 1.0\n" + "".join(prims))
    return path


def test_a_space_over_the_limit_is_walked_one_set_at_a_time(tmp_path, capsys):
    n = 9  # 2**9 = 512 combinations (and more with the nested set)
    assert 2 ** n > MAX_COMBINATIONS
    result = scan_paths([_many_sets(tmp_path, n)])
    (explored,) = result.variants
    assert explored.mode == "each-set"
    # the stage's own selection, then each set's other variant, then the nested set's
    assert explored.combinations == 1 + n + 1
    assert "more than 256 combinations" in explored.note
    materials = {s.material for s in result.stacks}
    assert materials == {f"</P{i}/M>" for i in range(n)} | {"</P0/Inner>"}
    inner = next(s for s in result.stacks if s.material == "</P0/Inner>")
    assert inner.to_dict()["variant"] == "set0=b, inner=y"
    assert main(["scan", "--json", str(tmp_path / "many.usda")]) == 0
    payload = json.loads(capsys.readouterr().out)
    jsonschema.validate(payload, json_schema("scan"))
    assert payload["variants"][0]["mode"] == "each-set"
    assert main(["scan", str(tmp_path / "many.usda")]) == 0
    assert "explored one variant set at a time" in capsys.readouterr().out


def test_within_the_limit_every_combination_is_composed(tmp_path):
    result = scan_paths([_many_sets(tmp_path, 3)])
    (explored,) = result.variants
    # P0 {a, b{x, y}} x P1 {a, b} x P2 {a, b}: 3 x 2 x 2
    assert (explored.mode, explored.combinations) == ("all", 12)


@pytest.mark.parametrize("bound_in", ["nowhere", "other"])
def test_library_material_is_one_nothing_binds_in_any_selection(tmp_path, bound_in):
    binding = 'rel material:binding = </Set/Looks/Lib>' if bound_in == "other" else ""
    path = tmp_path / "lib.usda"
    path.write_text(f'''#usda 1.0
def Xform "Set" (
    variants = {{ string look = "plain" }}
    prepend variantSets = "look"
) {{
    def Scope "Looks" {{ {material("/Set/Looks", "Lib", albedo="wood_color.png", rough="wood_roughness.png")}
    }}
    def Mesh "Quad" {{
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
        texCoord2f[] primvars:st = [(0, 0), (3, 0), (3, 3), (0, 3)] (interpolation = "vertex")
    }}
    variantSet "look" = {{
        "plain" {{ }}
        "other" {{
            over "Quad" {{
                {binding}
            }}
        }}
    }}
}}''')
    (stack,) = scan_paths([path]).stacks
    if bound_in == "nowhere":
        reason = "no bound geometry in any of the 2 variant selections explored (a library material)"
        assert reason in stack.intent_reason
    else:
        assert "UVs 0.00-3.00 x 0.00-3.00 on </Set/Quad> in look=other: 3.00 x 3.00 periods" in stack.intent_reason
        assert "library" not in stack.intent_reason


def test_an_in_memory_stage_is_explored_without_being_changed():
    stage = Usd.Stage.Open(str(SHADING / "king.usda"))
    stage.GetSessionLayer().ImportFromString(
        '#usda 1.0\nover "King" (variants = { string shadingVariant = "Black" }) {}')
    before = stage.GetSessionLayer().ExportToString()
    result = scan_stage(stage)
    # the session layer's selection (Black) is the stage's own: White is the other selection
    black = next(s for s in result.stacks if s.material == "</King/Looks/M_king_black>")
    white = next(s for s in result.stacks if s.material == "</King/Looks/M_king_white>")
    assert "in shadingVariant" not in black.intent_reason
    assert "in shadingVariant=White" in white.intent_reason
    assert stage.GetSessionLayer().ExportToString() == before
    assert stage.GetPrimAtPath("/King").GetVariantSet("shadingVariant").GetVariantSelection() == "Black"


def test_a_variant_set_inside_an_instance_is_named_not_passed_over(tmp_path):
    """A studio prop whose shading variant set sits on a child prim (/Prop/Looks), referenced as an instance: the
    tiling material of its unselected variant was missed with no finding (an instance's prims take no selection of
    their own, so the set cannot be explored there); referenced plainly, it is found under that selection."""
    import shutil
    import sys

    from pxr import UsdGeom

    sys.path.insert(0, str(SAMPLES))
    from usdkit import bind, plane, preview_material

    shutil.copy(SAMPLES / "textures" / "cloth.png", tmp_path / "cloth.png")
    prop = Usd.Stage.CreateNew(str(tmp_path / "prop.usda"))
    prop.SetDefaultPrim(UsdGeom.Xform.Define(prop, "/Prop").GetPrim())
    plane(prop, "/Prop/Floor", 10, 4)
    looks = prop.DefinePrim("/Prop/Looks", "Scope").GetVariantSets().AddVariantSet("shadingVariant")
    for name in ("plain", "tiles"):
        looks.AddVariant(name)
    looks.SetVariantSelection("tiles")
    with looks.GetVariantEditContext():
        preview_material(prop, "/Prop/Looks/Tiles", {"diffuseColor": ("./cloth.png", "rgb", "sRGB")})
        bind(prop.GetPrimAtPath("/Prop/Floor"), "/Prop/Looks/Tiles")
    looks.SetVariantSelection("plain")
    prop.GetRootLayer().Save()
    for instanced in (True, False):
        scene = Usd.Stage.CreateNew(str(tmp_path / f"scene_{instanced}.usda"))
        for n in range(2):
            holder = scene.DefinePrim(f"/World/Prop{n}")
            holder.GetReferences().AddReference("./prop.usda")
            holder.SetInstanceable(instanced)
        scene.GetRootLayer().Save()
    instanced = scan_paths([tmp_path / "scene_True.usda"])
    [said] = [f for f in instanced.findings if f.code == "variant-in-instance"]
    assert said.where == "</World/Prop0/Looks>" and "'shadingVariant' (plain, tiles)" in said.message
    assert "inside the instance </World/Prop0> (and in 1 more instance of it)" in said.message
    plain = scan_paths([tmp_path / "scene_False.usda"])
    assert {s.material for s in plain.stacks} == {"</World/Prop0/Looks/Tiles>", "</World/Prop1/Looks/Tiles>"}
    assert not [f for f in plain.findings if f.code == "variant-in-instance"]
