"""Perspective (``process --straighten``): where a pitched wall's lines meet, the picture rectified so they run
parallel, photos whose lines do not converge left alone, and the rectified source recorded for ``check``."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Usd

from seamless_usd.imaging.orientation import dominant_orientation
from seamless_usd.imaging.perspective import find_keystone, rectify_maps
from seamless_usd_cli.main import main
from scenes import ground_scene

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"
SKIMAGE = Path(__import__("skimage").__file__).parent / "data"


def _read(path: Path) -> np.ndarray:
    return np.asarray(oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT), dtype=np.float32)


def _pitched(front: np.ndarray, size: int, vx: float, vy: float) -> np.ndarray:
    """A ``size`` px view of the repeating picture ``front`` on a plane pitched away from the camera, its vertical
    lines meeting at (vx, vy) px above the view (the inverse of the rectification)."""
    from scipy import ndimage

    yr = -vy
    y, x = np.mgrid[0:size, 0:size].astype(np.float64)
    fx, fy = (x - vx) * yr / (y - vy) + 300.0, yr - yr * yr / (y - vy) + 40.0
    h, w = front.shape[:2]
    return np.stack([ndimage.map_coordinates(front[..., k], [fy % h, fx % w], order=1, mode="grid-wrap")
                     for k in range(front.shape[2])], -1).astype(np.float32)


def test_a_pitched_brick_wall_is_found_and_rectified():
    view = _pitched(_read(TEXTURES / "brick_albedo.png"), 384, 200.0, -700.0)
    found = find_keystone([view])
    assert found is not None and found.spread > 5.0
    assert abs(found.vx - 200 / 384) < 0.05 and -2.6 < found.vy < -1.5, found  # truth (0.52, -1.82)
    [rectified] = rectify_maps([view], [False], found)
    assert find_keystone([rectified]) is None  # its lines run parallel now
    assert abs(dominant_orientation([rectified]).degrees) < 0.5
    assert view.min() - 1e-6 <= rectified.min() and rectified.max() <= view.max() + 1e-6
    # pitched the other way (the lines meet below): found upside down, rectified the same
    flipped = find_keystone([view[::-1]])
    assert flipped is not None and abs(flipped.vx - found.vx) < 0.02 and 2.5 < flipped.vy < 3.6, flipped
    [again] = rectify_maps([view[::-1]], [False], flipped)
    assert find_keystone([again]) is None and abs(dominant_orientation([again]).degrees) < 0.5


def _converging(vx: float, vy: float, h: int = 256, w: int = 256) -> np.ndarray:
    """(h, w, 3) soft bars (a cosine across them) that all pass through (vx, vy) above the picture, 24 px apart
    along the bottom row."""
    y, x = np.mgrid[:h, :w].astype(np.float64)
    at_bottom = vx + (x - vx) * (h - 1 - vy) / (y - vy)  # where each texel's line crosses the bottom row
    bars = 0.55 * np.cos(2 * np.pi * at_bottom / 24)
    return np.repeat(bars[..., None], 3, axis=2).astype(np.float32)


def test_converging_bars_meet_where_they_were_drawn_and_are_rectified_parallel():
    picture = _converging(140.0, -500.0)
    found = find_keystone([picture])
    assert found.vx == pytest.approx(140 / 256, abs=0.02) and found.vy == pytest.approx(-500 / 256, rel=0.05)
    assert found.spread > 15  # the bars lean from about -13 to +13 degrees across the picture
    [rect] = rectify_maps([picture], [False], found)
    assert find_keystone([rect]) is None  # parallel now
    assert rect.shape[0] < 256 and rect.min() >= picture.min() and rect.max() <= picture.max()
    assert find_keystone([_converging(128.0, -1e7)]) is None  # upright bars: not rectified


def test_a_point_read_too_close_is_moved_out_and_one_too_close_to_keep_is_not_used():
    """Fine bars read their point too close at first (the lines then diverge the other way once rectified): the
    reading on the rectified picture moves it out. A point so close that rectifying keeps under 40 % of a side
    is not used (a 64 px picture would keep 10 x 10 texels)."""
    big = _converging(0.55 * 1025, -1.5 * 1025, 1025, 1025)
    found = find_keystone([big])
    assert found.vy == pytest.approx(-1.5, abs=0.1), found
    [rect] = rectify_maps([big], [False], found)
    assert find_keystone([rect]) is None
    assert find_keystone([_converging(32.0, -12.8, 64, 64)]) is None
    assert find_keystone([_converging(48.0, -20.0, 96, 96)]) is None


@pytest.mark.parametrize("picture", ["brick_albedo.png", "gravel.png", "grass.png"])
def test_lines_that_do_not_converge_are_left_alone(picture):
    """Straight bricks (parallel lines) and stochastic photos (leans spread at random, which no point explains)."""
    values = _read((TEXTURES if picture.startswith("brick") else SKIMAGE) / picture)
    assert find_keystone([values]) is None


def test_process_straighten_rectifies_a_pitched_wall_and_check_agrees(tmp_path, capsys, model_cache):
    view = _pitched(_read(TEXTURES / "brick_albedo.png"), 384, 200.0, -700.0)
    scene = ground_scene(tmp_path, view, "brick_pitched.png", "Brick")
    main(["process", str(scene), "--straighten", "--preset", "tiny", "--cache-dir", str(model_cache), "--json",
          "--report", str(tmp_path / "report.html")])
    payload = json.loads(capsys.readouterr().out)
    [stack] = payload["stacks"]
    facts = stack["resampled"]["straightened"]
    rectified = facts["rectified"]
    assert rectified["spread"] > 5.0 and -3.0 < rectified["vanishing"][1] < -1.0
    assert not facts.get("uv_turn")  # no UV transform undoes a keystone: written rectified
    layer = Usd.Stage.Open(str(tmp_path / "scene.seamless.usda"))
    prim = layer.GetPrimAtPath("/World/Looks/Brick/diffuseColorTex")
    recorded = prim.GetAttribute("seamless:rectified").Get()
    assert tuple(recorded) == pytest.approx((*rectified["vanishing"], rectified["spread"]), abs=1e-4)
    assert prim.GetAttribute("seamless:uvTurn").Get() == 0.0
    assert not layer.GetPrimAtPath("/World/Looks/Brick/SeamlessUVTurn")
    assert "written rectified" in (tmp_path / "report.html").read_text()
    # check makes the source rectified the same way from the provenance: one answer
    main(["check", str(tmp_path / "scene.seamless.usda"), "--json"])
    [item] = json.loads(capsys.readouterr().out)["items"]
    assert item["verdict"]["passed"] == (stack["status"] == "passed")
    assert item["verdict"]["strongest"] == pytest.approx(stack["verdict"]["strongest"], abs=0.05)


def _normals_of(height: np.ndarray) -> np.ndarray:
    """Unit normals (x right, y up) of a height field whose rows run downwards."""
    dy, dx = np.gradient(height.astype(np.float64))
    n = np.stack([-dx, dy, np.ones_like(dx)], axis=-1)
    return (n / np.linalg.norm(n, axis=-1, keepdims=True)).astype(np.float32)


@pytest.mark.parametrize("below", [False, True], ids=["above", "below"])
def test_normal_vectors_turn_with_the_lines_they_belong_to(below):
    """Ridges along lines that converge: once rectified, each ridge stands upright, so its normals must point
    across it, to the left or the right, everywhere (before, their direction leans with the ridge, +-13 degrees)."""
    bars = _converging(140.0, -500.0)[..., 0]
    height = 6.0 * bars
    grey, normals = (height[::-1], _normals_of(height[::-1])) if below else (height, _normals_of(height))
    found = find_keystone([grey[..., None]])
    assert found is not None
    [rect] = rectify_maps([normals], [True], found)
    inner = rect[6:-6, 6:-6]
    steep = np.hypot(inner[..., 0], inner[..., 1]) > 0.3
    direction = np.degrees(np.arctan2(inner[..., 1], inner[..., 0]))[steep]
    off = np.abs((direction + 90.0) % 180.0 - 90.0)  # from the horizontal, either way
    assert np.percentile(off, 95) < 4.0, np.percentile(off, [50, 95])
    before = np.degrees(np.arctan2(normals[..., 1], normals[..., 0]))[np.hypot(normals[..., 0], normals[..., 1]) > 0.3]
    assert np.percentile(np.abs((before + 90.0) % 180.0 - 90.0), 95) > 8.0  # the test can see a lean
    assert np.allclose(np.linalg.norm(rect[..., :3], axis=-1), 1.0, atol=1e-4)
