"""The verdict-time benchmark at a small size: the stand-in tile's joins are found and the figures printed."""
from __future__ import annotations

from pathlib import Path

import pytest

from benchscripts import load_benchmark

SHARED = Path(__file__).resolve().parents[2] / "shared" / "textures"


@pytest.mark.skipif(not (SHARED / "brick_base_gray.jpg").is_file(), reason="needs ../shared/textures")
def test_the_verdict_time_benchmark_judges_a_rolled_crop(capsys):
    bench = load_benchmark("verdict_time")
    tiles, sources, normals = bench.stand_in(256)
    assert [t.shape[:2] for t in tiles] == [(219, 219)] * 3 and normals == [False, True, False]
    assert bench.main(["--size", "256"]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert line.startswith("verdict at 256 px (tile 219 x 219):") and "passed False" in line  # its wraps are joins
