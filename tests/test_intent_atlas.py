"""A material nothing binds is a library material, unless its pixels show an atlas's layout:
then it is ``uv-atlas (pixels)``, left alone with its figures, and processed only when forced.

Measured with ``benchmarks/atlas.py`` (limits: at least 8 islands on a flat background covering
at least 10 %): 25 atlases with background between their islands, 9-64 islands on 0.150-0.332;
66 windows (256-2048 px) of the MaterialX example photos, at most 5 islands (background up to
0.759 on the brick mask); 9 tiling textures, 1 island (background 0.008-0.529). 16 atlases whose
padding fills the whole sheet measure 1 island and are not flagged.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from seamless_usd.discover import scan_paths
from seamless_usd.discover.atlas import BACKGROUND_MIN, ISLANDS_MIN, atlas_figures
from seamless_usd.discover.select import left_alone_stacks
from seamless_usd.imaging.io import read_image
from seamless_usd_cli.main import main
from test_discover_stacks import material

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"
ATLASES = ["teapot_utah_atlas.png", "teapot_porcelain_atlas.png", "teapot_porcelain_arm.png",
           "king_white_atlas.png", "king_black_atlas.png"]
NOT_ATLASES = ["brick_albedo.png", "brick_normal.png", "brick_roughness.png", "brick_orm.png", "cloth.png",
               "wood_color.png", "wood_roughness.png", "wood_tileable.jpg", "wood_tileable_roughness.jpg"]


@pytest.mark.parametrize("name", ATLASES)
def test_bundled_atlases_show_islands_on_a_background(name):
    figures = atlas_figures(read_image(TEXTURES / name)[0])
    assert figures.is_atlas, figures
    assert figures.islands >= 9 and figures.background >= 0.15


@pytest.mark.parametrize("name", NOT_ATLASES)
def test_photos_and_tiling_textures_do_not(name):
    figures = atlas_figures(np.clip(read_image(TEXTURES / name)[0], 0, 1))
    assert not figures.is_atlas, figures
    assert figures.islands < ISLANDS_MIN


def test_a_flat_background_alone_is_not_an_atlas():
    img = np.full((128, 128, 3), 0.2)
    img[10:60, 10:60] = np.random.default_rng(0).random((50, 50, 3))
    figures = atlas_figures(img)
    assert figures.background > BACKGROUND_MIN and figures.islands == 1 and not figures.is_atlas


def _library(tmp_path: Path, texture: str) -> Path:
    path = tmp_path / f"library_{Path(texture).stem}.usda"
    body = material("/Library", "M", albedo=texture, rough="brick_roughness.png")
    path.write_text(f'#usda 1.0\ndef Scope "Library" {{{body}\n}}\n')
    return path


def test_an_unbound_atlas_is_flagged_from_its_pixels(tmp_path):
    (stack,) = scan_paths([_library(tmp_path, "teapot_porcelain_atlas.png")]).stacks
    assert stack.intent == "uv-atlas (pixels)"
    assert "25 islands on a flat background covering 19%" in stack.intent_reason
    assert "no bound geometry on the stage" in stack.intent_reason
    assert left_alone_stacks([stack], "s") == {("s", stack.id)}
    assert left_alone_stacks([stack], "s", force=True) == set()
    (photo,) = scan_paths([_library(tmp_path, "brick_albedo.png")]).stacks
    assert photo.intent == "tiling" and "library material" in photo.intent_reason


def test_process_leaves_it_alone_and_force_plans_it(tmp_path, capsys):
    path = str(_library(tmp_path, "king_black_atlas.png"))
    common = ["process", "--dry-run", "--json", "--preset", "tiny", "--cache-dir", str(tmp_path / "cache")]
    main([*common, path])
    (stack,) = json.loads(capsys.readouterr().out)["stacks"]
    assert stack["status"] == "left-alone" and stack["intent"] == "uv-atlas (pixels)"
    assert "16 islands" in stack["message"]
    main([*common, "--force", path])
    (stack,) = json.loads(capsys.readouterr().out)["stacks"]
    assert stack["status"] == "planned" and "forced" in stack["message"]
