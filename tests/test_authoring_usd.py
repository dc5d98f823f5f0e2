"""Authoring into USD stages written by the tests: paths, wrap, UV composition, modes, re-runs."""
from __future__ import annotations

import hashlib
import math
import shutil
from pathlib import Path

import pytest
from pxr import Sdf, Usd, UsdShade

from seamless_usd.authoring import (
    Affine2,
    MapResult,
    Provenance,
    Schema,
    StackResult,
    WriteMode,
    author_usd,
    author_usd_stage,
    read_provenance,
    scale2d,
    transform2d,
    uv_affine,
    uv_scale_for,
)
from seamless_usd.textures import (
    AuthoredAt,
    ColorSpace,
    Origin,
    RoleUse,
    TextureMap,
    TextureStack,
    UVChain,
)
from seamless_usd.findings import Severity

ALBEDO = "textures/brick albedo é.png"  # spaces and non-ASCII on purpose
NORMAL = "textures/brick_normal.png"
PLAIN = "textures/plain.png"
LOOKS = "/World/Looks"
BRICK = f"{LOOKS}/Brick"
PLAIN_MAT = f"{LOOKS}/Plain"
WORKING, CROP = (1024, 512), (128, 64)  # -> uv scale (4, 4)
ROTATION, TRANSLATION, SCALE = 30.0, (0.25, -0.5), (2.0, 0.5)

LOOKS_LAYER = f"""#usda 1.0
over "World"
{{
    over "Looks"
    {{
        def Material "Brick"
        {{
            asset inputs:albedoFile = @{ALBEDO}@
            float inputs:uvRotation = {ROTATION}
            float2 inputs:uvTranslation = {TRANSLATION}
            token outputs:surface.connect = <{BRICK}/Surface.outputs:surface>

            def Shader "Surface"
            {{
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor.connect = <{BRICK}/Albedo.outputs:rgb>
                normal3f inputs:normal.connect = <{BRICK}/Normal.outputs:rgb>
                token outputs:surface
            }}
            def Shader "Reader"
            {{
                uniform token info:id = "UsdPrimvarReader_float2"
                string inputs:varname = "st"
                float2 outputs:result
            }}
            def Shader "Place"
            {{
                uniform token info:id = "UsdTransform2d"
                float2 inputs:in.connect = <{BRICK}/Reader.outputs:result>
                float inputs:rotation.connect = <{BRICK}.inputs:uvRotation>
                float2 inputs:scale = {SCALE}
                float2 inputs:translation.connect = <{BRICK}.inputs:uvTranslation>
                float2 outputs:result
            }}
            def Shader "Albedo"
            {{
                uniform token info:id = "UsdUVTexture"
                asset inputs:file.connect = <{BRICK}.inputs:albedoFile>
                float2 inputs:st.connect = <{BRICK}/Place.outputs:result>
                token inputs:wrapS = "clamp"
                float3 outputs:rgb
            }}
            def Shader "Normal"
            {{
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @{NORMAL}@
                float2 inputs:st.connect = <{BRICK}/Place.outputs:result>
                float4 inputs:scale = (2, 2, 2, 1)
                float4 inputs:bias = (-1, -1, -1, 0)
                float3 outputs:rgb
            }}
        }}
        def Material "Plain"
        {{
            token outputs:surface.connect = <{PLAIN_MAT}/Surface.outputs:surface>
            def Shader "Surface"
            {{
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor.connect = <{PLAIN_MAT}/Tex.outputs:rgb>
                token outputs:surface
            }}
            def Shader "Reader"
            {{
                uniform token info:id = "UsdPrimvarReader_float2"
                string inputs:varname = "st"
                float2 outputs:result
            }}
            def Shader "Tex"
            {{
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @{PLAIN}@
                float2 inputs:st.connect = <{PLAIN_MAT}/Reader.outputs:result>
                float3 outputs:rgb
            }}
        }}
    }}
}}
"""

ROOT_LAYER = """#usda 1.0
(
    defaultPrim = "World"
    subLayers = [@./looks.usda@]
)
def Xform "World"
{
    def Scope "Looks"
    {
    }
}
"""


@pytest.fixture()
def scene(tmp_path: Path) -> Path:
    """``scene.usda`` sublayering ``looks.usda`` (the materials), textures and tileable outputs."""
    (tmp_path / "scene.usda").write_text(ROOT_LAYER, encoding="utf-8")
    (tmp_path / "looks.usda").write_text(LOOKS_LAYER, encoding="utf-8")
    for rel in (ALBEDO, NORMAL, PLAIN):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_bytes(b"source " + rel.encode())
    for name in ("brick_albedo_tile.png", "brick_normal_tile.png", "plain_tile.png"):
        (tmp_path / "tileable").mkdir(exist_ok=True)
        (tmp_path / "tileable" / name).write_bytes(b"tile " + name.encode())
    return tmp_path / "scene.usda"


def provenance(source: str, scale=(4.0, 4.0)) -> Provenance:
    return Provenance(source_asset=source, crop_size=CROP, uv_scale=scale, q_passed=True,
                      q_tau=0.42, q_band_min=(0.5, 0.6), model_hash="abc123", tool_version="0.1.0")


def texture_map(root: Path, material: str, node: str, asset: str, file_at: AuthoredAt,
                resolved: Path | None = None) -> TextureMap:
    """A map as discovery describes it (built by hand: discovery is tested on its own)."""
    return TextureMap(
        material=f"<{material}>", node=node, node_type="UsdUVTexture", origin=Origin.USD,
        asset=asset, resolved=str(resolved or root / asset),
        file_at=file_at, roles=(RoleUse("diffuseColor", "rgb", f"<{material}/Surface.inputs:diffuseColor>"),),
        color_space=ColorSpace.SRGB, color_space_reason="test",
        uv=UVChain("st", f"{material}/Reader", (), connected_from=f"{material}/Reader.outputs:result"),
    )


def brick_result(root: Path, scale=None, albedo_resolved: Path | None = None) -> StackResult:
    scale = scale or uv_scale_for(WORKING, CROP)
    layer = str(root / "looks.usda")
    albedo = texture_map(root, BRICK, f"{BRICK}/Albedo", ALBEDO,
                         AuthoredAt(BRICK, "inputs:albedoFile", layer), albedo_resolved)
    normal = texture_map(root, BRICK, f"{BRICK}/Normal", NORMAL,
                         AuthoredAt(f"{BRICK}/Normal", "inputs:file", layer))
    stack = TextureStack(BRICK, albedo.uv, (albedo, normal))
    maps = [MapResult(albedo, root / "tileable" / "brick_albedo_tile.png"),
            MapResult(normal, root / "tileable" / "brick_normal_tile.png")]
    return StackResult(stack, maps, scale, provenance(ALBEDO, scale))


def plain_result(root: Path, scale=(4.0, 4.0)) -> StackResult:
    tex = texture_map(root, PLAIN_MAT, f"{PLAIN_MAT}/Tex", PLAIN,
                      AuthoredAt(f"{PLAIN_MAT}/Tex", "inputs:file", str(root / "looks.usda")))
    return StackResult(TextureStack(PLAIN_MAT, tex.uv, (tex,)),
                       [MapResult(tex, root / "tileable" / "plain_tile.png")], scale, provenance(PLAIN, scale))


def hashes(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def texel_offsets_match(old: Affine2, new: Affine2, working=WORKING, crop=CROP) -> None:
    """Texel offsets between sample points are the same in the source and in the 2c tile."""
    points = [(0.0, 0.0), (0.1, 0.7), (0.93, 0.25), (0.5, 0.5), (-0.3, 1.6)]
    for p in points:
        for q in points:
            (op, oq), (np_, nq) = (old(p), old(q)), (new(p), new(q))
            for axis in range(2):
                source_texels = (op[axis] - oq[axis]) * working[axis]
                tile_texels = (np_[axis] - nq[axis]) * 2 * crop[axis]
                assert tile_texels == pytest.approx(source_texels, abs=1e-6)


def uv_nodes(stage: Usd.Stage) -> list[Usd.Prim]:
    return [p for p in stage.Traverse()
            if UsdShade.Shader(p) and UsdShade.Shader(p).GetShaderId() == "UsdTransform2d"]


# ---------------------------------------------------------------------------------------------


def test_uv_scale_for_values():
    assert uv_scale_for((1024, 512), (128, 64)) == (4.0, 4.0)
    assert uv_scale_for((300, 200), (100, 100)) == (1.5, 1.0)
    with pytest.raises(ValueError):
        uv_scale_for((0, 10), (1, 1))


def test_transform2d_matches_spec_order():
    # scale, then rotate counter-clockwise, then translate
    f = transform2d((2.0, 0.5), 90.0, (1.0, 0.0))
    assert f((1.0, 0.0)) == pytest.approx((1.0, 2.0))
    assert f((0.0, 1.0)) == pytest.approx((0.5, 0.0))


def test_uv_points_without_existing_transform(scene: Path):
    result = author_usd(scene, [plain_result(scene.parent)])
    old = uv_affine(Usd.Stage.Open(str(scene)), f"{PLAIN_MAT}/Tex")
    new = uv_affine(Usd.Stage.Open(str(result.output)), f"{PLAIN_MAT}/Tex")
    assert old.close_to(Affine2())
    assert new.close_to(scale2d((4.0, 4.0)))
    texel_offsets_match(old, new)


def test_uv_points_with_rotated_translated_transform_on_interface_inputs(scene: Path):
    result = author_usd(scene, [brick_result(scene.parent)])
    old_stage, new_stage = Usd.Stage.Open(str(scene)), Usd.Stage.Open(str(result.output))
    for tex in ("Albedo", "Normal"):
        old = uv_affine(old_stage, f"{BRICK}/{tex}")
        new = uv_affine(new_stage, f"{BRICK}/{tex}")
        # by hand: st -> R(30deg) diag(2, 0.5) st + (0.25, -0.5), then diag(4, 4)
        c, s = math.cos(math.radians(ROTATION)), math.sin(math.radians(ROTATION))
        by_hand = Affine2(2 * c, -0.5 * s, 2 * s, 0.5 * c, *TRANSLATION)
        assert old.close_to(by_hand)
        assert new.close_to(by_hand.then(scale2d((4.0, 4.0))))
        texel_offsets_match(old, new)
    # the existing chain and its interface inputs are untouched; one transform was added
    brick = new_stage.GetPrimAtPath(BRICK)
    assert brick.GetAttribute("inputs:uvRotation").Get() == pytest.approx(ROTATION)
    assert len(uv_nodes(new_stage)) == len(uv_nodes(old_stage)) + 1


def test_non_uniform_scale_after_rotation_is_exact(scene: Path):
    scale = uv_scale_for((1024, 256), (64, 64))  # (8, 2): cannot fold into the rotated node
    result = author_usd(scene, [brick_result(scene.parent, scale=scale)])
    old = uv_affine(Usd.Stage.Open(str(scene)), f"{BRICK}/Albedo")
    new = uv_affine(Usd.Stage.Open(str(result.output)), f"{BRICK}/Albedo")
    assert new.close_to(old.then(scale2d(scale)))
    texel_offsets_match(old, new, working=(1024, 256), crop=(64, 64))


def test_new_layer_keeps_sources_and_resolves_relative_paths(scene: Path):
    root = scene.parent
    before = hashes(root)
    result = author_usd(scene, [brick_result(root), plain_result(root)])
    assert result.output == root / "scene.seamless.usda"
    assert result.layers_written == [result.output]
    assert {k: v for k, v in hashes(root).items() if k in before} == before
    layer = Sdf.Layer.FindOrOpen(str(result.output))
    assert layer.subLayerPaths == ["./scene.usda"]
    # the interface input is edited where it is authored, not on the texture node
    authored = layer.GetAttributeAtPath(f"{BRICK}.inputs:albedoFile").default
    assert authored.path == "./tileable/brick_albedo_tile.png"
    assert not layer.GetAttributeAtPath(f"{BRICK}/Albedo.inputs:file")
    stage = Usd.Stage.Open(str(result.output))
    for node, name in (("Albedo", "brick_albedo_tile.png"), ("Normal", "brick_normal_tile.png")):
        file_input = UsdShade.Shader(stage.GetPrimAtPath(f"{BRICK}/{node}")).GetInput("file")
        attr = file_input.GetValueProducingAttributes()[0]
        assert Path(attr.Get().resolvedPath) == (root / "tileable" / name).resolve()
    assert sorted(result.edited_prims) == sorted(
        [f"<{BRICK}/Albedo>", f"<{BRICK}/Normal>", f"<{PLAIN_MAT}/Tex>"])


def test_wrap_modes_and_provenance(scene: Path):
    result = author_usd(scene, [brick_result(scene.parent)])
    stage = Usd.Stage.Open(str(result.output))
    for tex in ("Albedo", "Normal"):
        prim = stage.GetPrimAtPath(f"{BRICK}/{tex}")
        assert prim.GetAttribute("inputs:wrapS").Get() == "repeat"
        assert prim.GetAttribute("inputs:wrapT").Get() == "repeat"
        assert prim.HasAPI(Schema.TILE_API)
        recorded = read_provenance(prim)
        assert recorded.uv_scale == (4.0, 4.0)
        assert recorded.crop_size == CROP and recorded.q_passed and recorded.model_hash == "abc123"
        assert prim.GetAttribute(Schema.Q_TAU).Get() == pytest.approx(0.42)
    (added,) = [p for p in uv_nodes(stage) if p.GetName() == "SeamlessUV"]
    assert added.HasAPI(Schema.UV_TRANSFORM_API)


def test_rerun_from_source_is_a_no_op(scene: Path):
    root = scene.parent
    first = author_usd(scene, [brick_result(root)])
    text = first.output.read_text(encoding="utf-8")
    again = author_usd(first.output, [brick_result(root)])
    assert again.layers_written == [] and not again.plan
    assert any(f.code == "already-up-to-date" for f in again.findings)
    # overwriting the first output from the original is a clean re-run with the same content
    rewritten = author_usd(scene, [brick_result(root)])
    assert rewritten.output.read_text(encoding="utf-8") == text


def test_rerun_on_processed_tile_updates_the_added_transform(scene: Path):
    root = scene.parent
    first = author_usd(scene, [brick_result(root)])
    # the pipeline processed the tile itself: its result composes with the first scale
    tile = root / "tileable" / "brick_albedo_tile.png"
    second = author_usd(first.output, [brick_result(root, scale=(2.0, 1.0), albedo_resolved=tile)])
    stage = Usd.Stage.Open(str(second.output))
    old = uv_affine(Usd.Stage.Open(str(scene)), f"{BRICK}/Albedo")
    new = uv_affine(stage, f"{BRICK}/Albedo")
    assert new.close_to(old.then(scale2d((8.0, 4.0))))
    assert len(uv_nodes(stage)) == 2  # Place + one SeamlessUV: never a duplicated chain
    albedo = stage.GetPrimAtPath(f"{BRICK}/Albedo")
    assert read_provenance(albedo).uv_scale == (8.0, 4.0)
    assert read_provenance(albedo).source_asset == f"./{ALBEDO}"  # the origin is kept


def test_in_place_edits_opinion_layers_with_backups(scene: Path):
    root = scene.parent
    originals = {name: (root / name).read_bytes() for name in ("scene.usda", "looks.usda")}
    old = uv_affine(Usd.Stage.Open(str(scene)), f"{BRICK}/Albedo")
    result = author_usd(scene, [brick_result(root)], mode=WriteMode.IN_PLACE)
    looks = root / "looks.usda"
    assert result.layers_written == [looks]  # only the changed layer is saved
    assert result.backups == [root / "looks.usda.bak"]
    assert (root / "looks.usda.bak").read_bytes() == originals["looks.usda"]
    assert (root / "scene.usda").read_bytes() == originals["scene.usda"]
    assert not (root / "scene.usda.bak").exists()
    layer = Sdf.Layer.OpenAsAnonymous(str(looks))
    assert layer.GetAttributeAtPath(f"{BRICK}.inputs:albedoFile").default.path == \
        "./tileable/brick_albedo_tile.png"
    stage = Usd.Stage.Open(str(scene))
    new = uv_affine(stage, f"{BRICK}/Albedo")
    assert new.close_to(old.then(scale2d((4.0, 4.0))))
    # a second in-place run changes nothing and keeps the first backup
    again = author_usd(scene, [brick_result(root)], mode=WriteMode.IN_PLACE)
    assert again.layers_written == []
    assert (root / "looks.usda.bak").read_bytes() == originals["looks.usda"]


def test_an_in_place_edit_never_goes_without_a_backup_of_what_it_replaces(scene: Path):
    """A ``looks.usda.bak`` of the user's own (or one a stopped run left, from before the layer changed) was taken
    for the backup: the layer was edited, the JSON named that .bak, and what the edit replaced was nowhere. The edit
    now gets a backup of its own beside it, and the .bak there is left as it was."""
    root = scene.parent
    theirs = b"#usda 1.0\n# the user's own notes\n"
    (root / "looks.usda.bak").write_bytes(theirs)
    before = (root / "looks.usda").read_bytes()
    result = author_usd(scene, [brick_result(root)], mode=WriteMode.IN_PLACE)
    assert result.layers_written == [root / "looks.usda"]
    assert result.backups == [root / "looks.usda.1.bak"]
    assert (root / "looks.usda.1.bak").read_bytes() == before and (root / "looks.usda.bak").read_bytes() == theirs


def test_dry_run_writes_nothing(scene: Path):
    root = scene.parent
    before = hashes(root)
    result = author_usd(scene, [brick_result(root)], mode=WriteMode.DRY_RUN)
    assert result.dry_run and result.layers_written == []
    assert hashes(root) == before
    assert any("inputs:albedoFile" in line and "brick_albedo_tile.png" in line for line in result.plan)
    assert any("SeamlessUV" in line for line in result.plan)


def test_open_in_memory_stage(tmp_path: Path, scene: Path):
    root = scene.parent
    stage = Usd.Stage.CreateInMemory()
    stage.GetRootLayer().ImportFromString(LOOKS_LAYER.replace('over "World"', 'def Xform "World"')
                                          .replace('over "Looks"', 'def Scope "Looks"'))
    before = hashes(root)
    result = author_usd_stage(stage, [brick_result(root)], anchor_dir=root)
    assert hashes(root) == before  # nothing saved
    albedo = stage.GetPrimAtPath(f"{BRICK}/Albedo")
    assert albedo.HasAPI(Schema.TILE_API)
    assert stage.GetPrimAtPath(BRICK).GetAttribute("inputs:albedoFile").Get().path == \
        "./tileable/brick_albedo_tile.png"
    assert uv_affine(stage, f"{BRICK}/Albedo").close_to(
        transform2d(SCALE, ROTATION, TRANSLATION).then(scale2d((4.0, 4.0))))
    assert not [f for f in result.findings if f.severity is Severity.ERROR]
    # into the session layer instead, with an anonymous layer and no anchor: absolute + a finding
    plain = Usd.Stage.CreateInMemory()
    plain.GetRootLayer().ImportFromString(LOOKS_LAYER.replace('over "World"', 'def Xform "World"')
                                          .replace('over "Looks"', 'def Scope "Looks"'))
    res2 = author_usd_stage(plain, [plain_result(root)], edit_target_layer=plain.GetSessionLayer())
    assert plain.GetSessionLayer().GetAttributeAtPath(f"{PLAIN_MAT}/Tex.inputs:file")
    said = [f for f in res2.findings if f.code == "absolute-asset-path"]
    assert len(said) == 1 and "save it to a file first" in said[0].message  # once, not for each map


def test_an_edit_a_stronger_layer_hides_is_named_not_passed_off(tmp_path: Path, scene: Path):
    """Edits into a sublayer of a root layer that sets the same values lose to it: each such texture node is
    recorded as not written, with a finding naming the layer that holds the stronger value."""
    root = scene.parent
    stage = Usd.Stage.CreateInMemory()
    stage.GetRootLayer().ImportFromString(LOOKS_LAYER.replace('over "World"', 'def Xform "World"')
                                          .replace('over "Looks"', 'def Scope "Looks"'))
    weaker = Sdf.Layer.CreateAnonymous(".usda")
    stage.GetRootLayer().subLayerPaths.insert(0, weaker.identifier)
    result = author_usd_stage(stage, [brick_result(root)], edit_target_layer=weaker, anchor_dir=root)
    hidden = [f for f in result.findings if f.code == "edit-not-composed"]
    assert hidden and all(f.severity is Severity.ERROR and "holds a stronger value" in f.message for f in hidden)
    assert f"<{BRICK}/Albedo>" in result.unwritten_nodes()
    # over the scene instead (a new root layer that sublayers it): the edits compose
    over = Sdf.Layer.CreateAnonymous(".usda")
    over.subLayerPaths.append(stage.GetRootLayer().identifier)
    top = Usd.Stage.Open(over)
    result = author_usd_stage(top, [brick_result(root)], anchor_dir=root)
    assert not result.unwritten_nodes() and not [f for f in result.findings if f.severity is Severity.ERROR]
    assert top.GetPrimAtPath(BRICK).GetAttribute("inputs:albedoFile").Get().path == "./tileable/brick_albedo_tile.png"


def test_shared_texture_node_is_edited_once(scene: Path):
    root = scene.parent
    brick = brick_result(root)
    albedo = brick.maps[0].map
    from dataclasses import replace

    other = replace(albedo, material="</World/Looks/Other>")
    conflicting = StackResult(TextureStack("</World/Looks/Other>", other.uv, (other,)),
                              [MapResult(other, root / "tileable" / "plain_tile.png")],
                              (2.0, 2.0), provenance(ALBEDO, (2.0, 2.0)))
    result = author_usd(scene, [brick, conflicting])
    assert [f.code for f in result.findings] == ["shared-texture-conflict"]
    stage = Usd.Stage.Open(str(result.output))
    assert read_provenance(stage.GetPrimAtPath(f"{BRICK}/Albedo")).uv_scale == (4.0, 4.0)


def test_usdz_new_layer_beside_it_and_in_place_skipped(scene: Path):
    from pxr import UsdUtils

    root = scene.parent
    flat = root / "flat.usda"
    Usd.Stage.Open(str(scene)).Export(str(flat))
    package = root / "scene.usdz"
    assert UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(flat)), str(package))
    before = package.read_bytes()
    skipped = author_usd(package, [plain_result(root)], mode=WriteMode.IN_PLACE)
    assert [f.code for f in skipped.findings] == ["in-package"] and not skipped.layers_written
    result = author_usd(package, [plain_result(root)])
    assert result.output == root / "scene.usdz.seamless.usda"  # scene.usda beside it keeps scene.seamless.usda
    assert package.read_bytes() == before
    stage = Usd.Stage.Open(str(result.output))
    tex = stage.GetPrimAtPath(f"{PLAIN_MAT}/Tex")
    assert Path(tex.GetAttribute("inputs:file").Get().resolvedPath) == (root / "tileable" / "plain_tile.png").resolve()
    assert uv_affine(stage, f"{PLAIN_MAT}/Tex").close_to(scale2d((4.0, 4.0)))


def test_dry_run_of_in_place_plans_opinion_layers(scene: Path):
    root = scene.parent
    before = hashes(root)
    result = author_usd(scene, [brick_result(root)], mode=WriteMode.DRY_RUN, plan_mode=WriteMode.IN_PLACE)
    assert hashes(root) == before and result.dry_run and not result.backups
    assert result.plan and all("looks.usda" in line for line in result.plan)
    assert Sdf.Layer.Find(str(root / "looks.usda")) is None or not Sdf.Layer.Find(str(root / "looks.usda")).dirty


def test_missing_output_file_and_unreadable_stage(scene: Path):
    from seamless_usd.errors import InputError

    root = scene.parent
    (root / "tileable" / "plain_tile.png").unlink()
    result = author_usd(scene, [plain_result(root), brick_result(root)])
    assert [f.code for f in result.findings] == ["missing-output"]
    assert f"<{BRICK}/Albedo>" in result.edited_prims  # the rest went on
    with pytest.raises(InputError):
        author_usd(root / "missing.usda", [plain_result(root)])
    (root / "broken.usda").write_text("#usda 1.0\ndef (((", encoding="utf-8")
    with pytest.raises(InputError):
        author_usd(root / "broken.usda", [plain_result(root)])


@pytest.mark.parametrize("name, magic", [("looks.usdc", b"PXR-USDC"), ("looks.usd", b"#usda")])
def test_in_place_keeps_the_layer_format(scene: Path, name: str, magic: bytes):
    root = scene.parent
    crate = root / name
    if name.endswith(".usd"):  # a .usd file holding text stays text
        crate.write_text(LOOKS_LAYER, encoding="utf-8")
    else:
        Sdf.Layer.FindOrOpen(str(root / "looks.usda")).Export(str(crate))
    (root / "scene.usda").write_text(ROOT_LAYER.replace("looks.usda", name), encoding="utf-8")
    results = [brick_result(root)]
    for r in results:  # discovery would report the crate layer as the opinion's layer
        for m in r.maps:
            object.__setattr__(m.map.file_at, "layer", str(crate))
    result = author_usd(scene, results, mode=WriteMode.IN_PLACE)
    assert result.layers_written == [crate]
    assert crate.read_bytes().startswith(magic)
    stage = Usd.Stage.Open(str(scene))
    assert stage.GetPrimAtPath(f"{BRICK}/Albedo").HasAPI(Schema.TILE_API)


def test_in_place_skips_opinions_inside_a_package(scene: Path):
    from pxr import UsdUtils

    root = scene.parent
    flat = root / "flat.usda"
    Usd.Stage.Open(str(scene)).Export(str(flat))
    assert UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(flat)), str(root / "looks.usdz"))
    (root / "outer.usda").write_text(
        '#usda 1.0\n(\n    subLayers = [@./looks.usdz@]\n)\n', encoding="utf-8")
    before = hashes(root)
    result = author_usd(root / "outer.usda", [plain_result(root)], mode=WriteMode.IN_PLACE)
    assert {f.code for f in result.findings} == {"in-package"}
    assert result.layers_written == [] and hashes(root) == before


TILED_LAYER = """#usda 1.0
def Material "Mat"
{
    token outputs:mtlx:surface.connect = </Mat/Surface.outputs:out>
    float2 inputs:tiling = (2, 2)
    def Shader "Surface"
    {
        uniform token info:id = "ND_standard_surface_surfaceshader"
        color3f inputs:base_color.connect = </Mat/Tiled.outputs:out>
        token outputs:out
    }
    def Shader "Coords"
    {
        uniform token info:id = "ND_texcoord_vector2"
        float2 outputs:out
    }
    def Shader "Tiled"
    {
        uniform token info:id = "ND_tiledimage_color3"
        asset inputs:file = @plain.png@
        float2 inputs:texcoord.connect = </Mat/Coords.outputs:out>
        float2 inputs:uvtiling.connect = </Mat.inputs:tiling>
        float2 inputs:uvoffset = (0.5, 0.25)
        color3f outputs:out
    }
}
"""


def test_usd_materialx_tiledimage_scales_uvtiling_where_authored(tmp_path: Path):
    path = tmp_path / "tiled.usda"
    path.write_text(TILED_LAYER, encoding="utf-8")
    (tmp_path / "plain.png").write_bytes(b"source")
    (tmp_path / "plain_tile.png").write_bytes(b"tile")
    tex = replace_map(texture_map(tmp_path, "/Mat", "/Mat/Tiled", "plain.png",
                                  AuthoredAt("/Mat/Tiled", "inputs:file", str(path))))
    stack = StackResult(TextureStack("/Mat", tex.uv, (tex,)), [MapResult(tex, tmp_path / "plain_tile.png")],
                        (4.0, 3.0), provenance("plain.png", (4.0, 3.0)))
    result = author_usd(path, [stack])
    old, new = Usd.Stage.Open(str(path)), Usd.Stage.Open(str(result.output))
    assert uv_affine(new, "/Mat/Tiled").close_to(uv_affine(old, "/Mat/Tiled").then(scale2d((4.0, 3.0))))
    assert tuple(new.GetPrimAtPath("/Mat").GetAttribute("inputs:tiling").Get()) == (8.0, 6.0)
    assert not [p for p in new.Traverse() if p.GetName().startswith("SeamlessUV")]
    again = author_usd(result.output, [stack])
    assert again.plan == []


def replace_map(tex: TextureMap) -> TextureMap:
    from dataclasses import replace

    return replace(tex, node_type="ND_tiledimage_color3")


def test_open_stage_with_a_new_file_root_layer(scene: Path):
    """As an export hook gets it: a root layer with a file name, not saved yet."""
    root = scene.parent
    out_dir = root / "export"
    out_dir.mkdir()
    stage = Usd.Stage.CreateNew(str(out_dir / "exported.usda"))
    stage.GetRootLayer().ImportFromString(LOOKS_LAYER.replace('over "World"', 'def Xform "World"')
                                          .replace('over "Looks"', 'def Scope "Looks"'))
    result = author_usd_stage(stage, [plain_result(root)])
    assert not result.findings and result.layers_written == []
    tex = stage.GetPrimAtPath(f"{PLAIN_MAT}/Tex")
    assert tex.GetAttribute("inputs:file").Get().path == "../tileable/plain_tile.png"
    stage.Save()
    reopened = Usd.Stage.Open(str(out_dir / "exported.usda"))
    assert Path(reopened.GetPrimAtPath(f"{PLAIN_MAT}/Tex").GetAttribute("inputs:file").Get().resolvedPath) == \
        (root / "tileable" / "plain_tile.png").resolve()


def test_dry_run_before_tiles_exist(scene: Path):
    root = scene.parent
    shutil.rmtree(root / "tileable")
    result = author_usd(scene, [brick_result(root)], mode=WriteMode.DRY_RUN)
    assert not result.findings and result.plan and not (root / "tileable").exists()


MTLX_IMAGE_WITHOUT_TEXCOORD = """#usda 1.0
(
    defaultPrim = "World"
)

def Xform "World"
{
    def Mesh "Floor" (
        prepend apiSchemas = ["MaterialBindingAPI"]
    )
    {
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        point3f[] points = [(0, 0, 0), (4, 0, 0), (4, 0, 4), (0, 0, 4)]
        texCoord2f[] primvars:st = [(0, 0), (4, 0), (4, 4), (0, 4)] (
            interpolation = "vertex"
        )
        rel material:binding = </World/Looks/B>
    }

    def Scope "Looks"
    {
        def Material "B"
        {
            token outputs:mtlx:surface.connect = </World/Looks/B/SR.outputs:out>

            def Shader "SR"
            {
                uniform token info:id = "ND_standard_surface_surfaceshader"
                color3f inputs:base_color.connect = </World/Looks/B/Img.outputs:out>
                token outputs:out
            }

            def Shader "Img"
            {
                uniform token info:id = "ND_image_color3"
                asset inputs:file = @./textures/brick_albedo.png@
                color3f outputs:out
            }
        }
    }
}
"""


def test_a_materialx_image_in_usd_with_no_texcoord_gets_its_uv_scale_through_a_uv0_reader(tmp_path, capsys):
    """An ND_image shader with no texcoord input reads UV0; its UV scale goes through a place2d that reads UV0 through
    an ND_texcoord node (a place2d's own default texcoord is a constant), so the tile keeps the source's texel
    density instead of being stretched over the UV square with a warning and a passed status."""
    import json
    import shutil

    from seamless_usd_cli.main import main

    shutil.copytree(Path(__file__).resolve().parents[1] / "sample_assets" / "textures", tmp_path / "textures")
    (tmp_path / "scene.usda").write_text(MTLX_IMAGE_WITHOUT_TEXCOORD)
    main(["process", str(tmp_path / "scene.usda"), "--force", "--preset", "tiny", "--seeds", "1", "--max-size", "128",
          "--cache-dir", str(tmp_path / "cache"), "--json"])
    payload = json.loads(capsys.readouterr().out)
    [stack] = payload["stacks"]
    assert not [f for f in payload["findings"] if f["code"] == "no-uv-input"], payload["findings"]
    stage = Usd.Stage.Open(str(tmp_path / "scene.seamless.usda"))
    image = UsdShade.Shader(stage.GetPrimAtPath("/World/Looks/B/Img"))
    [place] = image.GetInput("texcoord").GetConnectedSources()[0]
    place = UsdShade.Shader(place.source.GetPrim())
    assert place.GetShaderId() == "ND_place2d_vector2"
    scale = place.GetInput("scale").Get()
    assert (1 / scale[0], 1 / scale[1]) == pytest.approx(stack["uv_scale"], rel=1e-5)
    [reader] = place.GetInput("texcoord").GetConnectedSources()[0]
    reader = UsdShade.Shader(reader.source.GetPrim())
    assert reader.GetShaderId() == "ND_texcoord_vector2" and reader.GetInput("index").Get() == 0


def test_a_layer_reached_through_a_link_is_edited_in_the_file_it_links_to(scene: Path, tmp_path: Path):
    """``looks.usda``, a link to a library's layer: the in-place edit replaced the link with a file of its own, so the
    shot stopped following the library without a word. The edit is made in the linked file, the link stays, and a
    warning says every stage that uses that file shows the tiles now."""
    root = scene.parent
    library = tmp_path / "library"
    library.mkdir()
    shutil.move(root / "looks.usda", library / "looks.usda")
    (root / "looks.usda").symlink_to(library / "looks.usda")
    before = (library / "looks.usda").read_bytes()
    result = author_usd(scene, [brick_result(root)], mode=WriteMode.IN_PLACE)
    assert (root / "looks.usda").is_symlink() and (library / "looks.usda").read_bytes() != before
    assert result.layers_written == [library / "looks.usda"]
    assert result.backups == [library / "looks.usda.bak"] and (library / "looks.usda.bak").read_bytes() == before
    assert any("a link to" in f.message and "every stage that links or uses that file" in f.message
               for f in result.findings)
