"""A straightened tile turned back in the asset's UVs (``process --straighten``): the turn node before the UV
scale, in USD (UsdTransform2d) and MaterialX (place2d), its updates on later runs, and texel lengths kept."""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest
from pxr import Usd, UsdShade

from seamless_usd.authoring import UVTurn, author_mtlx, author_usd, read_mtlx_provenance, read_provenance, \
    scale2d, uv_affine
from seamless_usd.authoring.uvmath import turned_scale
from test_authoring_mtlx import SCALE, chain, document, read, results  # noqa: F401  (document: a fixture)
from test_authoring_usd import BRICK, brick_result, scene, uv_nodes  # noqa: F401  (scene: a fixture)


def _texel_vector(affine, p, q, size):
    """The texel offset (u right, v up) between the images of UV points ``p`` and ``q`` in a picture of ``size``."""
    a, b = affine(p), affine(q)
    return ((a[0] - b[0]) * size[0], (a[1] - b[1]) * size[1])


@pytest.mark.parametrize("source, tile, degrees", [((1024, 512), (300, 200), 17.0), ((256, 256), (90, 130), -31.0)])
def test_the_turn_keeps_texel_lengths_and_turns_them_clockwise_in_the_uvs(source, tile, degrees):
    """Every texel step on the asset is the same length in the tile as in the source, turned by the angle: the
    UVs turn clockwise, which shows the straight tile turned counter-clockwise, as its source ran."""
    (w, h), (tw, th) = source, tile
    turn = turned_scale((w / tw, h / th), degrees, h / w)
    points = [(0.0, 0.0), (0.3, 0.1), (0.9, 0.7), (0.2, 0.95)]
    for p in points:
        for q in points:
            if p == q:
                continue
            sx, sy = _texel_vector(lambda uv: uv, p, q, source)
            tx, ty = _texel_vector(turn, p, q, tile)
            assert math.hypot(tx, ty) == pytest.approx(math.hypot(sx, sy), rel=1e-9)
            turned_by = math.degrees(math.atan2(ty, tx) - math.atan2(sy, sx))
            assert (turned_by + degrees + 180.0) % 360.0 - 180.0 == pytest.approx(0.0, abs=1e-6)


def _turned(result, degrees=17.0, aspect=0.5):
    return replace(result, uv_turn=UVTurn(degrees, aspect))


def test_usd_turn_node_before_the_scale_node_and_recorded(scene):
    root = scene.parent
    result = author_usd(scene, [_turned(brick_result(root))])
    old_stage, stage = Usd.Stage.Open(str(scene)), Usd.Stage.Open(str(result.output))
    scale = brick_result(root).uv_scale
    for tex in ("Albedo", "Normal"):
        old, new = uv_affine(old_stage, f"{BRICK}/{tex}"), uv_affine(stage, f"{BRICK}/{tex}")
        assert new.close_to(old.then(turned_scale(scale, 17.0, 0.5)), tol=1e-6)
        prov = read_provenance(stage.GetPrimAtPath(f"{BRICK}/{tex}"))
        assert prov.uv_turn == pytest.approx(17.0) and prov.uv_scale == pytest.approx(scale)
    added = [p for p in uv_nodes(stage) if p.GetName().startswith("Seamless")]
    assert sorted(p.GetName() for p in added) == ["SeamlessUV", "SeamlessUVTurn"]  # shared by both maps
    [turn] = [UsdShade.Shader(p) for p in added if p.GetName() == "SeamlessUVTurn"]
    assert turn.GetInput("rotation").Get() == pytest.approx(-17.0)  # UsdTransform2d turns counter-clockwise


def test_usd_turn_is_updated_in_place_by_later_runs(scene):
    root = scene.parent
    first = author_usd(scene, [_turned(brick_result(root))])
    old = uv_affine(Usd.Stage.Open(str(scene)), f"{BRICK}/Albedo")
    scale = brick_result(root).uv_scale
    # the same again: nothing to do
    again = author_usd(first.output, [_turned(brick_result(root))])
    assert again.layers_written == [] and not again.plan
    # an angle a float input holds only to float32 precision reads back equal: still nothing to do
    odd = author_usd(scene, [_turned(brick_result(root), 17.3, 0.37)])
    assert not author_usd(odd.output, [_turned(brick_result(root), 17.3, 0.37)]).plan
    # made again from the source at another angle: the turn node is updated, never a second one
    other = author_usd(first.output, [_turned(brick_result(root), 5.0, 0.5)])
    stage = Usd.Stage.Open(str(other.output))
    assert uv_affine(stage, f"{BRICK}/Albedo").close_to(old.then(turned_scale(scale, 5.0, 0.5)), tol=1e-6)
    assert len([p for p in uv_nodes(stage) if p.GetName().startswith("Seamless")]) == 2
    # written straight this time: the turn becomes the identity and the scale is the UV scale alone
    straight = author_usd(other.output, [brick_result(root)])
    stage = Usd.Stage.Open(str(straight.output))
    assert uv_affine(stage, f"{BRICK}/Albedo").close_to(old.then(scale2d(scale)), tol=1e-6)
    assert read_provenance(stage.GetPrimAtPath(f"{BRICK}/Albedo")).uv_turn == 0.0


def test_usd_turn_of_a_tile_made_from_an_earlier_tile_is_inserted_and_composes(scene):
    root = scene.parent
    first = author_usd(scene, [brick_result(root)])  # not turned: a scale node only
    s1 = brick_result(root).uv_scale
    tile = root / "tileable" / "brick_albedo_tile.png"
    s2, tile_aspect = (2.0, 1.0), 0.25
    second = author_usd(first.output, [_turned(brick_result(root, scale=s2, albedo_resolved=tile), 9.0, tile_aspect)])
    stage = Usd.Stage.Open(str(second.output))
    old = uv_affine(Usd.Stage.Open(str(scene)), f"{BRICK}/Albedo")
    total = (s1[0] * s2[0], s1[1] * s2[1])
    # turned in the first source's texel units: its aspect is the tile's times the first scale's ratio
    expected = old.then(turned_scale(total, 9.0, tile_aspect * s1[1] / s1[0]))
    assert uv_affine(stage, f"{BRICK}/Albedo").close_to(expected, tol=1e-6)
    assert len([p for p in uv_nodes(stage) if p.GetName().startswith("Seamless")]) == 2


def test_mtlx_turn_place2d_before_the_scale_place2d(document):
    turned = [replace(r, uv_turn=UVTurn(23.0, 1.5)) for r in results(document)]
    result = author_mtlx(document, turned)
    old, new = read(document), read(result.layers_written[0])
    node = "NG_brick/image_color"
    assert chain(new, node).close_to(chain(old, node).then(turned_scale(SCALE, 23.0, 1.5)), tol=1e-6)
    assert read_mtlx_provenance(new.getDescendant(node)).uv_turn == pytest.approx(23.0)
    # a tiledimage cannot turn: scaled only, written straight, and the user is told
    tiled = "NG_brick/tiled_rough"
    assert chain(new, tiled).close_to(chain(old, tiled).then(scale2d(SCALE)), tol=1e-6)
    assert read_mtlx_provenance(new.getDescendant(tiled)).uv_turn == 0.0
    assert any("cannot turn" in f.message and "tiled_rough" in f.where for f in result.findings)
    # made again from the source, written straight: the turn is set to the identity, not removed or doubled
    again = author_mtlx(result.layers_written[0], [replace(r, maps=[replace(m, map=replace(
        m.map, document=str(result.layers_written[0]), file_at=replace(m.map.file_at, layer=str(
            result.layers_written[0])))) for m in r.maps]) for r in results(document)],
        output_path=document.with_name("again.mtlx"))
    third = read(again.layers_written[0])
    assert chain(third, node).close_to(chain(old, node).then(scale2d(SCALE)), tol=1e-6)
    place2ds = [n.getName() for n in third.getDescendant("NG_brick").getNodes() if n.getCategory() == "place2d"]
    assert sorted(place2ds) == ["place", "seamless_uv", "seamless_uv_turn"]



SHARED = """<?xml version="1.0"?>
<materialx version="1.39">
  <nodegraph name="NG">
    <texcoord name="uv" type="vector2" />
    <image name="color" type="color3">
      <input name="file" type="filename" value="textures/color.png" />
      <input name="texcoord" type="vector2" nodename="uv" />
    </image>
    <image name="rough" type="float">
      <input name="file" type="filename" value="textures/rough.png" />
      <input name="texcoord" type="vector2" nodename="uv" />
    </image>
    <output name="out_color" type="color3" nodename="color" />
    <output name="out_rough" type="float" nodename="rough" />
  </nodegraph>
</materialx>
"""


def test_mtlx_place2d_shared_by_a_stack_is_updated_once_a_run(tmp_path):
    """Two maps of one stack share the scale and turn place2d: a later run from their tiles composes its scale and
    turn once, not once a map."""
    from seamless_usd.authoring import MapResult, Provenance, StackResult
    from seamless_usd.textures import AuthoredAt, TextureStack
    from test_authoring_mtlx import mtlx_map

    doc = tmp_path / "shared.mtlx"
    doc.write_text(SHARED, encoding="utf-8")
    (tmp_path / "textures").mkdir()
    (tmp_path / "tileable").mkdir()
    for name in ("color.png", "rough.png"):
        (tmp_path / "textures" / name).write_bytes(b"source")
        (tmp_path / "tileable" / name).write_bytes(b"tile")

    def stack(document: Path, scale, turn, resolved: str):
        maps = [replace(mtlx_map(document, f"NG/{n}", f"{n}.png", AuthoredAt(f"NG/{n}", "file", str(document))),
                        resolved=str(tmp_path / resolved / f"{n}.png")) for n in ("color", "rough")]
        prov = Provenance("textures/color.png", (64, 64), scale, False, 0.3, (0.1, 0.2), "h", "0.1.0")
        return StackResult(TextureStack("M", maps[0].uv, tuple(maps)),
                           [MapResult(m, tmp_path / "tileable" / Path(m.resolved).name) for m in maps],
                           scale, prov, uv_turn=turn)

    first = author_mtlx(doc, [stack(doc, (4.0, 3.0), UVTurn(10.0, 0.75), "textures")])
    out = first.layers_written[0]
    # the tiles: the source (H / W = 0.75) over the scale (4, 3), so H / W = 1 in their texels
    second = author_mtlx(out, [stack(out, (2.0, 1.0), UVTurn(5.0, 1.0), "tileable")],
                         output_path=tmp_path / "second.mtlx")
    old, new = read(doc), read(second.layers_written[0])
    for n in ("color", "rough"):
        expected = chain(old, f"NG/{n}").then(turned_scale((8.0, 3.0), 15.0, 0.75))
        assert chain(new, f"NG/{n}").close_to(expected, tol=1e-6), n
        prov = read_mtlx_provenance(new.getDescendant(f"NG/{n}"))
        assert prov.uv_turn == pytest.approx(15.0) and prov.uv_scale == pytest.approx((8.0, 3.0))


def test_usd_turn_inside_the_variant_that_holds_the_material(tmp_path):
    """The floor's look lives in a variant of a payload's set: its turn node goes inside that variant of the new
    layer, beside the scale node, and nothing lands outside it."""
    import shutil

    from pxr import Sdf

    from seamless_usd.api import scan
    from seamless_usd.authoring import MapResult, Provenance, StackResult

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("shading", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    scene = tmp_path / "shading" / "set.usda"
    [floor] = [s for s in scan(scene).stacks if s.material == "</World/Floor/Looks/M_tiles>"]
    (tmp_path / "tile.png").write_bytes(b"tile")
    prov = Provenance(floor.maps[0].asset, (64, 64), (2.0, 2.0), None, 0.0, (0.0, 0.0), "h", "0.1.0")
    result = StackResult(floor, [MapResult(m, tmp_path / "tile.png") for m in floor.maps], (2.0, 2.0), prov,
                         uv_turn=UVTurn(12.0, 1.0))
    written = author_usd(scene, [result])
    layer = Sdf.Layer.FindOrOpen(str(written.output))
    inside = "/World/Floor{floorVariant=Tiled}Looks/M_tiles"
    assert layer.GetPrimAtPath(f"{inside}/SeamlessUVTurn") and layer.GetPrimAtPath(f"{inside}/SeamlessUV")
    assert not layer.GetPrimAtPath("/World/Floor/Looks")
    stage = Usd.Stage.Open(str(written.output))
    stage.GetPrimAtPath("/World/Floor").GetVariantSet("floorVariant").SetVariantSelection("Tiled")
    tex = "/World/Floor/Looks/M_tiles/diffuseColorTex"
    old = Usd.Stage.Open(str(scene))
    old.GetPrimAtPath("/World/Floor").GetVariantSet("floorVariant").SetVariantSelection("Tiled")
    assert uv_affine(stage, tex).close_to(uv_affine(old, tex).then(turned_scale((2.0, 2.0), 12.0, 1.0)), tol=1e-6)


def test_usd_materialx_nodes_turn_through_a_place2d(tmp_path):
    """MaterialX image nodes in a USD stage (texcoord -> place2d -> three images): one place2d turn and one
    place2d scale shared by the stack's maps, composing as the UsdTransform2d pair does."""
    import shutil

    from seamless_usd.api import scan
    from seamless_usd.authoring import MapResult, Provenance, StackResult

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("usd_mtlx", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    scene = tmp_path / "usd_mtlx" / "scene.usda"
    [stack] = scan(scene).stacks
    assert all(m.uv_turns for m in stack.maps) and len(stack.maps) == 3
    (tmp_path / "tile.png").write_bytes(b"tile")
    prov = Provenance(stack.maps[0].asset, (64, 64), (3.0, 1.5), None, 0.0, (0.0, 0.0), "h", "0.1.0")
    result = StackResult(stack, [MapResult(m, tmp_path / "tile.png") for m in stack.maps], (3.0, 1.5), prov,
                         uv_turn=UVTurn(-8.0, 0.5))
    written = author_usd(scene, [result])
    old, new = Usd.Stage.Open(str(scene)), Usd.Stage.Open(str(written.output))
    for m in stack.maps:
        node = m.node.strip("<>")
        assert uv_affine(new, node).close_to(uv_affine(old, node).then(turned_scale((3.0, 1.5), -8.0, 0.5)), tol=1e-6)
        assert read_provenance(new.GetPrimAtPath(node)).uv_turn == pytest.approx(-8.0)
    added = sorted(p.GetName() for p in new.Traverse() if p.GetName().startswith("SeamlessUV"))
    assert added == ["SeamlessUV", "SeamlessUVTurn"]
    assert UsdShade.Shader(new.GetPrimAtPath("/World/Looks/Brick/SeamlessUVTurn")).GetShaderId() == "ND_place2d_vector2"
