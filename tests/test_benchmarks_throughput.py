"""The passed-stacks-an-hour benchmark, small: one photo as a library, processed by the real command."""
from __future__ import annotations

import json

import pytest
from benchscripts import load_benchmark


def test_one_photo_library_is_processed_and_counted(tmp_path, capsys):
    bench = load_benchmark("throughput")
    assert bench.main(["--every", "40", "--size", "128", "--preset", "tiny", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "throughput.json").read_text())
    [row] = data["rows"]
    assert row["source"] == "bark_1" and row["intent"] == "tiling" and row["status"] in ("passed", "not-passed")
    assert data["stacks"] == 1 and data["passed"] == (row["status"] == "passed")
    assert data["passed_per_hour"] == pytest.approx(data["passed"] * 3600 / data["seconds"], rel=0.05)
    assert "passed stacks an hour" in capsys.readouterr().out
