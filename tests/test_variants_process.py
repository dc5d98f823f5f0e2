"""End to end on assets whose looks live in variants: every atlas is left alone with its reason
(the ones in selections the stage does not make included), the tiling floor is processed inside
its own variant, and the output stage is checked under each selection."""
from __future__ import annotations

import contextlib
import io
import itertools
import json
import shutil
from pathlib import Path

import jsonschema
import pytest
from pxr import Sdf, Usd, UsdShade
from runchecks import assert_all_written

from seamless_usd_cli.main import main
from seamless_usd_schemas import json_schema

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"
FLOOR_TEX = "/World/Floor/Looks/M_tiles/diffuseColorTex"
ATLAS_TEXTURES = {
    "/World/Teapot/Looks/M_utah/diffuseColorTex": "../textures/teapot_utah_atlas.png",
    "/World/Teapot/Looks/M_porcelain/diffuseColorTex": "../textures/teapot_porcelain_atlas.png",
    "/World/Teapot/Looks/M_porcelain/armTex": "../textures/teapot_porcelain_arm.png",
}


@pytest.fixture(scope="module")
def processed(tmp_path_factory):
    root = tmp_path_factory.mktemp("variants")
    for name in ("shading", "textures"):
        shutil.copytree(SAMPLES / name, root / name)
    before = {p: p.read_bytes() for p in (root / "shading").iterdir()}
    scene = root / "shading" / "set.usda"
    args = ["process", "--preset", "tiny", "--max-size", "128", "--cache-dir", str(root / "cache"), "--json",
            "--report", str(root / "report.html"), str(scene)]
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(args)
    return root, scene, code, json.loads(out.getvalue()), before


def _file(stage: Usd.Stage, prim: str) -> str | None:
    shader = UsdShade.Shader(stage.GetPrimAtPath(prim))
    if not shader:
        return None
    value = shader.GetInput("file").Get()
    return value.path if value else None


def test_atlases_are_left_alone_with_their_selection_named(processed):
    _, _, code, payload, _ = processed
    assert_all_written(code, payload)  # the exit code is the floor's verdict: 0 passed, 1 not passed
    jsonschema.validate(payload, json_schema("report"))
    by = {(s["material"], s["variant"]): s for s in payload["stacks"]}
    assert set(by) == {
        ("</World/Teapot/Looks/M_utah>", ""),
        ("</World/Teapot/Looks/M_porcelain>", "modelVariant=Fancy, shadingVariant=PorcelainFlowers"),
        ("</World/King/Looks/M_king_white>", ""),
        ("</World/King/Looks/M_king_black>", ""),
        ("</World/Floor/Looks/M_tiles>", "floorVariant=Tiled"),
    }
    for key, stack in by.items():
        if key[0] != "</World/Floor/Looks/M_tiles>":
            assert stack["status"] == "left-alone" and stack["intent"] == "uv-atlas", key
    assert "in shadingVariant=Black" in by[("</World/King/Looks/M_king_black>", "")]["message"]
    assert "in modelVariant=Fancy, shadingVariant=PorcelainFlowers" in by[
        ("</World/Teapot/Looks/M_porcelain>", "modelVariant=Fancy, shadingVariant=PorcelainFlowers")]["message"]
    floor = by[("</World/Floor/Looks/M_tiles>", "floorVariant=Tiled")]
    assert floor["status"] in ("passed", "not-passed") and floor["intent"] == "tiling"
    (explored,) = payload["variants"]
    assert explored["mode"] == "all" and explored["combinations"] == 12


def test_the_floor_is_edited_inside_its_variant_only(processed):
    root, scene, _, payload, before = processed
    assert {p: p.read_bytes() for p in before} == before  # sources untouched
    (written,) = payload["layers_written"]
    layer = Sdf.Layer.FindOrOpen(written)
    assert layer.GetPrimAtPath("/World/Floor{floorVariant=Tiled}Looks/M_tiles/diffuseColorTex")
    assert not layer.GetPrimAtPath("/World/Floor/Looks")  # nothing outside the variant
    assert not layer.GetPrimAtPath("/World/Teapot") and not layer.GetPrimAtPath("/World/King")
    sets = {"/World/Floor": ("floorVariant", ["Bare", "Tiled"]),
            "/World/King": ("shadingVariant", ["White", "Black"]),
            "/World/Teapot": ("modelVariant", ["Utah", "Fancy"])}
    for choice in itertools.product(*(names for _, names in sets.values())):
        stage = Usd.Stage.Open(written)
        for (prim, (vset, _)), variant in zip(sets.items(), choice):
            stage.GetPrimAtPath(prim).GetVariantSet(vset).SetVariantSelection(variant)
        if choice[2] == "Fancy":
            stage.GetPrimAtPath("/World/Teapot").GetVariantSet("shadingVariant").SetVariantSelection("PorcelainFlowers")
        floor = _file(stage, FLOOR_TEX)
        if choice[0] == "Bare":
            assert floor is None and not stage.GetPrimAtPath("/World/Floor/Looks")
        else:
            assert floor.startswith("./tileable/brick_albedo.") and stage.GetPrimAtPath(
                "/World/Floor/Looks/M_tiles/SeamlessUV")
        for prim, asset in ATLAS_TEXTURES.items():  # every atlas keeps its texture, in every selection
            assert _file(stage, prim) in (None, asset)
        binding = UsdShade.MaterialBindingAPI(stage.GetPrimAtPath("/World/King/Geom/Render"))
        assert binding.GetDirectBindingRel().GetTargets() == [
            Sdf.Path(f"/World/King/Looks/M_king_{choice[1].lower()}")]
    # the king's MaterialX document is not rewritten
    assert not list((root / "shading").glob("*.seamless.mtlx"))


def test_the_report_lists_the_selections_explored(processed):
    root, _, _, _, _ = processed
    html = (root / "report.html").read_text()
    assert "Variant selections explored" in html and "every combination explored (12)" in html
    assert "floorVariant=Tiled" in html and "modelVariant=Fancy, shadingVariant=PorcelainFlowers" in html


def test_in_place_edits_go_inside_the_variant_that_holds_the_material(processed, tmp_path, capsys):
    root, _, _, _, _ = processed
    for name in ("shading", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    scene = tmp_path / "shading" / "set.usda"
    main(["process", "--in-place", "--preset", "tiny", "--max-size", "128", "--cache-dir", str(root / "cache"),
          "--json", str(scene)])  # the model trained above is reused from the cache
    payload = json.loads(capsys.readouterr().out)
    assert [Path(p).name for p in payload["layers_written"]] == ["set.usda"]
    layer = Sdf.Layer.OpenAsAnonymous(str(scene))
    spec = layer.GetAttributeAtPath("/World/Floor{floorVariant=Tiled}Looks/M_tiles/diffuseColorTex.inputs:file")
    assert spec.default.path.startswith("./tileable/brick_albedo.")
    assert not layer.GetPrimAtPath("/World/Floor/Looks")
    stage = Usd.Stage.Open(str(scene))
    assert _file(stage, FLOOR_TEX) is None  # Bare, as the stage selects: untouched
    for name in ("teapot_mtl.usda", "king_look.usda", "king_mat.mtlx"):
        assert (tmp_path / "shading" / name).read_bytes() == (SAMPLES / "shading" / name).read_bytes()


def test_an_open_stage_is_not_edited_for_a_selection_it_does_not_make():
    from seamless_usd.authoring import MapResult, Provenance, StackResult, author_usd_stage
    from seamless_usd.discover import scan_stage

    stage = Usd.Stage.Open(str(SAMPLES / "prop" / "prop.usda"))  # as a DCC holds it: edited, not saved
    (cloth,) = [s for s in scan_stage(stage).stacks if s.selection]
    prov = Provenance(source_asset="", crop_size=(0, 0), uv_scale=(1.0, 1.0), q_passed=True, q_tau=0.0,
                      q_band_min=(0.0, 0.0), model_hash="", tool_version="test")
    result = author_usd_stage(stage, [StackResult(
        stack=cloth, maps=[MapResult(map=m, output_path=Path(m.resolved)) for m in cloth.maps],
        uv_scale=(2.0, 2.0), provenance=prov)])
    # (schema-not-registered: USD's registry may be built before the authoring was imported, by an earlier test)
    assert [f.code for f in result.findings if f.code != "schema-not-registered"] == ["variant-not-editable"]
    assert any("finish=cloth" in f.message for f in result.findings if f.code == "variant-not-editable")
    assert not result.edited_prims and not any(layer.dirty for layer in stage.GetUsedLayers())


def test_a_dcc_stage_names_the_stacks_of_other_selections_and_plans_its_own(tmp_path):
    import seamless_usd
    from seamless_usd.authoring import WriteMode

    stage = Usd.Stage.Open(str(SAMPLES / "prop" / "prop.usda"))
    options = seamless_usd.Options(preset="tiny", mode=WriteMode.DRY_RUN, output_dir=tmp_path / "tiles",
                                   cache_dir=tmp_path / "cache")
    report = seamless_usd.process_stage(stage, options)
    (skipped,) = [f for f in report.findings if f.code == "variant-not-editable"]
    assert skipped.where == "</Prop/Materials/M_floor>" and "finish=cloth" in skipped.message
    floors = [s for s in report.stacks if s.material == "</Prop/Materials/M_floor>"]
    assert [(s.variant, s.status.value) for s in floors] == [("", "planned")]
    assert report.variants and report.variants[0]["combinations"] == 2


def test_an_open_stage_is_edited_inside_the_variant_that_holds_the_material(tmp_path):
    """A DCC stage's edits (its root layer, the default edit target) go inside the variant whose opinion they
    replace: the other selection keeps its own texture."""
    from seamless_usd.authoring import MapResult, Provenance, StackResult, author_usd_stage
    from seamless_usd.discover import scan_stage

    for name in ("prop", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    stage = Usd.Stage.Open(str(tmp_path / "prop" / "prop.usda"))
    vset = stage.GetPrimAtPath("/Prop").GetVariantSet("finish")
    assert vset.GetVariantSelection() == "wood"
    floor = [s for s in scan_stage(stage).stacks if not s.selection and s.material == "</Prop/Materials/M_floor>"]
    prov = Provenance(source_asset="", crop_size=(0, 0), uv_scale=(1.0, 1.0), q_passed=True, q_tau=0.0,
                      q_band_min=(0.0, 0.0), model_hash="", tool_version="test")
    tile = Path(floor[0].maps[0].resolved).with_name("wood_color.tile.png")
    shutil.copy(floor[0].maps[0].resolved, tile)
    result = author_usd_stage(stage, [StackResult(stack=floor[0], maps=[MapResult(map=m, output_path=tile)
                                                                         for m in floor[0].maps],
                                                  uv_scale=(2.0, 2.0), provenance=prov)])
    assert result.edited_prims and not [f for f in result.findings if f.code != "schema-not-registered"]
    files = {}
    for selection in ("wood", "cloth"):
        vset.SetVariantSelection(selection)
        files[selection] = stage.GetAttributeAtPath("/Prop/Materials/M_floor/diffuseColorTex.inputs:file").Get().path
    assert files == {"wood": "../textures/wood_color.tile.png", "cloth": "../textures/cloth.png"}
    root = stage.GetRootLayer()
    assert root.GetPrimAtPath("/Prop{finish=wood}Materials/M_floor/diffuseColorTex") is not None


def test_check_judges_the_stack_of_a_selection_the_stage_does_not_make():
    """The floor under finish=cloth uses the same file as a clamped label (not judged): it is judged itself, and
    named with its selection."""
    from seamless_usd.pipeline.check import check_paths

    names = [i.name for i in check_paths([SAMPLES / "prop" / "prop.usda"]).items]
    assert names == ["</Prop/Materials/M_floor>", "</Prop/Materials/M_floor> in finish=cloth"]


def test_a_dry_run_plan_names_the_variant_each_edit_goes_into(tmp_path, capsys):
    for name in ("prop", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    assert main(["process", str(tmp_path / "prop" / "prop.usda"), "--dry-run"]) == 0
    plan = [line for line in capsys.readouterr().err.splitlines() if "diffuseColorTex.inputs:file>" in line]
    assert len(plan) == 2 and {line.rsplit("inside variant ", 1)[1] for line in plan} == {
        "{finish=wood} of </Prop>", "{finish=cloth} of </Prop>"}
    assert all("tileable/" in line for line in plan)


def test_in_place_edits_of_a_texture_whose_file_each_variant_sets_stay_inside_each_variant(tmp_path, capsys):
    """The prop's floor texture is defined once, its file set inside each variant of ``finish`` (cloth, wood) in the
    same layer: in place, each variant's new file goes inside that variant, so each selection shows its own tile
    (the edits went to the texture's definition, above every variant, and both showed the cloth's tile). Its ``st``
    is connected once, outside the variants (a connection inside one would lose to it): the UV scale node goes
    there, and each variant's own scale inside that variant."""
    for name in ("prop", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    scene = tmp_path / "prop" / "prop.usda"
    main(["process", "--in-place", "--preset", "tiny", "--seeds", "1", "--max-size", "128", "--cache-dir",
          str(tmp_path / "cache"), "--json", str(scene)])
    payload = json.loads(capsys.readouterr().out)
    floor = {s["variant"]: s for s in payload["stacks"] if s["material"] == "</Prop/Materials/M_floor>"}
    stage = Usd.Stage.Open(str(scene), Usd.Stage.LoadAll)
    stage.SetEditTarget(stage.GetSessionLayer())  # selections looked at, the file itself left as it is on disk
    finish = stage.GetPrimAtPath("/Prop").GetVariantSets().GetVariantSet("finish")
    assert len(floor) == 2 and all(s["status"] in ("passed", "not-passed") for s in floor.values()), floor
    scales = {}
    for selection, source in (("cloth", "cloth"), ("wood", "wood_color")):
        finish.SetVariantSelection(selection)
        value = _file(stage, "/Prop/Materials/M_floor/diffuseColorTex")
        assert value is not None and Path(value).name.startswith(f"{source}.Prop_Materials_M_floor-"), (selection, value)
        [stack] = [s for s in floor.values() if Path(s["maps"][0]["asset"]).stem == source]
        scales[selection] = _uv_scale(stage, "/Prop/Materials/M_floor/diffuseColorTex")
        assert scales[selection] == pytest.approx(stack["uv_scale"], rel=1e-5), (selection, scales)
    assert scales["cloth"] != pytest.approx(scales["wood"]), scales  # each variant's own
    assert not [f for f in payload["findings"] if f["code"] == "edit-not-composed"]
    # check reads each variant's tile against that variant's recorded source, and agrees with the run
    main(["check", "--json", str(scene)])
    items = {i["name"]: i for i in json.loads(capsys.readouterr().out)["items"] if "M_floor" in i["name"]}
    for variant, stack in floor.items():
        item = items["</Prop/Materials/M_floor>" + (f" in {variant}" if variant else "")]
        assert not item["note"] and item["passed"] == (stack["status"] == "passed"), (item, stack["status"])


def _uv_scale(stage: Usd.Stage, prim: str) -> tuple:
    """The scale of the UV node this tool inserted before the texture ``prim``, as the stage composes it."""
    st = UsdShade.Shader(stage.GetPrimAtPath(prim)).GetInput("st").GetConnectedSources()[0][0].source.GetPrim()
    from seamless_usd.authoring.schema import is_seamless_uv_transform

    # read as the product reads it: a stage opened before the schema was registered (an earlier test) lists it in
    # its apiSchemas only, not among the schemas the registry knows
    assert st.GetName().startswith("SeamlessUV") and is_seamless_uv_transform(st), st
    return tuple(UsdShade.Shader(st).GetInput("scale").Get())


def test_a_uv_scale_where_st_is_connected_outside_the_variant_is_composed_in_a_new_layer(tmp_path, capsys):
    """A material whose texture file is set inside variants while its ``st`` connection is authored outside them, in
    the root layer: a connection made inside the variant would lose to it (the tile at the wrong scale), so the new
    layer connects ``st`` outside the variant and sets the scale inside it."""
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    (tmp_path / "scene.usda").write_text('''#usda 1.0
(
    defaultPrim = "World"
)

def Xform "World"
{
    def Scope "Looks" (
        variants = {
            string look = "brick"
        }
        prepend variantSets = "look"
    )
    {
        def Material "Base"
        {
            token outputs:surface.connect = </World/Looks/Base/Surface.outputs:surface>

            def Shader "Surface"
            {
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor.connect = </World/Looks/Base/Albedo.outputs:rgb>
                token outputs:surface
            }

            def Shader "St"
            {
                uniform token info:id = "UsdPrimvarReader_float2"
                string inputs:varname = "st"
                float2 outputs:result
            }

            def Shader "Albedo"
            {
                uniform token info:id = "UsdUVTexture"
                float2 inputs:st.connect = </World/Looks/Base/St.outputs:result>
                float3 outputs:rgb
            }
        }
        variantSet "look" = {
            "brick" {
                over "Base"
                {
                    over "Albedo"
                    {
                        asset inputs:file = @./textures/brick_albedo.png@
                    }
                }
            }
        }
    }
}
''')
    code = main(["process", "--preset", "tiny", "--seeds", "1", "--max-size", "128", "--force", "--cache-dir",
                 str(tmp_path / "cache"), "--json", str(tmp_path / "scene.usda")])
    payload = json.loads(capsys.readouterr().out)
    [stack] = payload["stacks"]
    assert stack["status"] in ("passed", "not-passed") and code == payload["exit_code"], stack
    stage = Usd.Stage.Open(str(tmp_path / "scene.seamless.usda"))
    assert _uv_scale(stage, "/World/Looks/Base/Albedo") == pytest.approx(stack["uv_scale"], rel=1e-5)
    assert stack["uv_scale"] != pytest.approx([1.0, 1.0])
