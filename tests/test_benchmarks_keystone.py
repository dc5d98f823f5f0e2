"""The perspective experiment (benchmarks/experiments/keystone.py): the vanishing point of lines that converge is
found, and the one-point homography makes them run parallel."""
from __future__ import annotations

import numpy as np
import pytest
from benchscripts import load_benchmark


def _converging(vx: float, vy: float, h: int = 256, w: int = 256) -> np.ndarray:
    """(h, w, 3) soft bars (a cosine across them) that all pass through (vx, vy) above the picture, 24 px apart
    along the bottom row."""
    y, x = np.mgrid[:h, :w].astype(np.float64)
    at_bottom = vx + (x - vx) * (h - 1 - vy) / (y - vy)  # where each texel's line crosses the bottom row
    bars = 0.55 * np.cos(2 * np.pi * at_bottom / 24)
    return np.repeat(bars[..., None], 3, axis=2).astype(np.float32)


def test_the_vanishing_point_of_converging_bars_is_found_and_rectified_away():
    ks = load_benchmark("experiments/keystone")
    picture = _converging(140.0, -500.0)
    found = ks.vanishing_point(picture)
    assert found["vx"] == pytest.approx(140.0, abs=5) and found["vy"] == pytest.approx(-500.0, rel=0.05)
    assert found["lean_spread"] > 15  # the bars lean from about -13 to +13 degrees across the picture
    rect, facts = ks.rectify(picture, found["vx"], found["vy"])
    assert ks.vanishing_point(rect)["lean_spread"] < 2  # parallel now
    assert rect.shape[:2] == (facts["size"][1], facts["size"][0]) and facts["near_shrink_x"] > 1
    assert rect.min() >= picture.min() and rect.max() <= picture.max()  # clipped to the source's range
    parallel = ks.vanishing_point(_converging(128.0, -1e7))
    assert parallel["lean_spread"] < 1 < ks.MIN_SPREAD  # upright bars: not rectified
    assert parallel["vy"] is None or abs(parallel["vy"]) > 1e4  # and no vanishing point near the picture
    with pytest.raises(ValueError, match="above the picture"):
        ks.rectify(picture, 128.0, 300.0)
