"""Crossfaded tiles judged against their source: the band where two copies of a photo show through each other is
a seam (:mod:`seamless_usd.verdict.ghosts`), while tiles of the photo's own texels and tone-levelled tiles keep
their detail and show no ghosted band. Real photos, read with OpenImageIO."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from seamless_usd.synthesis.lattice.mend import best_mend
from seamless_usd.verdict import judge
from seamless_usd.verdict.ghosts import GHOST_DIP, detail_ratios, ghost_bands
from seamless_usd.verdict.prepare import map_weights, joint, prepare_maps, to_working

PHOTOS = Path(__file__).resolve().parent.parent / "benchmarks" / "photos"


def _photo(name: str, side: int = 192) -> np.ndarray:
    """The photo's centre, ``side`` px square, brought down by an area filter, in the network domain."""
    buf = oiio.ImageBuf(str(PHOTOS / name))
    spec = buf.spec()
    s = min(spec.width, spec.height)
    square = oiio.ImageBufAlgo.cut(buf, oiio.ROI((spec.width - s) // 2, (spec.width - s) // 2 + s,
                                                 (spec.height - s) // 2, (spec.height - s) // 2 + s))
    small = oiio.ImageBufAlgo.resize(square, roi=oiio.ROI(0, side, 0, side, 0, 1, 0, 3))
    return small.get_pixels(oiio.FLOAT).reshape(side, side, 3) * 2.0 - 1.0


def _crossfade(photo: np.ndarray, overlap: float = 0.25) -> np.ndarray:
    """What quick "make seamless" scripts do: the photo's last ``overlap`` laid over its first with a linear
    ramp, along each axis; the tile is shorter by the overlap."""
    out = photo.astype(np.float64)
    for axis in (0, 1):
        n = out.shape[axis]
        b = int(round(overlap * n))
        a = ((np.arange(b) + 0.5) / b).reshape([-1, 1, 1] if axis == 0 else [1, -1, 1])
        head, tail = np.take(out, np.arange(b), axis), np.take(out, np.arange(n - b, n), axis)
        out = np.concatenate([(1 - a) * tail + a * head, np.take(out, np.arange(b, n - b), axis)], axis)
    return out.astype(np.float32)


def _bands(tile: np.ndarray, source: np.ndarray):
    t, s = prepare_maps([tile], [False]), prepare_maps([source], [False])
    factor = min(1.0, 256 / max(tile.shape[:2]))
    tw, sw = to_working(t, factor, True), to_working(s, factor, False)
    weights = map_weights(sw)
    return ghost_bands(joint(tw, weights), joint(sw, weights), factor, tile.shape[:2], 0.5)


@pytest.mark.parametrize("name", ["gravel_1.jpg", "food_peas_1.jpg"])
def test_a_crossfaded_photo_is_not_passed_and_its_band_is_named(name):
    source = _photo(name)
    tile = _crossfade(source)
    verdict = judge([tile], [source], [False], ["color"])
    assert not verdict.passed and not verdict.seamless
    ghosts = [s for s in verdict.seams if s.kind == "ghost"]
    assert ghosts, verdict.reasons()
    # the bands lie over the first quarter of each axis (the crossfade's ramp), whole lines long
    for seam in ghosts:
        n = tile.shape[0] if seam.axis == "y" else tile.shape[1]
        assert 0 < seam.position < n // 2 and seam.end - seam.start + 1 == n
    assert any("ghosted band" in r for r in verdict.reasons(5))
    assert verdict.as_dict()["seams"][0].get("kind") in (None, "ghost")


def test_the_photos_own_texels_and_a_tone_levelled_tile_show_no_ghosted_band():
    source = _photo("food_peas_1.jpg")
    # a tile of the photo's own texels: its mend (joins cut through the photo, every texel a copy)
    field, _ = best_mend([source], 2)
    mended = source[field[..., 0], field[..., 1]]
    assert _bands(mended, source)[0] == []
    # the photo rolled, under a smooth tone field (what a gradient-domain levelling does): the detail stays
    yy, xx = np.mgrid[0:192, 0:192] / 192.0
    levelled = np.roll(source, (40, 70), (0, 1)) + (0.15 * np.sin(2 * np.pi * yy) * np.cos(2 * np.pi * xx))[..., None]
    ratios = detail_ratios(*[joint(to_working(prepare_maps([a], [False]), 1.0, p), [1.0])
                             for a, p in ((levelled, True), (source, False))])
    assert abs(float(np.nanmedian(ratios))) < 0.05
    seams, strongest = _bands(levelled, source)
    assert seams == [] and strongest / 0.5 * GHOST_DIP < GHOST_DIP
