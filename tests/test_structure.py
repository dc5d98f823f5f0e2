"""The structure figure, the interior join count and the boundary healing, on structured textures whose
structure is known: stone cells with dark joints and long curved stripes (``benchmarks/synthetic.py``)."""
from __future__ import annotations

import numpy as np
import pytest
import torch

from seamless_usd.metrics.structure import STRUCTURE_TARGET, structure_figures
from seamless_usd.synthesis.refinement.heal import relax_boundaries, seam_cost
from seamless_usd.verdict.joins import join_stats

from benchscripts import load_benchmark

synthetic = load_benchmark("synthetic")


def _blocks(img: np.ndarray, block: int, seed: int) -> np.ndarray:
    """The image rebuilt from ``block`` px squares copied from random places: stones cut and glued to others."""
    rng = np.random.default_rng(seed)
    h, w = img.shape[:2]
    out = np.empty_like(img)
    for y in range(0, h, block):
        for x in range(0, w, block):
            sy, sx = rng.integers(0, h - block), rng.integers(0, w - block)
            piece = img[sy:sy + block, sx:sx + block]
            out[y:y + block, x:x + block] = piece[: min(block, h - y), : min(block, w - x)]
    return out


@pytest.fixture(scope="module")
def stones() -> np.ndarray:
    return synthetic.cells(384, 48, seed=3)["color"][0]


@pytest.fixture(scope="module")
def lines() -> np.ndarray:
    return synthetic.stripes(384, 36, seed=4)["color"][0]


@pytest.mark.parametrize("texture", ["stones", "lines"])
def test_cut_and_glued_structure_scores_worse_than_the_sources_own_halves(texture, request):
    src = request.getfixturevalue(texture)
    cut = structure_figures(_blocks(src, 36, seed=1), src)
    # the figure is already divided by the source's half-vs-half spread, scale by scale
    assert cut["structure"] > STRUCTURE_TARGET * 1.5, cut
    worst = max(cut["scales"].values(), key=lambda v: v["figure"] / v["spread"])
    assert worst["figure"] > worst["spread"]
    assert worst["length"] < 1.0  # the lines were broken into shorter pieces, not merged


@pytest.mark.parametrize("texture", ["stones", "lines"])
def test_the_source_moved_by_a_few_texels_keeps_its_structure(texture, request):
    src = request.getfixturevalue(texture)
    assert structure_figures(np.roll(src, (3, 0), (0, 1)), src)["structure"] <= STRUCTURE_TARGET * 1.2


def test_another_stone_pattern_of_the_same_kind_reads_near_the_source():
    a = synthetic.cells(384, 48, seed=3)["color"][0]
    b = synthetic.cells(384, 48, seed=8)["color"][0]
    cut = structure_figures(_blocks(a, 36, seed=1), a)["structure"]
    assert structure_figures(b, a)["structure"] < cut / 2


def _glued(src: np.ndarray, offset: int, at: int) -> np.ndarray:
    """A field: columns before ``at`` copied from the source in place, the others from ``offset`` columns left."""
    h, w = src.shape[:2]
    yy, xx = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    return np.stack([yy, np.where(xx < at, xx, xx - offset)], -1)


def test_joins_are_counted_where_two_copies_meet():
    from scipy import ndimage

    rng = np.random.default_rng(0)  # smooth noise: a join of two unrelated places is a visible step
    src = ndimage.gaussian_filter(rng.normal(size=(96, 160)), 3.0)[..., None]
    src = (0.4 * src / src.std()).astype(np.float32)  # spans many 8-bit codes: each place is found once
    fld = _glued(src, 40, 90)[:, 40:136]  # a 96 x 96 tile: source columns 40..89, then 50..95 again
    tile = src[fld[..., 0], fld[..., 1]]
    stats = join_stats([tile], [src], [False], ["noise"])
    assert stats["copied"] == 1.0
    line = stats["maps"]["stack"]
    # three joins cross the whole tile: the glue line (column 50), the wrap along x (column 0) and the
    # wrap along y (row 0: the source's last row meets its first)
    assert line["count"] == 3 and 3 * 96 - 4 <= line["length"] <= 3 * 96  # the crossings may read lower
    pairs = 2 * 96 * 96
    assert stats["coherence"] == pytest.approx((pairs - 3 * 96) / pairs, abs=1e-3)


def test_a_tile_not_made_of_source_texels_has_no_join_figures():
    rng = np.random.default_rng(1)
    src = rng.normal(size=(64, 64, 1))
    stats = join_stats([rng.normal(size=(64, 64, 1))], [src], [False], ["noise"])
    assert stats["maps"] is None and stats["copied"] < 0.1


def test_healing_absorbs_slivers_and_keeps_every_texel_a_source_texel():
    """A coherent copy of a smooth source with one-texel slivers copied from elsewhere: the healing gives
    them back to the copy around them; every texel stays a source position. (A square island whose
    corners each touch two texels of either copy can stay: the healing is a local method.)"""
    from scipy import ndimage

    rng = np.random.default_rng(2)
    src = np.stack([ndimage.gaussian_filter(rng.normal(size=(80, 120)), 2.0) for _ in range(3)]).astype(np.float32)
    yy, xx = np.meshgrid(np.arange(64), np.arange(64), indexing="ij")
    fld = np.stack([yy + 8, xx + 20], -1)
    for y, x in ((10, 10), (30, 44), (50, 20)):  # 1 x 5 slivers from 40 columns further right
        fld[y, x:x + 5, 1] += 40
    f = torch.from_numpy(fld).long()
    s = torch.from_numpy(src)
    healed = relax_boundaries(s, f, passes=4)
    inner = (slice(6, -6), slice(6, -6))  # the tile's wrap is a join of its own, free to move
    assert (healed[inner] == torch.from_numpy(np.stack([yy + 8, xx + 20], -1))[inner]).all()
    clean = torch.from_numpy(np.stack([yy + 8, xx + 20], -1)).long()  # only the wrap's joins
    assert seam_cost(s, healed) <= seam_cost(s, clean) + 1e-6 < seam_cost(s, f)
    assert healed[..., 0].min() >= 0 and healed[..., 0].max() < 80 and healed[..., 1].max() < 120


def test_healing_never_raises_the_seam_cost_of_a_refined_field():
    from seamless_usd.synthesis import RefineConfig, refine
    from seamless_usd.synthesis.refinement.heal import smoothed
    from seamless_usd.synthesis.refinement.refine import joint_features

    stack = synthetic.cells(128, 32, seed=5)
    maps = [v[0] for v in stack.values()]
    fld = torch.from_numpy(refine(maps, None, (96, 96), RefineConfig(lattice=False, coarsest=32), seed=0).field)
    s = smoothed(torch.from_numpy(np.ascontiguousarray(joint_features(maps).transpose(2, 0, 1))), 1.5)
    healed = relax_boundaries(s, fld, passes=6)
    assert seam_cost(s, healed) < seam_cost(s, fld)
    assert (healed != fld).any(-1).float().mean() < 0.25  # boundaries moved; the blocks stayed


def _joint_network(img: np.ndarray) -> tuple[float, np.ndarray]:
    """Share of the darkest fifth of a map (its joints or lines) in the largest connected piece, and the mask."""
    from scipy import ndimage

    g = img.mean(axis=-1)
    mask = g < np.quantile(g, 0.2)
    labels, n = ndimage.label(mask)
    sizes = np.bincount(labels.ravel())[1:]
    return float(sizes.max() / sizes.sum()) if n else 0.0, mask


@pytest.fixture(scope="module")
def made_tiles(one_thread):
    """``make_tile`` (the ``tiny`` preset) on a stone-cell stack and a stripe stack, 160 px, non-periodic."""
    from seamless_usd.synthesis import MapInput, get_preset, make_tile

    out = {}
    for name, stack in (("cells", synthetic.cells(160, 40, seed=6)), ("stripes", synthetic.stripes(160, 30, seed=7))):
        maps = [MapInput(k, v[0], v[1]) for k, v in stack.items()]
        out[name] = (stack, make_tile(maps, get_preset("tiny"), seed=0, keep_alternatives=True))
    return out


@pytest.mark.parametrize("name", ["cells", "stripes"])
def test_a_window_cut_joins_only_across_its_wraps(name):
    """One window of the source, whole inside: every texel continues its neighbour as the source does, except
    on the cuts, which run in the first band of columns (the x wrap's) and the first band of rows (the y
    wrap's)."""
    from seamless_usd.synthesis.lattice.cut import lattice_cut
    from seamless_usd.synthesis.lattice.window import continues_itself, window_tile_size
    from seamless_usd.verdict.copies import copy_origins

    stack = synthetic.cells(160, 40, seed=6) if name == "cells" else synthetic.stripes(160, 30, seed=7)
    maps = [v[0] for v in stack.values()]
    (th, tw), (bh, bw), figures = window_tile_size(maps)
    assert not continues_itself(figures)  # neither repeats: make_tile does not offer this cut (see below)
    field, _ = lattice_cut(maps, (th, tw), (bh, bw))
    tile = np.concatenate([m[field[..., 0], field[..., 1]] for m in maps], -1).astype(np.float64)
    src = np.concatenate(maps, -1).astype(np.float64)
    origin, share = copy_origins(tile, src)
    assert share > 0.97
    rows, cols = np.meshgrid(np.arange(th), np.arange(tw), indexing="ij")
    for axis in (0, 1):
        nxt = np.roll(origin, 1, axis=axis) + (np.array([1, 0]) if axis == 0 else np.array([0, 1]))
        known = (origin[..., 0] >= 0) & (nxt[..., 0] >= 1) & (nxt[..., 0] < 160) & (nxt[..., 1] < 160)
        continued = src[np.clip(nxt[..., 0], 0, 159), np.clip(nxt[..., 1], 0, 159)]
        joined = known & (np.abs(continued - tile).max(-1) > 1e-6)  # not what the source has next
        assert joined.any() and np.all((rows[joined] <= bh) | (cols[joined] <= bw)), axis


@pytest.mark.parametrize("name", ["cells", "stripes"])
def test_a_stack_that_does_not_continue_itself_gets_a_quilt_not_a_window_cut(made_tiles, name):
    """Neither stack repeats, nor continues itself at any lag: a window of it is joined where stones and
    stripes visibly break, and the verdict misses some such joins
    (benchmarks/experiments/results/window_gate.md), so no window is offered. A source-sized quilt of four
    large blocks is weighed against the refined tile instead (lattice/quilt.py): the one that passes, else
    the lower score (fidelity and structure) is written. The verdict passes neither for the cells (their
    joins thicken joints and glue stone edges); it passes the stripes' quilt, whose lines run unbroken and
    unkinked across its joins and wraps at 3x, 2x2 repeated, so the stripes' quilt is written before any
    GAN is trained."""
    from seamless_usd.synthesis.lattice.window import WINDOW_MAX_DIFFERENCE
    from seamless_usd.synthesis.tile import QUILT_MAX_DIFFERENCE
    from seamless_usd.verdict import judge

    stack, made = made_tiles[name]
    keys = list(stack)
    refused = made.lattice["window_refused"]
    assert refused["most"] == WINDOW_MAX_DIFFERENCE and max(refused["lag_difference"].values()) > 0.3, refused
    lat = made.lattice
    assert lat["cut"] == "quilt" and lat["tile"] == [160, 160] and lat["cells"] == [2, 2] and len(lat["blocks"]) == 4
    assert made.tile_size == (160, 160) and made.uv_scale == (1.0, 1.0)
    if name == "stripes":  # its quilt passes before any training: written, and no GAN is trained
        assert lat["passes"] and lat["chosen"] and made.layout_kind == "quilt" and made.gan is None
        assert "not trained" in lat["gan"] and not any(k.startswith("score_") for k in lat)
        assert lat["difference_worst"] <= QUILT_MAX_DIFFERENCE and "quilt_refused" not in lat
        assert judge([made.maps[k] for k in keys], [stack[k][0] for k in keys], [False] * len(keys), keys,
                     fidelity=False).seamless
        return
    rival = next(k[len("score_"):] for k in lat if k.startswith("score_"))
    assert rival in ("gan", "random")
    assert lat["chosen"] == ((not lat["passes"], lat["score"]) < (not lat[f"passes_{rival}"], lat[f"score_{rival}"]))
    assert made.layout_kind == ("quilt" if lat["chosen"] else rival)
    assert set(made.alternatives) == {rival if lat["chosen"] else "quilt"}
    seamless = {}
    for kind, tiles in ((made.layout_kind, made.maps), *made.alternatives.items()):
        v = judge([tiles[k] for k in keys], [stack[k][0] for k in keys], [False] * len(keys), keys, fidelity=False)
        seamless[kind] = v.seamless
    assert seamless == ({"quilt": True, rival: False} if name == "stripes" else {"quilt": False, rival: False})
    assert lat["passes"] == (name == "stripes") and not lat[f"passes_{rival}"]
    # the stripes' quilt hides its joins; the cells' does not, and the verdict does not pass it either
    assert (lat["difference_worst"] <= QUILT_MAX_DIFFERENCE) == (name == "stripes") and "quilt_refused" not in lat


def test_a_stack_that_repeats_once_without_a_lattice_is_cut_as_one_window(one_thread):
    """A pattern that repeats once across the source (1.3 periods: too few for a lattice) continues itself at
    the window's lags: the window cut is offered, chosen over the refined tile and written whole, one period
    with the source's texel density, and it passes."""
    from scipy.ndimage import gaussian_filter

    from seamless_usd.synthesis import MapInput, get_preset, make_tile
    from seamless_usd.verdict import judge

    rng = np.random.default_rng(8)
    block = gaussian_filter(rng.normal(size=(150, 150, 3)), (2, 2, 0), mode="wrap")
    block = np.clip(block / (3 * block.std()), -1, 1).astype(np.float32)
    src = np.tile(block, (2, 2, 1))[:200, :200]
    made = make_tile([MapInput("color", src, False)], get_preset("tiny"), seed=0, keep_alternatives=True)
    assert made.lattice["period_px"] == [None, None] and "window_refused" not in made.lattice
    assert made.layout_kind == "window" and made.lattice["chosen"] and made.tile_size == (150, 150), made.lattice
    assert made.uv_scale == (200 / 150, 200 / 150)  # the window keeps the source's texel density
    tile = made.maps["color"]
    ys, xs = np.nonzero(np.all(block == tile[0, 0], axis=-1))  # where the tile starts in the period
    assert len(ys) == 1 and np.array_equal(np.roll(block, (-ys[0], -xs[0]), (0, 1)), tile)  # one whole period
    assert judge([tile], [src], [False], ["color"]).passed


@pytest.mark.parametrize("name", ["cells", "stripes"])
def test_a_structured_tile_is_made_of_source_texels_with_its_maps_aligned(made_tiles, name):
    from seamless_usd.verdict.copies import copy_origins

    stack, made = made_tiles[name]
    if made.layout_kind == "window":  # one window of the source, at least WINDOW_MIN of it along each side
        assert made.tile_size == tuple(made.lattice["tile"]) and min(made.tile_size) >= 0.7 * 160, made.lattice
    else:  # refined, or quilted from source-sized blocks
        assert made.tile_size == (160, 160)
    tile = np.concatenate([made.maps[k] for k in stack], -1).astype(np.float64)
    src = np.concatenate([stack[k][0] for k in stack], -1).astype(np.float64)
    _, share = copy_origins(tile, src)  # colour and height looked up together: found only if from one place
    _, colour_share = copy_origins(made.maps["color"].astype(np.float64), stack["color"][0].astype(np.float64))
    # texels beside a join have a neighbourhood the source lacks and may stay unplaced; the rest is found
    assert share > 0.8 and share > 0.97 * colour_share, (share, colour_share)
    # the stages are recorded as pictures: the GAN's layout, then every refinement level (none for a cut);
    # none at all where the cut passed before any training
    assert len(made.level_pictures) == (0 if made.gan is None else 1 + len(made.refine_levels))
    if made.refine_levels:
        assert made.level_pictures[-1][1].shape[:2] == (160, 160)


def test_a_stone_tile_keeps_its_joint_network_connected(made_tiles):
    stack, made = made_tiles["cells"]
    source_share, _ = _joint_network(stack["color"][0])
    tile_share, _ = _joint_network(made.maps["color"])
    assert tile_share >= 0.8 * source_share, (tile_share, source_share)


@pytest.mark.xfail(strict=True, reason="known limit: a texture that neither repeats nor continues itself (stone "
                   "cells, curved stripes) cannot be tiled from copies of its source without joins that show: the "
                   "refined tile cuts stones and jumps stripes at its copied blocks' edges, a window cut breaks them at "
                   "its wraps (so none is offered), and the quilt's joins thicken joints and end stripes")
@pytest.mark.parametrize("name", ["cells", "stripes"])
def test_a_structured_tile_has_no_interior_seam_and_keeps_its_structure(made_tiles, name):
    from seamless_usd.verdict import judge

    stack, made = made_tiles[name]
    keys = list(stack)
    v = judge([made.maps[k] for k in keys], [stack[k][0] for k in keys], [False] * len(keys), keys, fidelity=False)
    assert v.seamless, v.reasons()
    assert all(structure_figures(made.maps[k], stack[k][0])["structure"] <= STRUCTURE_TARGET for k in keys)
    source_share, _ = _joint_network(stack["color"][0])  # lines as long and networks as connected
    assert _joint_network(made.maps["color"])[0] >= 0.8 * source_share


@pytest.mark.parametrize("name", ["cells", "stripes"])
def test_a_stack_whose_joins_cannot_hide_is_told_what_to_do(made_tiles, name):
    """Neither stack repeats nor continues itself. The stripes' quilt hides its joins (and passes): nothing to
    advise. The cells' written tile shows its joins: the advice names the window lags and what to do."""
    from seamless_usd.synthesis import structure_advice

    _, made = made_tiles[name]
    advice = structure_advice(made.lattice, made.layout_kind)
    if name == "stripes":
        assert advice is None
    else:
        lags = made.lattice["window_refused"]["lag_difference"]
        assert advice is not None and "neither repeats nor continues itself" in advice, advice
        assert f"y {lags['y']:.2f}" in advice and "a source made to repeat" in advice
    # a stack that repeats is never advised so, whatever it wrote
    assert structure_advice({**made.lattice, "period_px": [40, None]}, made.layout_kind) is None
