"""Fidelity figures against the source: feature scale and patch-distribution distance, on real textures."""
from __future__ import annotations

import numpy as np
import pytest
from textures import load_texture
from scipy import ndimage

from seamless_usd import metrics
from seamless_usd.metrics import fidelity


@pytest.fixture(scope="module", params=["brick_albedo.png", "wood_color.png", "cloth.png", "brick_roughness.png"])
def source(request) -> np.ndarray:
    return load_texture(request.param)


def test_source_against_itself_scores_one(source):
    assert metrics.scale_ratio(source, source) == pytest.approx(1.0, abs=1e-9)
    a, b = fidelity.source_halves(source)
    assert metrics.scale_ratio(a, b) == pytest.approx(1.0, abs=0.2)  # two halves of one photo differ a little
    assert metrics.patch_distance(source, source) < 1.0


def test_magnified_crop_scores_below_0_6(source):
    h, w = source.shape[:2]
    up = ndimage.zoom(source[: h // 2, : w // 2], (2, 2, 1), order=1)  # bilinear 2x
    assert metrics.scale_ratio(up, source) < 0.6
    assert metrics.patch_distance(up, source) > 1.2


def test_shrunk_texture_scores_above_one(source):
    small = source[::2, ::2]
    assert metrics.scale_ratio(np.tile(small, (2, 2, 1)), source) > 1.3


@pytest.mark.parametrize("damage", ["blur", "checkerboard", "invented detail", "lost variety"])
def test_damage_raises_patch_distance(source, damage):
    h, w = source.shape[:2]
    if damage == "blur":
        tile = ndimage.gaussian_filter(source, (1.5, 1.5, 0))
    elif damage == "checkerboard":
        tile = source + 0.15 * ((np.indices((h, w)).sum(0) % 2) * 2 - 1)[..., None]
    elif damage == "invented detail":
        tile = source + np.random.default_rng(0).normal(0.0, 0.15, source.shape)
    else:
        tile = np.tile(source[: h // 8, : w // 8], (8, 8, 1))
    own = metrics.patch_distance(source, source)
    damaged = metrics.patch_distance(tile, source)
    assert damaged > 1.2, f"{damage}: {damaged:.2f}"
    assert damaged > 1.5 * own


def test_a_crop_of_a_periodic_source_scores_alike_at_every_offset():
    """Sharp edges on a short period: the pyramid's box grids meet them differently at each crop
    offset. The bundled weave repeats every 80 px; each 160 px crop holds two whole periods of it.
    Read on one grid, the crops scored 0.85-2.10 (the offsets 14, 5 and 39, 40 the highest)."""
    cloth = load_texture("cloth.png")
    figures = [metrics.patch_distance(cloth[y: y + 160, x: x + 160], cloth)
               for y, x in ((0, 0), (14, 5), (39, 40), (40, 40), (13, 7), (1, 3))]
    assert max(figures) < 1.0, figures
    assert max(figures) - min(figures) < 0.5, figures


def test_normal_maps_use_unit_vectors():
    n = load_texture("brick_normal.png")
    assert metrics.scale_ratio(n, n, is_normal=True) == pytest.approx(1.0)
    up = ndimage.zoom(n[:128, :128], (2, 2, 1), order=1)
    assert metrics.scale_ratio(up, n, is_normal=True) < 0.6


def test_map_metrics_carries_fidelity_and_targets():
    s = load_texture("wood_color.png")
    m = metrics.map_metrics(s, s)
    assert m["scale_ratio"] == pytest.approx(1.0)
    assert metrics.failing_figures(m) == []
    up = ndimage.zoom(s[:128, :128], (2, 2, 1), order=1)
    bad = metrics.map_metrics(up, s)
    failing = metrics.failing_figures(bad)
    assert [f.split()[0] for f in failing] == ["scale_ratio", "patch_distance"]
    assert metrics.map_metrics(s[:8, :8], s)["scale_ratio"] is None


def test_bad_inputs():
    with pytest.raises(ValueError, match="too small"):
        metrics.scale_ratio(np.zeros((4, 4)), np.zeros((4, 4)))
    with pytest.raises(ValueError, match="NaN|inf|non-finite"):
        metrics.scale_ratio(np.full((32, 32), np.nan), np.zeros((32, 32)))
    assert metrics.scale_ratio(np.zeros((32, 32)), np.zeros((32, 32))) == 1.0  # constant: no features either way
