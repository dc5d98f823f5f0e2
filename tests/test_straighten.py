"""Straightening turned structure: the orientation read off real textures, the maps turned back (normals as
vectors), and ``process --straighten`` end to end on a turned brick stack."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Usd, UsdShade

from seamless_usd.authoring import uv_affine

from seamless_usd.imaging.orientation import MIN_STRENGTH, dominant_orientation
from seamless_usd.imaging.straighten import inscribed_size, straighten_maps
from seamless_usd_cli.main import main
from scenes import ground_scene

ROOT = Path(__file__).resolve().parents[1]
TEXTURES = ROOT / "sample_assets" / "textures"
SKIMAGE = Path(__import__("skimage").__file__).parent / "data"


def _read(path: Path) -> np.ndarray:
    return np.asarray(oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT), dtype=np.float32)


def _turned_tileable(values: np.ndarray, degrees: float, side: int) -> np.ndarray:
    """A ``side`` px centre window of a tileable picture repeated and turned counter-clockwise (as seen)
    by ``degrees``: a turned texture with no border, at the picture's own texel size."""
    reps = int(np.ceil(side * 1.5 / min(values.shape[:2]))) + 1  # the window's turned corners stay inside
    big = oiio.ImageBuf(np.ascontiguousarray(np.tile(values, (reps, reps, 1))))
    h, w = big.spec().height, big.spec().width
    window = oiio.ROI((w - side) // 2, (w - side) // 2 + side, (h - side) // 2, (h - side) // 2 + side, 0, 1,
                      0, big.nchannels)  # only the window is resampled (the turn is about the whole picture's centre)
    turned = oiio.ImageBufAlgo.rotate(big, math.radians(-degrees), filtername="lanczos3", roi=window)
    return np.ascontiguousarray(turned.get_pixels(oiio.FLOAT, window), dtype=np.float32)


@pytest.mark.parametrize("degrees", [17.0, -31.0])
def test_the_turn_of_a_brick_wall_is_read_to_a_fraction_of_a_degree(degrees):
    brick = _read(TEXTURES / "brick_albedo.png")
    found = dominant_orientation([_turned_tileable(brick, degrees, 320)])
    assert abs(found.degrees - degrees) <= 0.3, found
    assert found.straightens and found.strength > 2 * MIN_STRENGTH


def test_straight_bricks_and_stochastic_photos_are_left_as_they_are():
    brick = dominant_orientation([_read(TEXTURES / "brick_albedo.png")])
    assert abs(brick.degrees) < 0.5 and not brick.straightens
    for photo in ("gravel.png", "grass.png"):  # no direction of lines to straighten
        found = dominant_orientation([_read(SKIMAGE / photo)])
        assert found.strength < MIN_STRENGTH and not found.straightens, (photo, found)


def test_straightening_undoes_the_turn_with_source_texels_only():
    brick = _read(TEXTURES / "brick_albedo.png")
    source = _turned_tileable(brick, 0.0, 256)
    turned = _turned_tileable(brick, 23.0, 256)
    [straight] = straighten_maps([turned], [False], 23.0)
    h, w = straight.shape[:2]
    assert (w, h) == tuple(v - 6 for v in inscribed_size(256, 256, 23.0))
    y0, x0 = (256 - h) // 2, (256 - w) // 2
    # the texture turned and turned back: the source's own centre, softened only by two resamplings
    assert np.abs(straight - source[y0:y0 + h, x0:x0 + w]).mean() < 0.03
    assert straight.min() >= turned.min() and straight.max() <= turned.max()  # no black corners, no overshoot


def _normals_of(height: np.ndarray) -> np.ndarray:
    """Unit normals (x right, y up) of a height field whose rows run downwards."""
    dy, dx = np.gradient(height.astype(np.float64))
    n = np.stack([-dx, dy, np.ones_like(dx)], axis=-1)  # rows down: the upward slope is -dy
    return (n / np.linalg.norm(n, axis=-1, keepdims=True)).astype(np.float32)


def test_normal_vectors_turn_with_the_picture():
    y, x = np.mgrid[0:256, 0:256].astype(np.float64)
    a = math.radians(20.0)  # ridges turned 20 degrees counter-clockwise, as seen
    height = 4.0 * np.sin(2 * np.pi * (x * math.cos(a) - y * math.sin(a)) / 24.0)
    found = dominant_orientation([height[..., None]])
    assert abs(found.degrees - 20.0) <= 0.3
    grey, normals = straighten_maps([height[..., None].astype(np.float32), _normals_of(height)], [False, True],
                                    found.degrees)
    expected = _normals_of(grey[..., 0])
    inner = (slice(4, -4), slice(4, -4))
    assert np.abs(normals[inner] - expected[inner]).max() < 0.05
    assert np.allclose(np.linalg.norm(normals, axis=-1), 1.0, atol=1e-4)
    # turned back by the asset's UVs, the tile is seen in the asset's tangent frame: the vectors keep the source's
    # direction (the ridges' slope still points 20 degrees off the picture's x axis)
    _, kept = straighten_maps([height[..., None].astype(np.float32), _normals_of(height)], [False, True],
                              found.degrees, turn_vectors=False)
    slope = np.degrees(np.arctan2(kept[inner][..., 1], kept[inner][..., 0]))
    steep = np.hypot(kept[inner][..., 0], kept[inner][..., 1]) > 0.3
    assert np.abs(((slope[steep] - 20.0) + 90.0) % 180.0 - 90.0).max() < 3.0
    assert np.allclose(np.linalg.norm(kept, axis=-1), 1.0, atol=1e-4)


def _turned_scene(folder: Path, degrees: float) -> Path:
    """A ground plane whose UsdPreviewSurface reads the bundled brick colour map turned by ``degrees``."""
    turned = _turned_tileable(_read(TEXTURES / "brick_albedo.png"), degrees, 256)
    return ground_scene(folder, turned, "brick_turned.png", "Brick")


def _seen_on_asset(stage: Usd.Stage, texture: str, tile: np.ndarray, size: int) -> np.ndarray:
    """What the asset shows over its UV square (``size`` px a side): the tile sampled (bilinear, repeating) where
    the texture's authored UV chain sends each point."""
    a = uv_affine(stage, texture)
    v, u = (1.0 - (np.arange(size) + 0.5) / size), (np.arange(size) + 0.5) / size
    u, v = np.meshgrid(u, v)
    tu, tv = a.a * u + a.b * v + a.tx, a.c * u + a.d * v + a.ty
    th, tw = tile.shape[:2]
    x, y = tu * tw - 0.5, (1.0 - tv) * th - 0.5
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    at = lambda yy, xx: tile[yy % th, xx % tw]  # noqa: E731
    return ((at(y0, x0) * (1 - fx) + at(y0, x0 + 1) * fx) * (1 - fy)
            + (at(y0 + 1, x0) * (1 - fx) + at(y0 + 1, x0 + 1) * fx) * fy).astype(np.float32)


@pytest.mark.parametrize("straight", [False, True], ids=["uv-turn", "write-straight"])
def test_process_straighten_tiles_the_turned_bricks_straight_and_records_the_turn(tmp_path, capsys, model_cache,
                                                                                  straight):
    scene = _turned_scene(tmp_path, 17.0)
    # --write-straight straightens too (it implies --straighten)
    code = main(["process", str(scene), "--write-straight" if straight else "--straighten", "--preset", "tiny",
                 "--cache-dir", str(model_cache), "--json", "--report", str(tmp_path / "report.html")])
    payload = json.loads(capsys.readouterr().out)
    [stack] = payload["stacks"]
    facts = stack["resampled"]["straightened"]
    assert abs(facts["degrees"] - 17.0) <= 0.3, facts
    w, h = facts["size"]
    assert (w, h) == tuple(v - 6 for v in inscribed_size(256, 256, facts["degrees"]))
    layer = Usd.Stage.Open(str(tmp_path / "scene.seamless.usda"))
    prim = layer.GetPrimAtPath("/World/Looks/Brick/diffuseColorTex")
    assert prim.GetAttribute("seamless:straightened").Get() == pytest.approx(facts["degrees"])
    tile_path = Path(UsdShade.Shader(prim).GetInput("file").Get().resolvedPath)
    tile = _read(tile_path)
    # written straight: the courses run along the axes, at the source's texel size
    assert abs(dominant_orientation([tile]).degrees) < 0.5
    th, tw = tile.shape[:2]
    assert stack["uv_scale"] == pytest.approx([256 / tw, 256 / th], rel=1e-6)
    assert (code == 0) == (stack["status"] == "passed")
    assert f"turned {facts['degrees']:g} degrees clockwise" in (tmp_path / "report.html").read_text()
    assert ("so the asset looks as before" in (tmp_path / "report.html").read_text()) != straight
    assert ("On the asset, through the UV turn" in (tmp_path / "report.html").read_text()) != straight
    # check judges the written tile against its source straightened the same way: one answer
    main(["check", str(tmp_path / "scene.seamless.usda"), "--json"])
    [item] = json.loads(capsys.readouterr().out)["items"]
    assert item["verdict"]["passed"] == (stack["status"] == "passed")
    assert item["verdict"]["strongest"] == pytest.approx(stack["verdict"]["strongest"], abs=0.05)
    # on the asset: turned back by the UVs, the courses run as the source's did (at its texel size); written
    # straight, they run along the axes
    seen = dominant_orientation([_seen_on_asset(layer, "/World/Looks/Brick/diffuseColorTex", tile, 256)])
    assert prim.GetAttribute("seamless:uvTurn").Get() == pytest.approx(0.0 if straight else facts["degrees"])
    assert abs(seen.degrees - (0.0 if straight else facts["degrees"])) < 0.5, seen


TILED_DOC = """<?xml version="1.0"?>
<materialx version="1.39" colorspace="lin_rec709">
  <nodegraph name="NG_brick">
    <texcoord name="uv0" type="vector2" />
    <NODE name="brick_color" type="color3">
      <input name="file" type="filename" value="brick_turned.png" colorspace="srgb_texture" />
      <input name="texcoord" type="vector2" nodename="uv0" />
    </NODE>
    <output name="base_color_out" type="color3" nodename="brick_color" />
  </nodegraph>
  <standard_surface name="SR_brick" type="surfaceshader">
    <input name="base_color" type="color3" nodegraph="NG_brick" output="base_color_out" />
  </standard_surface>
  <surfacematerial name="M_brick" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_brick" />
  </surfacematerial>
</materialx>
"""


@pytest.mark.parametrize("node", ["image", "tiledimage"])
def test_process_straighten_on_a_materialx_document(tmp_path, capsys, model_cache, node):
    """An image node's UVs turn the straightened tile back through a place2d before the UV scale; a tiledimage's
    cannot (uvtiling / uvoffset only): its tile is written straight, as with --write-straight (normal vectors
    turned with it), and the run says so, node by node."""
    import MaterialX as mx

    from seamless_usd.authoring.uvmath import place2d

    turned = _turned_tileable(_read(TEXTURES / "brick_albedo.png"), 17.0, 256)
    out = oiio.ImageBuf(np.ascontiguousarray(np.clip(turned, 0.0, 1.0), dtype=np.float32))
    out.set_write_format(oiio.UINT8)
    assert out.write(str(tmp_path / "brick_turned.png")), out.geterror()
    doc = tmp_path / "brick.mtlx"
    doc.write_text(TILED_DOC.replace("NODE", node), encoding="utf-8")
    main(["process", str(doc), "--straighten", "--preset", "tiny", "--cache-dir", str(model_cache), "--json"])
    payload = json.loads(capsys.readouterr().out)
    [stack] = payload["stacks"]
    facts = stack["resampled"]["straightened"]
    assert abs(facts["degrees"] - 17.0) <= 0.3
    written = mx.createDocument()
    mx.readFromXmlFile(written, str(tmp_path / "brick.seamless.mtlx"))
    image = written.getDescendant("NG_brick/brick_color")
    warnings = [f for f in payload["findings"] if f["code"] == "uv-not-composed"]
    if node == "tiledimage":
        assert not facts.get("uv_turn") and facts["uv_turn_refused"] == ["NG_brick/brick_color"]
        assert len(warnings) == 1 and "brick_color" in warnings[0]["where"]
        assert "written straight" in warnings[0]["message"]
        assert written.getDescendant("NG_brick/seamless_uv_turn") is None and not image.getAttribute("seamless_uvturn")
        return
    assert facts["uv_turn"] and not warnings
    turn = written.getDescendant("NG_brick/seamless_uv_turn")
    assert turn.getInputValue("rotate") == pytest.approx(facts["degrees"])  # place2d turns clockwise
    assert float(image.getAttribute("seamless_uvturn")) == pytest.approx(facts["degrees"])
    scale = written.getDescendant("NG_brick/seamless_uv")
    assert scale.getInput("texcoord").getNodeName() == "seamless_uv_turn"
    assert image.getInput("texcoord").getNodeName() == "seamless_uv"
    # the chain turns texel steps by the angle, keeping their length (the source is square: no aspect)
    chain = place2d(rotate=turn.getInputValue("rotate"), scale=tuple(turn.getInputValue("scale"))).then(
        place2d(scale=tuple(scale.getInputValue("scale"))))
    u, v = chain((1.0, 0.0)), chain((0.0, 0.0))
    th, tw = 256 / stack["uv_scale"][1], 256 / stack["uv_scale"][0]
    step = ((u[0] - v[0]) * tw, (u[1] - v[1]) * th)
    assert np.hypot(*step) == pytest.approx(256.0, rel=1e-6)
    assert np.degrees(np.arctan2(step[1], step[0])) == pytest.approx(-facts["degrees"], abs=1e-4)


def test_the_report_sees_a_tile_through_its_uv_turn_as_the_asset_does():
    """The report's asset picture samples the tile through the authored UV map: with no turn it is the tile
    repeated (as the same-scale view shows it), and through a turn the courses run at the source's angle."""
    from seamless_usd.authoring.uvmath import Affine2, turned_scale
    from seamless_usd.report.repeat import ViewGeometry, repeat_view, through_uv

    tile = _read(TEXTURES / "brick_albedo.png")[:32, :32]
    g = ViewGeometry(window=(2.0, 2.0), tile_extent=(1.0, 1.0), size=(64, 64))
    assert np.allclose(through_uv(tile, Affine2(), g), repeat_view(tile, (1.0, 1.0), g), atol=1e-5)
    straight = _read(TEXTURES / "brick_albedo.png")
    seen = through_uv(straight, turned_scale((1.0, 1.0), 17.0, 1.0), ViewGeometry((1.0, 1.0), (1.0, 1.0), (256, 256)))
    assert abs(dominant_orientation([seen]).degrees - 17.0) < 0.5
