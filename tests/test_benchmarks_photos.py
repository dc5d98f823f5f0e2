"""The real-photo benchmark, small: which photos are windowed, the product's tile judged, peers left out cleanly."""
from __future__ import annotations

import json

import numpy as np
import pytest

from benchscripts import load_benchmark


def test_photos_made_to_tile_are_judged_through_a_window(tmp_path):
    photos = load_benchmark("photos")
    made = photos.tileable_photos(photos.PHOTOS)
    assert "sand_coast_1.jpg" in made and "fruit_berries_1.jpg" not in made and "gravel_1.jpg" not in made
    whole = photos.load_photo(photos.PHOTOS / "sand_coast_1.jpg", 256)
    window = photos.load_photo(photos.PHOTOS / "sand_coast_1.jpg", 256, window=True)
    assert whole.shape == (256, 256, 3) and window.shape == (256, 256, 3)  # the window is brought to size too
    assert not np.allclose(whole, window) and -1.0 <= window.min() and window.max() <= 1.0
    # the 2048 px versions are listed in the folder above's SOURCES.md: they are windowed too, not tiled whole
    assert "stones_wall_1.jpg" in photos.tileable_photos(photos.PHOTOS / "full")


def test_the_product_tile_of_a_photo_is_judged_and_pictured(tmp_path, capsys):
    photos = load_benchmark("photos")
    assert photos.main(["--only", "gravel_1", "--methods", "seamless-usd,resynthesizer", "--size", "192",
                        "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "resynthesizer left out" in out  # no peer environment here: said, not a crash
    data = json.loads((tmp_path / "photos.json").read_text())
    [row] = data["rows"]
    made = row["seamless-usd"]
    assert row["photo"] == "gravel_1.jpg" and row["size"] == [192, 192] and not row["window"]
    assert made["kind"] in ("lattice", "window", "mend", "quilt") and made["gan"] is False
    assert isinstance(made["passed"], bool) and made["tile"] == [192, 192]
    assert (tmp_path / "tiles" / "gravel_1__seamless-usd.jpg").is_file()
    assert (tmp_path / "tiles" / "gravel_1__seamless-usd_zoom.png").is_file()
    assert "| seamless-usd |" in (tmp_path / "photos.md").read_text()


def test_the_resynthesizer_peer_needs_its_own_environment(monkeypatch):
    methods = load_benchmark("methods")
    monkeypatch.delenv("RESYNTH_PYTHON", raising=False)
    with pytest.raises(RuntimeError, match="--resynth-python"):
        methods.resynthesizer_tile(np.zeros((32, 32, 3), np.float32))
