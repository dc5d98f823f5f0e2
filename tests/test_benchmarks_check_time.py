"""The check timing benchmark, small: a stack, a picture and a labelled folder, each checked from the command line."""
from __future__ import annotations

from pathlib import Path

import pytest

from benchscripts import load_benchmark

SHARED = Path(__file__).resolve().parents[2] / "shared" / "textures"


@pytest.mark.skipif(not (SHARED / "brick_base_gray.jpg").is_file(), reason="needs ../shared/textures")
def test_check_time_runs_each_check_and_counts_the_labelled_folder(tmp_path, capsys):
    bench = load_benchmark("check_time")
    assert bench.main(["--out", str(tmp_path), "--size", "128", "--repeat", "1", "--pictures", "6", "--jobs", "1",
                       "--picture", "food_peas_1.jpg"]) == 0
    out = capsys.readouterr().out
    assert "check a 128 px 3-map stack:" in out and "check a 320 px picture:" in out
    assert "check a folder of 6 pictures (256 px; 2 seamless by construction)" in out
    assert (tmp_path / "sheet.html").stat().st_size > 0
    assert len(list((tmp_path / "library").glob("*.png"))) == 6
