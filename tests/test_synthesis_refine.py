"""Toroidal exemplar refinement, working resolution and the crop plan for source-sized tiles."""
from __future__ import annotations

import numpy as np
import pytest
from textures import load_texture

from seamless_usd import metrics
from seamless_usd.synthesis import MapInput, RefineConfig, get_preset, make_tile, refine
from seamless_usd.synthesis.refinement.refine import level_scales
from seamless_usd.synthesis.gan.sample import SOURCE_TILE_MIN_FRACTION, crop_plan
from seamless_usd.synthesis.scale import structure_size, working_factor


@pytest.fixture(scope="module")
def brick() -> list[np.ndarray]:
    albedo, normal, rough = load_texture("brick_albedo.png"), load_texture("brick_normal.png"), load_texture("brick_roughness.png")
    n = normal / np.linalg.norm(normal, axis=-1, keepdims=True)
    return [albedo, n.astype(np.float32), rough]


@pytest.fixture(scope="module")
def refined(brick):
    return refine(brick, None, (256, 256), RefineConfig(), seed=0)


def test_every_map_is_copied_through_one_field(brick, refined):
    f = refined.field
    assert f.shape == (256, 256, 2)
    for source, tile in zip(brick, refined.maps):
        assert tile.shape == (256, 256, source.shape[2])
        # every texel is a source texel (found by value, not through the field), and the field says which
        src_rows = {r.tobytes() for r in source.reshape(-1, source.shape[2])}
        assert all(r.tobytes() in src_rows for r in tile.reshape(-1, source.shape[2]))
        assert np.array_equal(tile[7, 11], source[f[7, 11, 0], f[7, 11, 1]]) and (f >= 0).all()
    lengths = np.linalg.norm(refined.maps[1], axis=-1)
    np.testing.assert_allclose(lengths, 1.0, atol=1e-5)  # copied normals stay unit vectors


def test_refined_tile_is_faithful_and_tiles(brick, refined):
    """From a random start the refinement alone keeps the feature scale and wraps around without a seam."""
    for source, tile in zip(brick, refined.maps):
        m = metrics.map_metrics(tile, source)
        assert 0.85 <= m["scale_ratio"] <= 1.4, m  # copy boundaries add a little fine detail
    # seam ratios on wood (straight mortar rows on a brick tile's border inflate the ratio without a seam)
    wood = [load_texture("wood_color.png"), load_texture("wood_roughness.png")]
    res = refine(wood, None, (256, 256), seed=0)
    for source, tile in zip(wood, res.maps):
        m = metrics.map_metrics(tile, source)
        assert m["seam_ratio_x"] < 1.3 and m["seam_ratio_y"] < 1.3, m
        assert 0.9 <= m["scale_ratio"] <= 1.3 and m["patch_distance"] < 2.0, m
    # coherent copies, not a mosaic of single texels
    f = refined.field
    coherent = (np.roll(f, -1, 1) - f == np.array([0, 1])).all(-1).mean()
    assert coherent > 0.8


def test_layout_seeds_the_arrangement(brick):
    """A layout made of the source's own left half brought back the same: the refinement follows it."""
    layout = [np.roll(m, 64, axis=1) for m in brick]  # a periodic stand-in for a GAN tile
    res = refine(brick, layout, (256, 256), RefineConfig(), seed=1)
    albedo = res.maps[0]
    err_layout = np.abs(albedo - layout[0]).mean()
    err_other = np.abs(albedo - brick[0]).mean()
    assert err_layout < err_other


def test_non_square_and_paper_sized_tiles(brick):
    src = [m[:, :200] for m in brick]
    res = refine(src, None, (180, 330), seed=0)
    assert res.field.shape == (180, 330, 2)
    assert res.field[..., 0].max() < 256 and res.field[..., 1].max() < 200


def test_level_scales_double_up_to_one():
    assert level_scales((256, 256), 64) == [0.25, 0.5, 1.0]
    assert level_scales((2048, 1024), 64) == [1 / 32, 1 / 16, 1 / 8, 0.25, 0.5, 1.0]
    assert level_scales((48, 48), 64) == [1.0]


def test_structure_size_and_working_factor():
    rng = np.random.default_rng(0)
    assert structure_size([rng.normal(size=(128, 128, 1))]) <= 2  # white noise has no structure
    yy, xx = np.mgrid[0:256, 0:256]
    stripes = np.cos(2 * np.pi * xx / 64.0)[..., None] + 0.05 * rng.normal(size=(256, 256, 1))
    assert 8 <= structure_size([stripes]) <= 32  # decorrelates within a quarter period
    assert working_factor(512, 512, 64, 54.0) == pytest.approx(0.504)
    assert working_factor(512, 512, 64, 500.0) == pytest.approx(0.375)  # short side never below 3k
    assert working_factor(256, 256, 64, 5.0) == 1.0
    assert structure_size([np.zeros((64, 64, 1))]) == 0.0


def test_crop_plan_for_source_sized_tiles():
    cfg = get_preset("default")
    plan = list(crop_plan(256, 192, cfg, seed=0, tile_size="source"))
    (c_h, c_w), first = plan[0]
    assert (c_h, c_w) == (128, 96) and first == (64, 48)  # half the stack, centred
    assert all(max(c) >= SOURCE_TILE_MIN_FRACTION * 128 for c, _ in plan)
    assert len([p for p in plan if p[0] == (128, 96)]) == 1 + cfg.crops_per_size
    with pytest.raises(AssertionError, match="tile_size"):
        list(crop_plan(256, 256, cfg, seed=0, tile_size="huge"))


def test_make_tile_source_sized_and_refine_off():
    albedo = load_texture("wood_color.png")[:128, :160]
    rough = load_texture("wood_roughness.png")[:128, :160]
    maps = [MapInput("a", albedo), MapInput("r", rough)]
    # the refinement alone: without the cut candidate (a window of the source, which would win here)
    made = make_tile(maps, get_preset("tiny"), refine_config=RefineConfig(lattice=False), seed=0)
    assert made.refined and made.tile_size == (128, 160) and made.uv_scale == (1.0, 1.0)
    for m in maps:
        tile = made.maps[m.name]
        # every texel of every map comes from the same source position
        assert np.isin(tile.reshape(-1, tile.shape[2]).view([("", tile.dtype)] * tile.shape[2]),
                       m.pixels.reshape(-1, tile.shape[2]).view([("", tile.dtype)] * tile.shape[2])).all()
    # Worked by hand: the tiny preset (k = 16) works at 3k = 48 px on the short side, 128 x 160 -> 48 x 60.
    raw = make_tile(maps, get_preset("tiny"), refine_config=None, seed=0)
    assert not raw.refined and raw.working_size == (48, 60) and raw.grid_size == (48, 60)
    h, w = raw.tile_size  # the GAN's own tile, on the 48 x 60 grid that spans the UV unit square
    assert raw.uv_scale == pytest.approx((60 / w, 48 / h))
    # the paper's search starts from the whole working stack (c = 48 x 60) and goes down; the tile is 2c x 2c
    # of the crop Q chose, brought to source px (x 128/48 = 160/60 = 8/3): the whole stack gives 96 x 120
    # working px, 256 x 320 source px, uv scale 1/2
    paper = make_tile(maps, get_preset("tiny"), tile_size="paper", seed=0)
    assert paper.gan.candidates[0].crop_size == (48, 60)
    ch, cw = paper.gan.crop_size
    assert next(iter(paper.gan.maps.values())).shape[:2] == (2 * ch, 2 * cw)
    assert paper.tile_size == (round(2 * ch * 8 / 3), round(2 * cw * 8 / 3))
    assert paper.uv_scale == pytest.approx((160 / paper.tile_size[1], 128 / paper.tile_size[0]))
