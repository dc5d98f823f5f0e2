"""Results kept by the content of the arrays they were computed from."""
import numpy as np

from seamless_usd.memo import ContentMemo
from seamless_usd.metrics import patch_distance
from seamless_usd.metrics import fidelity


def test_equal_content_is_one_entry_and_any_difference_another():
    memo: ContentMemo[int] = ContentMemo(keep=3)
    calls = []

    def compute(tag):
        calls.append(tag)
        return len(calls)

    a = np.arange(12, dtype=np.float32).reshape(3, 4)
    assert memo.get((a,), "s", lambda: compute("a")) == 1
    assert memo.get((a.copy(),), "s", lambda: compute("again")) == 1  # equal content: kept
    assert memo.get((a.astype(np.float64),), "s", lambda: compute("f64")) == 2  # another dtype
    assert memo.get((a.reshape(4, 3),), "s", lambda: compute("shape")) == 3  # same bytes, another shape
    assert memo.get((a,), "other settings", lambda: compute("settings")) == 4
    assert calls == ["a", "f64", "shape", "settings"] and len(memo) == 3  # the oldest ("a", "s") dropped
    assert memo.get((a,), "s", lambda: compute("a2")) == 5


def test_a_kept_patch_distance_equals_a_fresh_one_and_a_changed_tile_is_measured_anew():
    rng = np.random.default_rng(4)
    source = rng.normal(size=(96, 96, 3)).astype(np.float32)
    tile = np.roll(source, (17, 40), (0, 1))
    fidelity._PATCH_DISTANCES.clear()
    fidelity._OWN_SPREAD.clear()
    first = patch_distance(tile, source)
    assert len(fidelity._PATCH_DISTANCES) == 1 and len(fidelity._OWN_SPREAD) == 1
    blurred = 0.5 * (tile + np.roll(tile, 1, 1))
    other = patch_distance(blurred, source)  # another tile of the same source: the source's spread is kept
    assert len(fidelity._PATCH_DISTANCES) == 2 and len(fidelity._OWN_SPREAD) == 1
    assert other > first  # the blur is measured, not a kept figure returned
    fidelity._PATCH_DISTANCES.clear()
    fidelity._OWN_SPREAD.clear()
    assert patch_distance(tile.copy(), source.copy()) == first
