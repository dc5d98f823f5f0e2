"""Keep and mend: the source rolled by half, its seams' band re-laid from itself, judged by the verdict."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from benchscripts import load_benchmark
from seamless_usd.synthesis import MapInput
from seamless_usd.synthesis.candidates import check_cut
from seamless_usd.synthesis.lattice.mend import best_mend, mend_field
from seamless_usd.verdict import judge

synthetic = load_benchmark("synthetic")
SKIMAGE = Path(__import__("skimage").__file__).parent / "data"


def _photo(name: str, side: int = 256) -> np.ndarray:
    """A real grey photo from scikit-image's data (CC0), a plain window of it, in [-1, 1]: it does not tile."""
    from PIL import Image

    with Image.open(SKIMAGE / name) as im:
        a = np.asarray(im.convert("L"), dtype=np.float32) / 127.5 - 1.0
    return np.ascontiguousarray(a[20: 20 + side, 30: 30 + side, None])


def _joins(field: np.ndarray) -> np.ndarray:
    """Where a texel's right or lower neighbour (across the wraps) is not the next texel of the source."""
    down = np.abs(np.roll(field, -1, 0) - field - np.array([1, 0])).sum(-1) > 0
    right = np.abs(np.roll(field, -1, 1) - field - np.array([0, 1])).sum(-1) > 0
    return down | right


def test_the_photo_is_kept_whole_outside_a_band_over_its_seams():
    src = _photo("gravel.png")
    field, figures = mend_field([src])
    H, W = src.shape[:2]
    core, overlap = figures["band"]
    reach = core + overlap
    rolled_y = (np.arange(H)[:, None] + H // 2) % H
    rolled_x = (np.arange(W)[None, :] + W // 2) % W
    kept = (field[..., 0] == rolled_y) & (field[..., 1] == rolled_x)
    cy, cx = H - H // 2, W - W // 2
    outside = np.ones((H, W), dtype=bool)
    outside[cy - reach: cy + reach] = False
    outside[:, cx - reach: cx + reach] = False
    assert kept[outside].all()  # every texel away from the band where the photographer put it
    assert kept.mean() > 0.6
    # the seams themselves are gone: the band's core is new texels
    assert not kept[cy - core: cy + core].any() and not kept[:, cx - core: cx + core].any()
    # every texel is a source texel (the verdict can find the copies), and the joins lie inside the band
    assert field.min() >= 0 and field[..., 0].max() < H and field[..., 1].max() < W
    away = np.ones((H, W), dtype=bool)  # a texel beside the band may join its neighbour inside it
    away[cy - reach - 1: cy + reach + 1] = False
    away[:, cx - reach - 1: cx + reach + 1] = False
    assert not _joins(field)[away].any()


def test_the_joins_wander_instead_of_running_straight_along_a_block():
    field, _ = mend_field([_photo("gravel.png")])
    joins = _joins(field)
    # no join runs straight along a whole block edge: the longest straight run of joins in any row or
    # column is far shorter than a block (segment) or the band
    def longest_run(mask: np.ndarray) -> int:
        best = 0
        for line in mask:
            run = 0
            for v in line:
                run = run + 1 if v else 0
                best = max(best, run)
        return best
    down = np.abs(np.roll(field, -1, 0) - field - np.array([1, 0])).sum(-1) > 0
    right = np.abs(np.roll(field, -1, 1) - field - np.array([0, 1])).sum(-1) > 0
    assert longest_run(down) < 40 and longest_run(right.T) < 40
    assert joins.any()


@pytest.mark.parametrize("name", ["gravel.png", "grass.png"])
def test_a_mended_photo_passes_where_the_photo_offset_by_half_does_not(name):
    src = _photo(name)
    field, figures = best_mend([src], 3)
    tile = src[field[..., 0], field[..., 1]]
    rolled = np.roll(src, (src.shape[0] // 2, src.shape[1] // 2), (0, 1))
    mended = judge([tile], [src], [False], ["photo"])
    offset = judge([rolled], [src], [False], ["photo"])
    assert not offset.seamless  # the offset photo's edges meet in a cross: the verdict sees it
    assert mended.method == "copies" and mended.passed, mended.reasons()
    assert figures["difference_worst"] < 0.5 and len(figures["blocks"]) >= 4


def test_the_best_of_several_mends_has_the_cheapest_worst_join():
    src = _photo("grass.png")
    made = [mend_field([src], seed=s)[1] for s in range(3)]
    _, best = best_mend([src], 3)
    assert best["join_worst"] == min(m["join_worst"] for m in made)


def test_every_map_of_a_stack_is_copied_through_one_field():
    src = _photo("gravel.png", 160)
    rough = np.clip(-src * 0.8 + 0.1, -1, 1)
    field, _ = mend_field([src, rough])
    copied = src[field[..., 0], field[..., 1]]
    assert np.array_equal(rough[field[..., 0], field[..., 1]], np.clip(-copied * 0.8 + 0.1, -1, 1))


def test_a_source_too_small_for_a_block_gets_no_mend():
    assert mend_field([np.zeros((16, 16, 1), np.float32)]) is None
    assert mend_field([np.zeros((40, 40, 1), np.float32)]) is not None  # a 40 px game texture is mended


def test_a_stochastic_photo_is_mended_before_any_quilt_and_the_tries_are_recorded():
    """Grass neither repeats nor continues itself: the lattice finds nothing, no window is offered, and the mend,
    tried before the quilt, passes; nothing after it is made."""
    check = check_cut([MapInput("color", _photo("grass.png"))], True, 0)
    assert check.kind == "mend" and check.passes
    assert check.figures["band"] and "difference_worst" in check.figures
    assert "quilt" not in [c["kind"] for c in check.notes.get("candidates", [{"kind": "mend"}])]


def test_a_mend_of_a_texture_with_long_lines_passes_only_where_its_joins_hide():
    """Curved stripes: their mend ends stripes in its band and leaves a tone patch. A texture with long lines is
    gated as a quilt is (its joins must hide), so the mend is refused and the quilt after it, whose stripes run
    unbroken, is the stack's cut. The verdict alone passed the mend until it read broad steps of tone; it now
    finds the tone patch's edge too."""
    stack = synthetic.stripes(160, 30, seed=7)
    maps = [MapInput(k, v[0], v[1]) for k, v in stack.items()]
    check = check_cut(maps, True, 0)
    tried = check.notes["candidates"]
    assert [c["kind"] for c in tried] == ["mend", "quilt"] and not tried[0]["passes"]
    assert check.kind == "quilt" and check.passes
    field, figures = best_mend([m.pixels for m in maps], 3)
    mended = {m.name: m.pixels[field[..., 0], field[..., 1]] for m in maps}
    assert figures["difference_worst"] > 0.05  # the stripes' mend does not hide its joins
    verdict = judge(list(mended.values()), [m.pixels for m in maps], [m.is_normal for m in maps], list(mended))
    assert not verdict.seamless and {s.kind for s in verdict.seams} == {"tone"}


def test_a_mend_scored_on_a_halved_grid_passes_or_not_as_its_full_resolution_verdict_says(monkeypatch):
    """A source larger than SCORE_SIDE is scored on its grid halved, where a mend's copies at odd offsets are no
    longer copies and read as seams; whether it passes is the full resolution's verdict, as the written tile's."""
    import seamless_usd.synthesis.types as types

    src = _photo("gravel.png", 384)
    field, _ = best_mend([src], 3)
    assert judge([src[field[..., 0], field[..., 1]]], [src], [False], ["gravel"]).passed
    monkeypatch.setattr(types, "SCORE_SIDE", 192)  # a 384 px source is scored at 192 px, as a 2K one at 1024
    check = check_cut([MapInput("gravel", src)], True, 0)
    assert check.halve == 2 and check.kind == "mend" and check.passes
    [tried] = check.notes["candidates"]
    assert tried["passes"] and tried["passes_on_grid"] is False
