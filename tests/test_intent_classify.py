"""Tiling intent on real structures, and the measured figures the thresholds come from."""
from __future__ import annotations

import json
import re
from pathlib import Path

import jsonschema
import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Usd

from seamless_usd.discover import scan_paths
from seamless_usd.discover.intent import THRESHOLDS, _reduce
from seamless_usd.discover.uvgeom import material_bindings, uv_stats
from seamless_usd.metrics import ps_score, seam_ratios
from seamless_usd_cli.main import main
from seamless_usd_schemas import json_schema

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "sample_assets"
SHARED = ROOT.parent / "shared" / "textures"  # the MaterialX example images at full size, when present


def _intents(path: Path) -> dict[str, tuple[str, str]]:
    return {s.material: (s.intent, s.intent_reason) for s in scan_paths([path]).stacks}


def _figures(path: Path, box: tuple[int, int, int] | None = None) -> tuple[float, float]:
    """(periodic-plus-smooth, worst seam ratio) at the measuring size, as intent measures them."""
    px = oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT).astype(np.float64)
    if box is not None:
        x, y, size = box
        px = px[y:y + size, x:x + size]
    px = _reduce(px, THRESHOLDS.measure_size)
    seams = seam_ratios(px)
    return ps_score(px), max(seams["seam_ratio_x"], seams["seam_ratio_y"])


# -- figures ----------------------------------------------------------------------------------

def test_thresholds_separate_measured_tiling_and_non_tiling_files():
    tiling = [_figures(SAMPLES / "textures" / n) for n in ("wood_tileable.jpg", "wood_tileable_roughness.jpg")]
    not_tiling = [_figures(SAMPLES / "textures" / n) for n in (
        "brick_albedo.png", "brick_normal.png", "brick_roughness.png", "cloth.png", "wood_color.png",
        "wood_roughness.png")]
    # measured (512 px): the bundled tileable wood 0.050 / 0.049 (seam 1.45 / 1.33);
    # the bundled off-grid samples 0.137 .. 0.768 (seam 1.32 .. 9.75)
    assert all(ps <= THRESHOLDS.ps_max and seam <= THRESHOLDS.seam_max for ps, seam in tiling), tiling
    assert all(ps > THRESHOLDS.ps_max for ps, _ in not_tiling), not_tiling
    assert max(ps for ps, _ in tiling) < 0.06 < 0.13 < min(ps for ps, _ in not_tiling)


@pytest.mark.skipif(not (SHARED / "wood_color.jpg").is_file(), reason="needs ../shared/textures")
def test_figures_on_the_full_size_materialx_images():
    # the MaterialX wood tiles: 0.044 at 512 px (0.051 at 2048 px)
    ps, seam = _figures(SHARED / "wood_color.jpg")
    assert ps == pytest.approx(0.044, abs=0.01) and seam < 1.2
    ps, _ = _figures(SHARED / "wood_roughness.jpg")
    assert ps == pytest.approx(0.049, abs=0.01)
    # off-grid windows of the same periodic images do not: 0.105 (brick normal) .. 0.79
    windows = [_figures(SHARED / name, (137, 291, 700)) for name in (
        "wood_color.jpg", "wood_roughness.jpg", "brick_base_gray.jpg", "brick_normal.jpg", "brick_roughness.jpg")]
    assert min(ps for ps, _ in windows) > 0.1 > THRESHOLDS.ps_max
    assert _figures(SHARED / "cloth.jpg")[0] == pytest.approx(0.142, abs=0.01)


# -- geometry ---------------------------------------------------------------------------------

def test_uv_stats_of_an_atlas_and_a_tiling_plane_in_a_payload():
    stage = Usd.Stage.Open(str(SAMPLES / "prop" / "prop.usda"), Usd.Stage.LoadAll)
    bindings = material_bindings(stage)
    [body] = bindings["</Prop/Materials/M_body>"]
    stats = uv_stats(stage, body, "st")
    assert stats.islands == 36 and stats.full_islands == 0
    assert stats.lo == pytest.approx((0.1204, 0.1204), abs=1e-3) and stats.hi == pytest.approx((0.8796, 0.8796), abs=1e-3)
    [floor] = bindings["</Prop/Materials/M_floor>"]
    stats = uv_stats(stage, floor, "st")
    assert stats.islands == 1 and stats.span == pytest.approx((4.0, 4.0))
    # unloaded payload: no geometry, no bindings
    assert material_bindings(Usd.Stage.Open(str(SAMPLES / "prop" / "prop.usda"), Usd.Stage.LoadNone)) == {}


# -- classes ----------------------------------------------------------------------------------

def test_prop_atlas_decal_and_tiling_floor_in_a_variant():
    intents = _intents(SAMPLES / "prop" / "prop.usda")
    assert intents["</Prop/Materials/M_body>"][0] == "uv-atlas"
    assert re.search(r"UVs 0\.12-0\.88 x 0\.12-0\.88, 36 islands on </Prop/Geom/Body>", intents["</Prop/Materials/M_body>"][1])
    assert intents["</Prop/Materials/M_label>"][0] == "other"
    assert "clamp" in intents["</Prop/Materials/M_label>"][1]
    assert intents["</Prop/Materials/M_floor>"][0] == "tiling"
    assert "4.00 x 4.00 periods" in intents["</Prop/Materials/M_floor>"][1]


def test_chess_piece_mtlx_look_through_a_payload():
    result = scan_paths([SAMPLES / "chess" / "piece.usda"])
    assert str(SAMPLES / "chess" / "piece_mat.mtlx") in result.sources
    assert sorted(result.materials) == ["</Piece/Materials/M_board>", "</Piece/Materials/M_piece>"]
    intents = {s.material: s.intent for s in result.stacks}
    assert intents == {"</Piece/Materials/M_piece>": "uv-atlas", "</Piece/Materials/M_board>": "tiling"}
    assert not [f for f in result.findings if f.severity.value == "error"]


def test_already_tileable_texture_directly_and_from_usd():
    for path in (SAMPLES / "tileable" / "wood_tiled.mtlx", SAMPLES / "tileable" / "floor.usda"):
        [(intent, reason)] = _intents(path).values()
        assert intent == "already-tileable", (path, reason)
        assert re.search(r"periodic-plus-smooth 0\.0[45]\d", reason)


@pytest.mark.parametrize("scene", ["brick", "orm", "interface", "transform2d", "referenced", "usd_mtlx", "mtlx"])
def test_sample_scenes_stay_tiling(scene):
    intents = _intents(SAMPLES / scene / "scene.usda")
    assert intents and all(intent == "tiling" for intent, _ in intents.values()), intents


def test_library_material_without_geometry_is_tiling():
    [(intent, reason)] = _intents(SAMPLES / "mtlx" / "prefixed.mtlx").values()
    assert intent == "tiling" and "no bound geometry" in reason


def test_scan_shows_the_intent_in_the_table_and_json(capsys):
    path = str(SAMPLES / "prop" / "prop.usda")
    assert main(["scan", path]) == 0
    table = capsys.readouterr().out
    # the floor's texture under finish=cloth (not selected) is a stack of its own, judged there
    assert "intent: uv-atlas" in table and "36 islands" in table and "2 tiling" in table
    assert "in finish=cloth" in table
    assert main(["scan", "--json", path]) == 0
    payload = json.loads(capsys.readouterr().out)
    jsonschema.validate(payload, json_schema("scan"))
    assert {(s["material"], s["variant"]): s["intent"] for s in payload["stacks"]} == {
        ("</Prop/Materials/M_floor>", ""): "tiling", ("</Prop/Materials/M_body>", ""): "uv-atlas",
        ("</Prop/Materials/M_label>", ""): "other", ("</Prop/Materials/M_floor>", "finish=cloth"): "tiling"}
