"""The continuation ratio (verdict/across.py) on real photos: a plain window of a forest floor, whose wrap the
line breaks and the classifier both miss, has its seam found at the wrap, and rolled by half at its centre; the
photo made to tile, rolled, has none."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from seamless_usd.verdict import judge
from seamless_usd.verdict.across import MARGIN, continuation_ratios, unrelated_lines
from seamless_usd.verdict.alone import reduce_bins
from seamless_usd.verdict.breaks import line_breaks
from seamless_usd.verdict.prepare import prepare_maps

PHOTOS = Path(__file__).resolve().parents[1] / "benchmarks" / "photos"


def _reading(name: str, window: bool) -> np.ndarray:
    """The photo (made to tile) at 512 px as ``check`` reads it; ``window``: its middle 75 %, which does not tile."""
    a = np.asarray(Image.open(PHOTOS / name).convert("RGB"), dtype=np.float64) / 255.0
    if window:
        h, w = a.shape[:2]
        a = a[h // 10:h // 10 + 3 * h // 4, w // 10:w // 10 + 3 * w // 4]
    return 2.0 * reduce_bins(a, (512, 512)) - 1.0


def test_a_forest_floor_window_is_seamed_at_its_wrap_and_the_whole_photo_is_not():
    window = _reading("soil_forest_1.jpg", window=True)
    prepared = prepare_maps([window], [False])
    assert not line_breaks(prepared, ["color"])[0]  # the line breaks alone miss this wrap
    seams, strongest = unrelated_lines(prepared)
    assert seams and strongest > 1.0
    assert {(s.axis, s.position) for s in seams} <= {("x", 0), ("y", 0)}
    verdict = judge([window], None, [False], ["color"])
    assert not verdict.seamless
    assert any(s.position == 0 and s.start == 0 for s in verdict.seams)

    half = np.roll(window, (256, 256), (0, 1))  # its wrap now clean, the seam through the middle
    seams, _ = unrelated_lines(prepare_maps([half], [False]))
    assert seams and {(s.axis, s.position) for s in seams} <= {("x", 256), ("y", 256)}

    whole = np.roll(_reading("soil_forest_1.jpg", window=False), (171, 97), (0, 1))
    seams, strongest = unrelated_lines(prepare_maps([whole], [False]))
    assert not seams and strongest < 1.0
    assert judge([whole], None, [False], ["color"]).seamless


def test_ratios_read_texture_not_contrast():
    """White noise continues no better over one texel than over three: every line's ratio is about 1, and no
    line stands out. A flat picture has no seam and no NaN."""
    rng = np.random.default_rng(0)
    noise = rng.normal(size=(256, 256, 3))
    ratios = continuation_ratios(noise)
    assert np.all(np.abs(ratios - 1.0) < 0.12)
    seams, strongest = unrelated_lines(prepare_maps([noise], [False]))
    assert not seams and strongest < 1.0
    seams, strongest = unrelated_lines(prepare_maps([np.zeros((64, 64, 1))], [False]))
    assert not seams and np.isfinite(strongest) and strongest == 1.0 / MARGIN
