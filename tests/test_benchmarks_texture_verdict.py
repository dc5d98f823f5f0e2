"""The corpus of textures judged on their own, and the benchmark that measures the rules on it."""
from __future__ import annotations

import collections
from pathlib import Path

import numpy as np
import pytest

from benchscripts import load_benchmark

SHARED = Path(__file__).resolve().parents[2] / "shared" / "textures"


def test_the_corpus_labels_each_kind_and_keeps_a_held_back_part():
    corpus = load_benchmark("texture_corpus")
    items = corpus.build((128,))
    kinds = collections.Counter((i.kind, i.seamless) for i in items)
    assert all(seamless == (kind in corpus.SEAMLESS) for kind, seamless in kinds)
    assert {"window", "half-roll", "splice", "lit"} <= {k for k, s in kinds if not s}
    assert {i.split for i in items} == {"tuning", "held-back"}
    for i in items:
        assert i.picture.ndim == 3 and i.picture.dtype == np.float32
        assert -1.0 <= float(i.picture.min()) and float(i.picture.max()) <= 1.0
        if i.is_normal:
            assert np.allclose(np.linalg.norm(i.picture, axis=-1), 1.0, atol=1e-4)
    assert len({i.name for i in items}) == len(items)


@pytest.mark.skipif(not (SHARED / "wood_color.jpg").is_file(), reason="needs ../shared/textures")
def test_the_rules_tell_a_rolled_texture_from_its_splice_and_a_lit_copy():
    corpus = load_benchmark("texture_corpus")
    bench = load_benchmark("texture_verdict")
    items = {i.name: i for i in corpus.build((128,)) if i.family == "wood_color"}
    rolled = bench.rules(items["wood_color-128-rolled"])
    assert not rolled["verdict"][0] and not rolled["line-breaks"][0]
    for name in ("wood_color-128-splice", "wood_color-128-lit"):
        found = bench.rules(items[name])
        assert found["line-breaks"][0] and found["verdict"][0], (name, found)
    shares = bench.table([{"split": "tuning", "seamless": True, "rules": rolled},
                          {"split": "tuning", "seamless": False, "rules": found}])
    row = next(s for s in shares if s["part"] == "tuning" and s["rule"] == "line-breaks")
    assert row["seamless_right"] == 1.0 and row["seamed_right"] == 1.0
